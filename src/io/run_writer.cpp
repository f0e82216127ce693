#include "io/run_writer.hpp"

#include <array>
#include <cstdio>
#include <initializer_list>
#include <map>
#include <numeric>
#include <optional>
#include <set>
#include <stdexcept>
#include <string_view>
#include <system_error>
#include <utility>

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

// The vertex ids run.xdmf's polyvertex topologies refer to, one list per
// particle count: written once at assembly, not with every snapshot.
void write_vertex_ids(h5::Group& root, const std::vector<XdmfSnapshot>& snapshots) {
  if (snapshots.empty()) return;
  h5::Group support = root.require_group(xdmf_group);
  for (const XdmfSnapshot& s : snapshots) {
    if (support.contains(vertices_name(s.count))) continue;
    std::vector<std::int64_t> ids(s.count);
    std::iota(ids.begin(), ids.end(), std::int64_t{0});
    support.write_ints(vertices_name(s.count), ids, {static_cast<hsize_t>(s.count)});
  }
}

// HDF5's errors name a dataset or an operation ("cannot write dataset
// 'stress': ... (File too large)"); the user needs the file too. An error
// that already names its file passes through unchanged.
struct FileError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

[[noreturn]] void rethrow_naming(const fs::path& file) {
  try {
    throw;
  } catch (const FileError&) {
    throw;
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    if (what.find(file.string()) != std::string::npos) throw FileError(what);
    throw FileError(file.string() + ": " + what);
  }
}

// Runs `operation`; a failure names `file`.
template <class Operation>
void naming(const fs::path& file, Operation&& operation) {
  try {
    operation();
  } catch (...) {
    rethrow_naming(file);
  }
}

void copy_dataset(const h5::Group& from, const fs::path& source, h5::Group& to,
                  const fs::path& target, const std::string& name) {
  std::vector<double> values;
  std::vector<hsize_t> shape;
  naming(source, [&] {
    const h5::Dataset dataset = from.open_dataset(name);
    values = dataset.read_doubles();
    shape = dataset.shape();
  });
  naming(target, [&] { to.write_doubles(name, values, shape); });
}

// Adds one snapshot file's groups to the run file being assembled: every
// child of /particles, /grid, /xdmf and /xdmf_grid the run file lacks
// (/grid's origin and spacing, the same in every file, come once). Copied
// through our own reads and writes, not H5Ocopy: when a write under
// H5Ocopy failed (a full disk), HDF5 1.10.8 crashed (SIGSEGV in
// H5T_close_real) where our writes fail with a message. A failure names
// the snapshot file when reading it failed, the run file otherwise.
void copy_snapshot(const h5::Group& snapshot_root, const fs::path& source, h5::Group& run_root,
                   const fs::path& target) {
  for (const char* group_name : snapshot_groups) {
    std::optional<h5::Group> from;
    std::vector<std::string> children;
    naming(source, [&] {
      if (!snapshot_root.contains(group_name)) return;
      from.emplace(snapshot_root.open_group(group_name));
      children = from->children();
    });
    if (!from) continue;
    h5::Group to = run_root.require_group(group_name);
    for (const std::string& child : children) {
      if (to.contains(child)) continue;
      if (parse_step_name(child) < 0) {
        copy_dataset(*from, source, to, target, child);
        continue;
      }
      std::optional<std::int64_t> step;
      std::optional<double> time;
      std::vector<std::string> fields;
      std::optional<h5::Group> group;
      naming(source, [&] {
        group.emplace(from->open_group(child));
        if (group->has_attribute("step")) step = group->int_attribute("step");
        if (group->has_attribute("time")) time = group->double_attribute("time");
        fields = group->children();
      });
      h5::Group copy = to.create_group(child);
      if (step) copy.set_int_attribute("step", *step);
      if (time) copy.set_double_attribute("time", *time);
      for (const std::string& field : fields) copy_dataset(*group, source, copy, target, field);
    }
  }
}

void write_series_group(h5::Group& root, const std::vector<std::string>& names,
                        const std::vector<std::vector<double>>& columns) {
  std::string list;
  for (std::size_t i = 0; i < names.size(); ++i) list += (i == 0 ? "" : ",") + names[i];
  h5::Group series = root.create_group(series_group);
  series.set_string_attribute("columns", list);
  for (std::size_t i = 0; i < names.size(); ++i)
    series.write_doubles(names[i], columns[i], {static_cast<hsize_t>(columns[i].size())});
}

// The step of a snapshot file's name (step_<10 digits>.h5), or -1.
long snapshot_file_step(const fs::path& file) {
  if (file.extension() != ".h5") return -1;
  return parse_step_name(file.stem().string());
}

// The snapshot files in the partial directory, in step order.
std::map<long, fs::path> snapshot_files(const fs::path& partial) {
  std::map<long, fs::path> files;
  for (const fs::directory_entry& entry : fs::directory_iterator(partial)) {
    const long step = snapshot_file_step(entry.path());
    if (step >= 0) files.emplace(step, entry.path());
  }
  return files;
}

// A snapshot file a restart keeps must open and hold its snapshot: a
// damaged one is refused at the restart, not found at the run's end.
void check_snapshot_file(const fs::path& file, long step) {
  naming(file, [&] {
    const h5::File in = h5::File::open(file, h5::File::Mode::read_only);
    const h5::Group root = in.root();
    if (!root.contains(particles_group) ||
        !root.open_group(particles_group).contains(step_name(step)))
      throw std::runtime_error("holds no snapshot of step " + std::to_string(step));
  });
}

}  // namespace

RunWriter::RunWriter(fs::path dir, bool open) : dir_(std::move(dir)), open_(open) {}

RunWriter::RunWriter(const fs::path& dir) : dir_(dir) {
  fs::create_directories(dir_);
  fs::remove(h5_path());
  fs::remove(xdmf_path());
  fs::remove(grid_xdmf_path());
  fs::remove_all(partial_path());
  fs::create_directory(partial_path());
  open_ = true;
}

RunWriter RunWriter::reopen(const fs::path& dir, long last_step) {
  RunWriter writer(dir, true);
  const fs::path partial = writer.partial_path();
  if (!fs::exists(partial)) {
    throw std::runtime_error("cannot restart: " + partial.string() + " does not exist");
  }
  if (!fs::is_directory(partial)) {
    // Until 2026-12-01 the partial was one HDF5 file.
    throw std::runtime_error("cannot restart: " + partial.string() +
                             " is not a directory of snapshots (written by an older mmpm)");
  }
  std::vector<fs::path> stale;
  for (const fs::directory_entry& entry : fs::directory_iterator(partial)) {
    const long step = snapshot_file_step(entry.path());
    // .tmp files and a half-assembled run.h5 are what a killed process was
    // writing; later snapshots belong to steps the restart runs again.
    if (step < 0 || step > last_step) stale.push_back(entry.path());
  }
  for (const fs::path& path : stale) fs::remove_all(path);
  for (const auto& [step, file] : snapshot_files(partial)) check_snapshot_file(file, step);
  if (last_step >= 0 && !fs::exists(writer.snapshot_path(last_step))) {
    throw std::runtime_error(writer.snapshot_path(last_step).string() +
                             ": missing (the checkpoint's last snapshot)");
  }
  fsync_directory(partial);
  fs::remove(writer.h5_path());
  fs::remove(writer.xdmf_path());
  fs::remove(writer.grid_xdmf_path());
  return writer;
}

RunWriter::RunWriter(RunWriter&& other) noexcept
    : dir_(std::move(other.dir_)),
      open_(std::exchange(other.open_, false)),
      attributes_(std::move(other.attributes_)),
      series_(std::move(other.series_)),
      unsynced_(std::move(other.unsynced_)) {}

RunWriter& RunWriter::operator=(RunWriter&& other) noexcept {
  if (this != &other) {
    dir_ = std::move(other.dir_);
    open_ = std::exchange(other.open_, false);
    attributes_ = std::move(other.attributes_);
    series_ = std::move(other.series_);
    unsynced_ = std::move(other.unsynced_);
  }
  return *this;
}

RunWriter::~RunWriter() = default;

fs::path RunWriter::snapshot_path(long step) const {
  return partial_path() / (step_name(step) + ".h5");
}

void RunWriter::require_open(const char* operation) const {
  if (!open_) {
    throw std::logic_error(std::string("RunWriter::") + operation + " after finish() or abandon()");
  }
}

void RunWriter::set_attribute(const std::string& name, const std::string& value) {
  require_open("set_attribute");
  attributes_[name] = value;
}

void RunWriter::write_snapshot(const Snapshot& snapshot) {
  require_open("write_snapshot");
  check_snapshot(snapshot);
  check_grid(snapshot);
  const fs::path file = snapshot_path(snapshot.step);
  fs::path tmp = file;
  tmp += ".tmp";
  try {
    h5::File out = h5::File::create(tmp);
    {
      h5::Group root = out.root();
      write_snapshot_data(root, snapshot, step_name(snapshot.step));
    }  // every handle into the file is closed before the file itself
    out.close();
    fs::rename(tmp, file);
  } catch (...) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    rethrow_naming(tmp);
  }
  unsynced_.insert(file);
}

void RunWriter::sync() {
  require_open("sync");
  if (unsynced_.empty()) return;
  for (const fs::path& file : unsynced_) fsync_file(file);
  fsync_directory(partial_path());
  unsynced_.clear();
}

void RunWriter::write_series(const std::vector<std::string>& names,
                             const std::vector<std::vector<double>>& columns) {
  require_open("write_series");
  if (names.size() != columns.size()) {
    throw std::invalid_argument("time series: " + std::to_string(names.size()) + " names for " +
                                std::to_string(columns.size()) + " columns");
  }
  std::set<std::string> seen;
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
  }
  series_ = Series{names, columns};
}

void RunWriter::finish(const std::function<void()>& before_publishing) {
  require_open("finish");
  // Assembled inside the partial directory: a run killed while it is being
  // written leaves it where a restart removes it.
  const fs::path assembled = partial_path() / "run.h5";
  std::string document, grid_document;
  try {
    h5::File out = h5::File::create(assembled);
    {
      h5::Group root = out.root();
      root.set_int_attribute("mmpm_layout", 1);
      for (const auto& [name, value] : attributes_) root.set_string_attribute(name, value);
      for (const auto& [step, file] : snapshot_files(partial_path())) {
        std::optional<h5::File> in;
        std::optional<h5::Group> in_root;
        naming(file, [&] {
          in.emplace(h5::File::open(file, h5::File::Mode::read_only));
          in_root.emplace(in->root());
        });
        copy_snapshot(*in_root, file, root, assembled);
      }
      if (series_) write_series_group(root, series_->names, series_->columns);
      const std::vector<XdmfSnapshot> snapshots = describe(root);
      write_vertex_ids(root, snapshots);
      document = xdmf_document("run.h5", snapshots);
      const std::vector<XdmfGridSnapshot> grids = describe_grid(root);
      if (!grids.empty()) grid_document = xdmf_grid_document("run.h5", grids);
    }
    out.close();
    // The data must be on disk before the name that promises a complete result.
    fsync_file(assembled);
  } catch (...) {
    std::error_code ignored;
    fs::remove(assembled, ignored);
    rethrow_naming(assembled);
  }
  // Everything else first: if a write fails (a full disk), run.h5 does not
  // appear, the partial stays and the run can be restarted from its
  // checkpoint once there is room.
  try {
    write_file_atomic(xdmf_path(), document);
    if (!grid_document.empty()) write_file_atomic(grid_xdmf_path(), grid_document);
    if (before_publishing) before_publishing();
    fs::rename(assembled, h5_path());
  } catch (...) {
    std::error_code ignored;
    fs::remove(xdmf_path(), ignored);
    fs::remove(grid_xdmf_path(), ignored);
    fs::remove(assembled, ignored);
    throw;
  }
  fsync_directory(dir_);
  open_ = false;
  // run.h5 holds every snapshot now; a failure to tidy up loses nothing.
  std::error_code ignored;
  fs::remove_all(partial_path(), ignored);
}

void RunWriter::abandon() {
  // finish() or abandon() already ran (or this writer was moved from):
  // there is no partial of ours to delete.
  if (!open_) return;
  open_ = false;
  std::error_code ignored;
  fs::remove_all(partial_path(), ignored);
}

}  // namespace mmpm::io
