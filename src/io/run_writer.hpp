// The run's results: DIR/run.h5 (particle snapshots, time series, the
// resolved scene) and DIR/run.xdmf (opens run.h5 in ParaView).
//
// DIR/run_grid.xdmf opens /grid in ParaView when the run wrote grid data.
//
// While a run is going its snapshots are files of their own, in the
// directory DIR/run.h5.partial/: step_<10-digit step>.h5, each in run.h5's
// layout below holding that one snapshot, each written as a .tmp file and
// renamed once complete (and fsync'd before the next checkpoint, sync()).
// Only finish() assembles run.h5 from
// them (in run.h5.partial/run.h5, renamed to DIR/run.h5 once complete), so a
// run.h5 is always a complete result, and a run killed at any instant, even
// in the middle of a write, leaves every snapshot it had finished intact for
// `mmpm run --restart` (see reopen()). One HDF5 file written in place was
// not safe: a SIGKILL during a write left its free-space metadata
// inconsistent and the whole file unreadable (2026-12-01).
//
// Layout of run.h5 (all floating-point data in double precision):
//   /                           string attributes from set_attribute(),
//                               int attribute mmpm_layout = 1 (run.h5 only)
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
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace mmpm::io {

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
  // Creates DIR (and parents) and an empty DIR/run.h5.partial/, deleting any
  // old partial. A run.h5 / run.xdmf left from an earlier run in DIR is
  // deleted first: it does not describe this run.
  explicit RunWriter(const std::filesystem::path& dir);

  // For restart: takes over DIR/run.h5.partial/, deleting the snapshots with
  // step > last_step and whatever a killed process was writing (.tmp files,
  // a half-assembled run.h5), so that the restarted run ends with the same
  // content as an uninterrupted run's. Throws std::runtime_error naming the
  // file if there is no partial directory, or if a snapshot it keeps (or the
  // one at last_step, when last_step >= 0) is missing or unreadable.
  static RunWriter reopen(const std::filesystem::path& dir, long last_step);

  RunWriter(RunWriter&&) noexcept;
  RunWriter& operator=(RunWriter&&) noexcept;
  RunWriter(const RunWriter&) = delete;
  RunWriter& operator=(const RunWriter&) = delete;

  // Leaves the partial directory in place unless finish() or abandon() ran.
  ~RunWriter();

  // A string attribute on run.h5's root (resolved scene text, build and
  // machine description); replaces an attribute of the same name. Kept in
  // memory until finish(): a restart sets them again.
  void set_attribute(const std::string& name, const std::string& value);

  // Writes run.h5.partial/step_<10-digit step>.h5 (with grid data when the
  // snapshot carries some), replacing a snapshot already written for that
  // step: written as a .tmp file, closed (so handed to the operating
  // system, which keeps it whatever happens to this process) and renamed
  // into place. Throws std::invalid_argument on inconsistent sizes or bad
  // names, std::runtime_error on HDF5 or file system failures (then no
  // file of that step is left half-written).
  void write_snapshot(const Snapshot& snapshot);

  // Forces the snapshots written since the last sync() to stable storage
  // (fsync of each file, then of the directory), so that a checkpoint
  // written afterwards survives a machine crash with the snapshots it
  // refers to. Called before each checkpoint rather than after each
  // snapshot: an fsync per snapshot would tax runs that write one every
  // few steps.
  void sync();

  // The time series run.h5's /series will hold: columns[i] is the column
  // called names[i]; all columns have the same length. Checked now, kept in
  // memory until finish() (replacing an earlier call's).
  void write_series(const std::vector<std::string>& names,
                    const std::vector<std::vector<double>>& columns);

  // Assembles run.h5 from the snapshots, the attributes and the series,
  // writes run.xdmf describing every snapshot (and run_grid.xdmf for the
  // grid snapshots, if any), calls `before_publishing` (the driver's
  // summary.json), then renames the assembled file to run.h5 (atomically,
  // synced to disk) and removes the partial directory. If any of these but
  // the last throws, the xdmf files are removed, run.h5 does not appear and
  // the partial stays for a restart.
  void finish(const std::function<void()>& before_publishing = {});

  // Deletes the partial directory: a failed run leaves nothing that looks
  // like a result. Does nothing after finish().
  void abandon();

  const std::filesystem::path& directory() const { return dir_; }
  std::filesystem::path h5_path() const { return dir_ / "run.h5"; }
  std::filesystem::path partial_path() const { return dir_ / "run.h5.partial"; }
  std::filesystem::path snapshot_path(long step) const;  // in partial_path()
  std::filesystem::path xdmf_path() const { return dir_ / "run.xdmf"; }
  std::filesystem::path grid_xdmf_path() const { return dir_ / "run_grid.xdmf"; }

 private:
  struct Series {
    std::vector<std::string> names;
    std::vector<std::vector<double>> columns;
  };
  RunWriter(std::filesystem::path dir, bool open);
  void require_open(const char* operation) const;

  std::filesystem::path dir_;
  bool open_ = false;  // false once finish() or abandon() has run, or moved from
  std::map<std::string, std::string> attributes_;
  std::optional<Series> series_;              // none until write_series()
  std::set<std::filesystem::path> unsynced_;  // snapshot files since the last sync()
};

}  // namespace mmpm::io
