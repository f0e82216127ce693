#include "io/run_writer.hpp"

#include <array>
#include <cstdio>
#include <initializer_list>
#include <numeric>
#include <set>
#include <stdexcept>
#include <string_view>
#include <system_error>

#include "io/atomic_file.hpp"
#include "io/h5.hpp"
#include "io/xdmf.hpp"

namespace mmpm::io {

namespace fs = std::filesystem;

namespace {

constexpr const char* particles_group = "particles";
constexpr const char* series_group = "series";
constexpr const char* xdmf_group = "xdmf";
constexpr const char* grid_group = "grid";
constexpr const char* xdmf_grid_group = "xdmf_grid";  // padded 2D vectors of /grid
// Every group that holds a snapshot's step_* children.
constexpr std::array<const char*, 4> snapshot_groups{particles_group, xdmf_group, grid_group,
                                                     xdmf_grid_group};
constexpr const char* step_prefix = "step_";
constexpr long max_step = 9'999'999'999;  // 10 digits keep name order == step order

std::string step_name(long step) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "step_%010ld", step);
  return buffer;
}

// The step encoded in a snapshot group's name, or -1 if it is not one.
long parse_step_name(const std::string& name) {
  const std::string prefix = step_prefix;
  if (name.size() != prefix.size() + 10 || name.compare(0, prefix.size(), prefix) != 0) return -1;
  long step = 0;
  for (std::size_t i = prefix.size(); i < name.size(); ++i) {
    if (name[i] < '0' || name[i] > '9') return -1;
    step = step * 10 + (name[i] - '0');
  }
  return step;
}

std::string vertices_name(std::size_t count) {
  return "vertices_" + std::to_string(count);
}

// "/a/b/c" from {"a", "b", "c"}. (Built by appending: GCC 12 at -O3 gives a
// false -Wrestrict on `"/" + std::string(...)`.)
std::string absolute(std::initializer_list<std::string_view> parts) {
  std::string out;
  for (const std::string_view part : parts) {
    out += '/';
    out += part;
  }
  return out;
}

// Names become HDF5 links, XML attribute values and comma-separated lists:
// keep them to a plain alphabet.
void check_name(const std::string& name, const char* what) {
  bool ok = !name.empty() && name != "." && name != "..";
  for (const char c : name) {
    const bool plain = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                       c == '_' || c == '.' || c == '-';
    ok = ok && plain;
  }
  if (!ok) {
    throw std::invalid_argument(std::string(what) + " name '" + name +
                                "' must be non-empty letters, digits, '_', '.' or '-'");
  }
}

// Fields of `count` points (particles or nodes): plain distinct names, at
// least one component, count x components values.
void check_fields(const std::vector<ParticleField>& fields, std::size_t count,
                  const std::string& where, const char* what) {
  std::set<std::string> names;
  for (const ParticleField& f : fields) {
    check_name(f.name, what);
    if (!names.insert(f.name).second)
      throw std::invalid_argument(where + "field '" + f.name + "' given twice");
    if (f.components < 1)
      throw std::invalid_argument(where + "field '" + f.name + "' needs >= 1 component");
    const std::size_t expected = count * static_cast<std::size_t>(f.components);
    if (f.values.size() != expected) {
      throw std::invalid_argument(where + "field '" + f.name + "' holds " +
                                  std::to_string(f.values.size()) + " values, expected " +
                                  std::to_string(expected));
    }
  }
}

void check_snapshot(const Snapshot& s) {
  const std::string where = "snapshot at step " + std::to_string(s.step) + ": ";
  if (s.step < 0 || s.step > max_step) {
    throw std::invalid_argument(where + "step must lie in [0, " + std::to_string(max_step) + "]");
  }
  if (s.dimension != 2 && s.dimension != 3) {
    throw std::invalid_argument(where + "dimension must be 2 or 3");
  }
  if (s.position.size() != s.count * static_cast<std::size_t>(s.dimension)) {
    throw std::invalid_argument(where + "position holds " + std::to_string(s.position.size()) +
                                " values, expected count x dimension = " +
                                std::to_string(s.count * static_cast<std::size_t>(s.dimension)));
  }
  for (const ParticleField& f : s.fields)
    if (f.name == "position")
      throw std::invalid_argument(where + "a field may not be called 'position'");
  check_fields(s.fields, s.count, where, "particle field");
}

void check_grid(const Snapshot& s) {
  const GridSnapshot& g = s.grid;
  const std::string where = "grid snapshot at step " + std::to_string(s.step) + ": ";
  std::size_t nodes = 1;
  for (int d = 0; d < 3; ++d) {
    if (g.nodes[std::size_t(d)] < 1 || (d >= s.dimension && g.nodes[std::size_t(d)] != 1))
      throw std::invalid_argument(where + "node counts must be >= 1 (1 beyond the dimension)");
    nodes *= std::size_t(g.nodes[std::size_t(d)]);
  }
  check_fields(g.fields, nodes, where, "grid field");
}

std::vector<double> padded_to_3(const std::vector<double>& xy, std::size_t count) {
  std::vector<double> xyz(3 * count, 0.0);
  for (std::size_t i = 0; i < count; ++i) {
    xyz[3 * i] = xy[2 * i];
    xyz[3 * i + 1] = xy[2 * i + 1];
  }
  return xyz;
}

void remove_if_present(h5::Group& group, const std::string& name) {
  if (group.contains(name)) group.remove(name);
}

// A snapshot lives in /particles and /grid and, for their padded 2D
// vectors, in /xdmf and /xdmf_grid.
void remove_snapshot(h5::Group& root, const std::string& name) {
  for (const char* group_name : snapshot_groups) {
    if (!root.contains(group_name)) continue;
    h5::Group group = root.open_group(group_name);
    remove_if_present(group, name);
  }
}

// The 2D vector fields of a snapshot, padded with a zero third column
// (xdmf.hpp: ParaView takes only 3-component data as vectors), in
// support/<snapshot>/<field> shaped `shape`; nothing without such a field.
void write_padded_vectors(h5::Group& root, const char* support_group, const std::string& snapshot,
                          const std::vector<ParticleField>& fields, std::size_t count,
                          const std::vector<hsize_t>& shape) {
  bool any_vector = false;
  for (const ParticleField& f : fields)
    any_vector = any_vector || attribute_kind(f.components, 2) == AttributeKind::vector;
  if (!any_vector) return;
  h5::Group padded = root.require_group(support_group).create_group(snapshot);
  for (const ParticleField& f : fields)
    if (attribute_kind(f.components, 2) == AttributeKind::vector)
      padded.write_doubles(f.name, padded_to_3(f.values, count), shape);
}

bool has_padded_copy(const h5::Group& root, const std::string& snapshot, const std::string& field,
                     const char* support_group) {
  if (!root.contains(support_group)) return false;
  const h5::Group support = root.open_group(support_group);
  return support.contains(snapshot) && support.open_group(snapshot).contains(field);
}

// How run.xdmf / run_grid.xdmf reference data_group/<snapshot>/<field>: a
// 2D vector through its padded copy in support_group, or, without one, as
// plain components.
XdmfField xdmf_field(const h5::Group& root, const char* data_group, const char* support_group,
                     const std::string& snapshot, const std::string& field, int components,
                     int dimension) {
  XdmfField f{field, attribute_kind(components, dimension), absolute({data_group, snapshot, field}),
              components};
  if (f.kind == AttributeKind::vector && dimension == 2) {
    if (has_padded_copy(root, snapshot, field, support_group)) {
      f.dataset = absolute({support_group, snapshot, field});
      f.stored_components = 3;
    } else {
      f.kind = AttributeKind::matrix;  // still viewable, just not as arrows
    }
  }
  return f;
}

// The HDF5 shape of a grid quantity: [nz,] ny, nx, components.
std::vector<hsize_t> grid_shape(const GridSnapshot& g, int dimension, int components) {
  std::vector<hsize_t> shape;
  for (int d = dimension - 1; d >= 0; --d) shape.push_back(hsize_t(g.nodes[std::size_t(d)]));
  shape.push_back(hsize_t(components));
  return shape;
}

void write_grid_data(h5::Group& root, const Snapshot& s, const std::string& name) {
  const GridSnapshot& g = s.grid;
  const auto D = static_cast<std::size_t>(s.dimension);
  h5::Group grid = root.require_group(grid_group);
  // The geometry is the scene's, the same for every snapshot.
  if (!grid.contains("origin")) {
    grid.write_doubles("origin", std::vector<double>(g.origin.begin(), g.origin.begin() + D),
                       {hsize_t(D)});
    grid.write_doubles("spacing", std::vector<double>(g.spacing.begin(), g.spacing.begin() + D),
                       {hsize_t(D)});
  }
  h5::Group group = grid.create_group(name);
  group.set_int_attribute("step", s.step);
  group.set_double_attribute("time", s.time);
  std::size_t nodes = 1;
  for (std::size_t d = 0; d < D; ++d) nodes *= std::size_t(g.nodes[d]);
  for (const ParticleField& f : g.fields)
    group.write_doubles(f.name, f.values, grid_shape(g, s.dimension, f.components));
  if (s.dimension != 2) return;
  // Shaped [1, ny, nx, 3], the rank of the 3D structured grid run_grid.xdmf
  // describes: ParaView's XDMF reader selects vector data by the grid's
  // dimensions and failed on [ny, nx, 3] ("selection + offset not within
  // extent"; scalars read either way).
  std::vector<hsize_t> shape = grid_shape(g, 2, 3);
  shape.insert(shape.begin(), 1);
  write_padded_vectors(root, xdmf_grid_group, name, g.fields, nodes, shape);
}

// What run_grid.xdmf must describe, read back from the file (after a
// restart the file, not this process, knows every snapshot).
std::vector<XdmfGridSnapshot> describe_grid(const h5::Group& root) {
  std::vector<XdmfGridSnapshot> out;
  if (!root.contains(grid_group)) return out;
  const h5::Group grid = root.open_group(grid_group);
  const std::vector<double> origin = grid.open_dataset("origin").read_doubles();
  const std::vector<double> spacing = grid.open_dataset("spacing").read_doubles();
  const int D = static_cast<int>(origin.size());
  for (const std::string& name : grid.children()) {
    if (parse_step_name(name) < 0) continue;
    const h5::Group group = grid.open_group(name);
    XdmfGridSnapshot s;
    s.step = group.int_attribute("step");
    s.time = group.double_attribute("time");
    s.dimension = D;
    for (int d = 0; d < D; ++d) {
      s.origin[std::size_t(d)] = origin[std::size_t(d)];
      s.spacing[std::size_t(d)] = spacing[std::size_t(d)];
    }
    for (const std::string& field : group.children()) {
      const std::vector<hsize_t> shape = group.open_dataset(field).shape();
      if (shape.size() != std::size_t(D) + 1)
        throw std::runtime_error("run file: grid/" + name + "/" + field + " has the wrong rank");
      for (int d = 0; d < D; ++d)
        s.nodes[std::size_t(d)] = std::size_t(shape[std::size_t(D - 1 - d)]);
      s.fields.push_back(xdmf_field(root, grid_group, xdmf_grid_group, name, field,
                                    static_cast<int>(shape.back()), D));
    }
    out.push_back(std::move(s));
  }
  return out;
}

void write_snapshot_data(h5::Group& root, const Snapshot& s, const std::string& name) {
  const auto n = static_cast<hsize_t>(s.count);
  h5::Group group = root.require_group(particles_group).create_group(name);
  group.set_int_attribute("step", s.step);
  group.set_double_attribute("time", s.time);
  group.write_doubles("position", s.position, {n, static_cast<hsize_t>(s.dimension)});
  for (const ParticleField& f : s.fields) {
    group.write_doubles(f.name, f.values, {n, static_cast<hsize_t>(f.components)});
  }

  if (!s.grid.fields.empty()) write_grid_data(root, s, name);

  h5::Group support = root.require_group(xdmf_group);
  if (!support.contains(vertices_name(s.count))) {
    std::vector<std::int64_t> ids(s.count);
    std::iota(ids.begin(), ids.end(), std::int64_t{0});
    support.write_ints(vertices_name(s.count), ids, {n});
  }
  if (s.dimension == 2) write_padded_vectors(root, xdmf_group, name, s.fields, s.count, {n, 3});
}

// Reads back what run.xdmf must describe, from the file itself: after a
// restart the file, not this process, knows every snapshot.
std::vector<XdmfSnapshot> describe(const h5::Group& root) {
  std::vector<XdmfSnapshot> out;
  if (!root.contains(particles_group)) return out;
  const h5::Group particles = root.open_group(particles_group);
  for (const std::string& name : particles.children()) {
    if (parse_step_name(name) < 0) continue;
    const h5::Group group = particles.open_group(name);
    const std::vector<hsize_t> shape = group.open_dataset("position").shape();
    if (shape.size() != 2) throw std::runtime_error("run file: " + name + "/position is not 2-D");
    XdmfSnapshot s{group.int_attribute("step"),
                   group.double_attribute("time"),
                   static_cast<int>(shape[1]),
                   static_cast<std::size_t>(shape[0]),
                   absolute({particles_group, name, "position"}),
                   absolute({xdmf_group, vertices_name(static_cast<std::size_t>(shape[0]))}),
                   {}};
    for (const std::string& field : group.children()) {
      if (field == "position") continue;
      const std::vector<hsize_t> fshape = group.open_dataset(field).shape();
      const int components = fshape.size() == 2 ? static_cast<int>(fshape[1]) : 1;
      s.fields.push_back(
          xdmf_field(root, particles_group, xdmf_group, name, field, components, s.dimension));
    }
    out.push_back(std::move(s));
  }
  return out;
}

// Vertex-id lists no remaining snapshot uses (left by snapshots a restart
// deleted) would make a restarted file differ from an uninterrupted one.
void drop_unused_vertices(h5::Group& root, const std::vector<XdmfSnapshot>& snapshots) {
  if (!root.contains(xdmf_group)) return;
  h5::Group support = root.open_group(xdmf_group);
  std::set<std::string> used;
  for (const XdmfSnapshot& s : snapshots) used.insert(vertices_name(s.count));
  for (const std::string& name : support.children()) {
    if (name.rfind("vertices_", 0) == 0 && used.count(name) == 0) support.remove(name);
  }
}

}  // namespace

RunWriter::RunWriter(fs::path dir, std::unique_ptr<h5::File> file)
    : dir_(std::move(dir)), file_(std::move(file)) {}

RunWriter::RunWriter(const fs::path& dir) : dir_(dir) {
  fs::create_directories(dir_);
  fs::remove(h5_path());
  fs::remove(xdmf_path());
  fs::remove(grid_xdmf_path());
  file_ = std::make_unique<h5::File>(h5::File::create(partial_path()));
  file_->root().set_int_attribute("mmpm_layout", 1);
}

RunWriter RunWriter::reopen(const fs::path& dir, long last_step) {
  const fs::path partial = dir / "run.h5.partial";
  if (!fs::exists(partial)) {
    throw std::runtime_error("cannot restart: " + partial.string() + " does not exist");
  }
  RunWriter writer(dir,
                   std::make_unique<h5::File>(h5::File::open(partial, h5::File::Mode::read_write)));
  h5::Group root = writer.file_->root();
  for (const char* group_name : snapshot_groups) {
    if (!root.contains(group_name)) continue;
    h5::Group group = root.open_group(group_name);
    for (const std::string& name : group.children()) {
      if (parse_step_name(name) > last_step) group.remove(name);
    }
  }
  remove_if_present(root, series_group);
  writer.file_->flush();
  fs::remove(writer.h5_path());
  fs::remove(writer.xdmf_path());
  fs::remove(writer.grid_xdmf_path());
  return writer;
}

RunWriter::RunWriter(RunWriter&&) noexcept = default;

RunWriter& RunWriter::operator=(RunWriter&& other) noexcept {
  if (this != &other) {
    close_quietly();
    dir_ = std::move(other.dir_);
    file_ = std::move(other.file_);
  }
  return *this;
}

RunWriter::~RunWriter() {
  close_quietly();
}

void RunWriter::close_quietly() noexcept {
  if (!is_open()) return;
  try {
    file_->close();
  } catch (...) {
    // Nothing to report to from here; the partial stays for restart.
  }
}

bool RunWriter::is_open() const {
  return file_ != nullptr && file_->valid();
}

void RunWriter::require_open(const char* operation) const {
  if (!is_open()) {
    throw std::logic_error(std::string("RunWriter::") + operation + " after finish() or abandon()");
  }
}

namespace {

// HDF5's errors name a dataset or an operation ("cannot write dataset
// 'stress': ... (File too large)"); the user needs the file too.
[[noreturn]] void rethrow_naming(const fs::path& file) {
  try {
    throw;
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    if (what.find(file.string()) != std::string::npos) throw;
    throw std::runtime_error(file.string() + ": " + what);
  }
}

}  // namespace

void RunWriter::set_attribute(const std::string& name, const std::string& value) {
  require_open("set_attribute");
  file_->root().set_string_attribute(name, value);
}

void RunWriter::write_snapshot(const Snapshot& snapshot) {
  require_open("write_snapshot");
  check_snapshot(snapshot);
  check_grid(snapshot);
  h5::Group root = file_->root();
  const std::string name = step_name(snapshot.step);
  remove_snapshot(root, name);
  try {
    write_snapshot_data(root, snapshot, name);
  } catch (...) {
    // Leave no half-written snapshot behind (best effort: the file may be
    // unwritable, which is likely why we are here).
    try {
      remove_snapshot(root, name);
    } catch (...) {
    }
    rethrow_naming(partial_path());
  }
  file_->flush();
}

void RunWriter::write_series(const std::vector<std::string>& names,
                             const std::vector<std::vector<double>>& columns) {
  require_open("write_series");
  if (names.size() != columns.size()) {
    throw std::invalid_argument("time series: " + std::to_string(names.size()) + " names for " +
                                std::to_string(columns.size()) + " columns");
  }
  std::set<std::string> seen;
  std::string list;
  for (std::size_t i = 0; i < names.size(); ++i) {
    check_name(names[i], "time series");
    if (!seen.insert(names[i]).second) {
      throw std::invalid_argument("time series: column '" + names[i] + "' given twice");
    }
    if (columns[i].size() != columns[0].size()) {
      throw std::invalid_argument("time series: column '" + names[i] + "' has " +
                                  std::to_string(columns[i].size()) + " rows, '" + names[0] +
                                  "' has " + std::to_string(columns[0].size()));
    }
    list += (i == 0 ? "" : ",") + names[i];
  }
  try {
    h5::Group root = file_->root();
    remove_if_present(root, series_group);
    h5::Group series = root.create_group(series_group);
    series.set_string_attribute("columns", list);
    for (std::size_t i = 0; i < names.size(); ++i) {
      series.write_doubles(names[i], columns[i], {static_cast<hsize_t>(columns[i].size())});
    }
  } catch (...) {
    rethrow_naming(partial_path());
  }
  file_->flush();
}

void RunWriter::finish(const std::function<void()>& before_publishing) {
  require_open("finish");
  std::string document, grid_document;
  {
    h5::Group root = file_->root();
    const std::vector<XdmfSnapshot> snapshots = describe(root);
    drop_unused_vertices(root, snapshots);
    document = xdmf_document("run.h5", snapshots);
    const std::vector<XdmfGridSnapshot> grids = describe_grid(root);
    if (!grids.empty()) grid_document = xdmf_grid_document("run.h5", grids);
  }  // every handle into the file is closed before the file itself
  file_->close();
  // The data must be on disk before the name that promises a complete result.
  fsync_file(partial_path());
  // Everything else first: if a write fails (a full disk), run.h5 does not
  // appear, the partial stays and the run can be restarted from its
  // checkpoint once there is room.
  try {
    write_file_atomic(xdmf_path(), document);
    if (!grid_document.empty()) write_file_atomic(grid_xdmf_path(), grid_document);
    if (before_publishing) before_publishing();
    fs::rename(partial_path(), h5_path());
  } catch (...) {
    std::error_code ignored;
    fs::remove(xdmf_path(), ignored);
    fs::remove(grid_xdmf_path(), ignored);
    throw;
  }
  fsync_directory(dir_);
}

void RunWriter::abandon() {
  // A closed file means finish() or abandon() already ran (or this writer
  // was moved from): there is no partial of ours to delete.
  if (!is_open()) return;
  close_quietly();  // the file is being discarded: a close failure changes nothing
  std::error_code ignored;
  fs::remove(partial_path(), ignored);
}

}  // namespace mmpm::io
