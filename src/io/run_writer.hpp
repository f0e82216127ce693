// The run's results: DIR/run.h5 (particle snapshots, time series, the
// resolved scene) and DIR/run.xdmf (opens run.h5 in ParaView).
//
// DIR/run_grid.xdmf opens /grid in ParaView when the run wrote grid data.
//
// While a run is going the file is DIR/run.h5.partial; only finish() gives it
// its real name, so a run.h5 is always a complete result. A killed run leaves
// its .partial behind for `mmpm run --restart` (see reopen()).
//
// Layout of run.h5 (all floating-point data in double precision):
//   /                           string attributes from set_attribute(),
//                               int attribute mmpm_layout = 1
//   /particles/step_0000000420  attributes step (int64), time (double)
//       position                [count x dimension]
//       <field>                 [count x components], one per ParticleField
//   /grid/origin, /grid/spacing [dimension], the grid's first node and cell
//   /grid/step_0000000420       attributes step, time; with output.grid_fields
//       <quantity>              [nz x] ny x nx x components (x fastest)
//   /series/<name>              1-D, one per time-series column; the group's
//                               attribute "columns" lists the names in order,
//                               comma-separated
//   /xdmf/...                   support data for run.xdmf only (vertex ids,
//                               2D vectors padded to 3 columns); scripts
//                               should read /particles and /series
#pragma once

#include <array>
#include <cstddef>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace mmpm::io {

namespace h5 {
class File;  // io/h5.hpp; kept out of this header so users need no HDF5 headers
}

struct ParticleField {
  std::string name;  // letters, digits, '_', '.', '-'; not "position"
  int components;
  std::vector<double> values;  // count * components, particle-major
};

// Nodal quantities written with a snapshot (SCENE.md "grid fields on
// request"): `fields` hold nodes * components values each, node-major with
// x fastest (node (i, j, k) at i + nx (j + ny k)); empty: no grid data.
struct GridSnapshot {
  std::array<int, 3> nodes{1, 1, 1};  // per direction (cells + 1); 1 beyond the dimension
  std::array<double, 3> origin{0, 0, 0};
  std::array<double, 3> spacing{1, 1, 1};
  std::vector<ParticleField> fields;
};

struct Snapshot {
  long step;
  double time;
  int dimension;  // 2 or 3
  std::size_t count;
  std::vector<double> position;  // count * dimension, particle-major
  std::vector<ParticleField> fields;
  GridSnapshot grid;
};

class RunWriter {
 public:
  // Creates DIR (and parents) and DIR/run.h5.partial, truncating any old
  // partial. A run.h5 / run.xdmf left from an earlier run in DIR is deleted
  // first: it does not describe this run.
  explicit RunWriter(const std::filesystem::path& dir);

  // For restart: opens the existing DIR/run.h5.partial and deletes the
  // snapshots with step > last_step and any time series, so that the
  // restarted run's file ends with the same content as an uninterrupted run's.
  // Throws std::runtime_error if there is no partial file or it is unreadable.
  static RunWriter reopen(const std::filesystem::path& dir, long last_step);

  RunWriter(RunWriter&&) noexcept;
  RunWriter& operator=(RunWriter&&) noexcept;  // the replaced writer is closed as by ~RunWriter
  RunWriter(const RunWriter&) = delete;
  RunWriter& operator=(const RunWriter&) = delete;

  // Leaves the .partial in place (closed) unless finish() or abandon() ran.
  ~RunWriter();

  // A string attribute on the file's root (resolved scene text, build and
  // machine description); replaces an attribute of the same name.
  void set_attribute(const std::string& name, const std::string& value);

  // Writes /particles/step_<10-digit step> (and /grid/step_<...> when the
  // snapshot carries grid data); a snapshot already present for
  // that step is replaced. Flushed to the operating system before returning,
  // so a checkpoint written afterwards never refers to a snapshot the
  // partial file lacks. Throws std::invalid_argument on inconsistent sizes
  // or bad names, std::runtime_error on HDF5 failures.
  void write_snapshot(const Snapshot& snapshot);

  // Writes /series (replacing it if present): columns[i] is the column
  // called names[i]; all columns have the same length.
  void write_series(const std::vector<std::string>& names,
                    const std::vector<std::vector<double>>& columns);

  // Closes the file, writes run.xdmf describing every snapshot in the file
  // (and run_grid.xdmf for the grid snapshots, if any), calls
  // `before_publishing` (the driver's summary.json), then renames
  // run.h5.partial to run.h5 (atomically, synced to disk). If any of these
  // throws, the xdmf files are removed and the partial stays.
  void finish(const std::function<void()>& before_publishing = {});

  // Closes and deletes the partial file: a failed run leaves nothing that
  // looks like a result. Does nothing after finish().
  void abandon();

  const std::filesystem::path& directory() const { return dir_; }
  std::filesystem::path h5_path() const { return dir_ / "run.h5"; }
  std::filesystem::path partial_path() const { return dir_ / "run.h5.partial"; }
  std::filesystem::path xdmf_path() const { return dir_ / "run.xdmf"; }
  std::filesystem::path grid_xdmf_path() const { return dir_ / "run_grid.xdmf"; }

 private:
  RunWriter(std::filesystem::path dir, std::unique_ptr<h5::File> file);
  bool is_open() const;
  void require_open(const char* operation) const;
  void close_quietly() noexcept;

  std::filesystem::path dir_;
  std::unique_ptr<h5::File> file_;  // null or closed once finish() or abandon() has run
};

}  // namespace mmpm::io
