#include "io/xdmf.hpp"

#include <charconv>
#include <sstream>
#include <stdexcept>

namespace mmpm::io {

namespace {

std::string escaped(const std::string& text) {
  std::string out;
  for (const char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&apos;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

// Shortest text that reads back to the same double: ParaView's time values
// then match the file's "time" attributes exactly.
std::string exact(double value) {
  char buffer[32];
  const auto [end, error] = std::to_chars(buffer, buffer + sizeof buffer, value);
  if (error != std::errc()) throw std::runtime_error("xdmf: cannot format a time value");
  return std::string(buffer, end);
}

const char* kind_name(AttributeKind kind) {
  switch (kind) {
    case AttributeKind::scalar:
      return "Scalar";
    case AttributeKind::vector:
      return "Vector";
    case AttributeKind::tensor:
      return "Tensor";
    case AttributeKind::matrix:
      return "Matrix";
  }
  return "Matrix";
}

// An XDMF 3 document up to the opening of its one temporal collection.
void open_collection(std::ostringstream& out, const char* name) {
  out << "<?xml version=\"1.0\" ?>\n"
      << "<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n"
      << "<Xdmf Version=\"3.0\">\n"
      << "  <Domain>\n"
      << "    <Grid Name=\"" << name << "\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
}

void close_collection(std::ostringstream& out) {
  out << "    </Grid>\n"
      << "  </Domain>\n"
      << "</Xdmf>\n";
}

// "<DataItem ...>" for an HDF5 dataset of the given shape (slowest first).
void data_item(std::ostringstream& out, const std::string& indent,
               const std::vector<std::size_t>& shape, const char* number_type,
               const std::string& h5_file, const std::string& dataset) {
  out << indent << "<DataItem Dimensions=\"";
  for (std::size_t i = 0; i < shape.size(); ++i) out << (i ? " " : "") << shape[i];
  out << "\" NumberType=\"" << number_type << "\" Precision=\"8\" Format=\"HDF\">"
      << escaped(h5_file) << ':' << escaped(dataset) << "</DataItem>\n";
}

// "<Attribute ...>" of one nodal field, its dataset shaped `shape`.
void attribute(std::ostringstream& out, const std::string& indent, const XdmfField& f,
               const std::vector<std::size_t>& shape, const std::string& h5_file) {
  out << indent << "<Attribute Name=\"" << escaped(f.name) << "\" AttributeType=\""
      << kind_name(f.kind) << "\" Center=\"Node\">\n";
  data_item(out, indent + "  ", shape, "Float", h5_file, f.dataset);
  out << indent << "</Attribute>\n";
}

}  // namespace

AttributeKind attribute_kind(int components, int dimension) {
  if (components == 1) return AttributeKind::scalar;
  if (components == dimension) return AttributeKind::vector;
  if (components == 9 && dimension == 3) return AttributeKind::tensor;
  return AttributeKind::matrix;
}

std::string xdmf_document(const std::string& h5_file, const std::vector<XdmfSnapshot>& snapshots) {
  std::ostringstream out;
  open_collection(out, "particles");
  for (const XdmfSnapshot& s : snapshots) {
    if (s.dimension != 2 && s.dimension != 3) {
      throw std::invalid_argument("xdmf: dimension must be 2 or 3");
    }
    const std::string in = "        ";
    out << "      <Grid Name=\"step_" << s.step << "\" GridType=\"Uniform\">\n"
        << in << "<Time Value=\"" << exact(s.time)
        << "\"/>\n"
        // One vertex cell per particle, with explicit connectivity: readers
        // differ on what an implicit Polyvertex topology means.
        << in << "<Topology TopologyType=\"Polyvertex\" NumberOfElements=\"" << s.count
        << "\" NodesPerElement=\"1\">\n";
    data_item(out, in + "  ", {s.count}, "Int", h5_file, s.connectivity);
    out << in << "</Topology>\n"
        << in << "<Geometry GeometryType=\"" << (s.dimension == 2 ? "XY" : "XYZ") << "\">\n";
    data_item(out, in + "  ", {s.count, std::size_t(s.dimension)}, "Float", h5_file, s.position);
    out << in << "</Geometry>\n";
    for (const XdmfField& f : s.fields)
      attribute(out, in, f, {s.count, std::size_t(f.stored_components)}, h5_file);
    out << "      </Grid>\n";
  }
  close_collection(out);
  return out.str();
}

std::string xdmf_grid_document(const std::string& h5_file,
                               const std::vector<XdmfGridSnapshot>& snapshots) {
  std::ostringstream out;
  open_collection(out, "grid");
  for (const XdmfGridSnapshot& s : snapshots) {
    if (s.dimension != 2 && s.dimension != 3) {
      throw std::invalid_argument("xdmf: dimension must be 2 or 3");
    }
    const std::string in = "        ";
    // XDMF lists structured dimensions slowest first: z, y, x.
    const std::size_t nz = s.dimension == 3 ? s.nodes[2] : 1;
    const double oz = s.dimension == 3 ? s.origin[2] : 0.0;
    const double hz = s.dimension == 3 ? s.spacing[2] : 1.0;
    out << "      <Grid Name=\"step_" << s.step << "\" GridType=\"Uniform\">\n"
        << in << "<Time Value=\"" << exact(s.time) << "\"/>\n"
        << in << "<Topology TopologyType=\"3DCoRectMesh\" Dimensions=\"" << nz << ' ' << s.nodes[1]
        << ' ' << s.nodes[0] << "\"/>\n"
        << in << "<Geometry GeometryType=\"ORIGIN_DXDYDZ\">\n"
        << in << "  <DataItem Dimensions=\"3\" NumberType=\"Float\" Precision=\"8\" "
        << "Format=\"XML\">" << exact(oz) << ' ' << exact(s.origin[1]) << ' ' << exact(s.origin[0])
        << "</DataItem>\n"
        << in << "  <DataItem Dimensions=\"3\" NumberType=\"Float\" Precision=\"8\" "
        << "Format=\"XML\">" << exact(hz) << ' ' << exact(s.spacing[1]) << ' '
        << exact(s.spacing[0]) << "</DataItem>\n"
        << in << "</Geometry>\n";
    for (const XdmfField& f : s.fields) {
      std::vector<std::size_t> shape;
      // A 2D vector's padded copy has the 3D grid's rank (run_writer.cpp).
      if (s.dimension == 2 && f.kind == AttributeKind::vector) shape.push_back(1);
      for (int d = s.dimension - 1; d >= 0; --d) shape.push_back(s.nodes[std::size_t(d)]);
      shape.push_back(std::size_t(f.stored_components));
      attribute(out, in, f, shape, h5_file);
    }
    out << "      </Grid>\n";
  }
  close_collection(out);
  return out.str();
}

}  // namespace mmpm::io
