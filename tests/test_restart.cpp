// `mmpm run --restart DIR` after a SIGKILL continues bitwise where the run
// left off: every particle snapshot in run.h5 (positions, displacements,
// velocities, stresses, materials) and every time-series column except the
// wall-clock stage_*_s timings are bitwise equal to those of an uninterrupted
// run, and so are the summary's steps, end time and energies.
//
// Scene: 2D gimp, two materials joined by a compliant interface (Dn = 300,
// Dt = 5: interface energy is part of the state), a traction ramp and a
// fixed face; 44 x 26 cells of 1 mm, 2592 particles, 670 steps, snapshots
// every 0.025 ms (11), a series row every 10 steps, and checkpoint_minutes =
// 1e-5 so that a checkpoint is written after almost every step (~1 s wall
// on an idle 2-core machine, several seconds on a loaded one).
// All runs use --threads 1 (thread-count independence is test_determinism's
// job; a loaded 2-core CI machine makes 2-thread runs slow and erratic).
// Tolerance: none (bitwise).
#include <gtest/gtest.h>
#include <signal.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "io/checkpoint.hpp"
#include "io/h5.hpp"
#include "test_util.hpp"

namespace {

using namespace mmpm_test;
using nlohmann::json;

const char* const kScene = R"(# restart test scene (tests/test_restart.cpp)
[simulation]
dimension = 2
plane = "strain"
end_time = 0.25
cfl = 0.5

[grid]
origin = [0.0, 0.0]
cell = [1.0, 1.0]
cells = [44, 26]
shape = "gimp"

[[material]]
name = "a"
type = "isotropic"
density = 1.0e-3
E = 1000.0
nu = 0.3

[[material]]
name = "b"
type = "isotropic"
density = 2.0e-3
E = 3000.0
nu = 0.25

[[body]]
name = "left"
material = "a"
shape = "box"
min = [4.0, 4.0]
max = [22.0, 22.0]
particles_per_cell = 2
velocity = [0.0, 2.0]

[[body]]
name = "right"
material = "b"
shape = "box"
min = [22.0, 4.0]
max = [40.0, 22.0]
particles_per_cell = 2
velocity = [0.0, -2.0]

[[interaction]]
materials = ["a", "b"]
law = "interface"
Dn = 300.0
Dt = 5.0
normal = "specified"
normal_vector = [1.0, 0.0]

[[boundary]]
where = "y_min"
fix = ["y"]

[[load]]
kind = "traction"
where = { body = "right", face = "x_max" }
traction = [1.0, 0.0]
ramp = 0.02

[output]
every = 0.025
series = 10
checkpoint_minutes = 1.0e-5
fields = ["displacement", "velocity", "stress", "material"]
grid_fields = ["mass", "velocity", "force"]
)";

// Everything run.h5 holds that a restart must reproduce.
struct RunFile {
  // snapshot group name -> dataset name -> values; plus the time/step attributes.
  std::map<std::string, std::map<std::string, std::vector<double>>> snapshots;
  std::map<std::string, std::pair<double, std::int64_t>> snapshot_time_step;
  // /grid: step group name -> quantity -> values (output.grid_fields).
  std::map<std::string, std::map<std::string, std::vector<double>>> grid;
  std::vector<std::string> columns;
  std::map<std::string, std::vector<double>> series;
};

RunFile read_run(const fs::path& file) {
  using namespace mmpm::io;
  RunFile r;
  const h5::File f = h5::File::open(file, h5::File::Mode::read_only);
  const h5::Group root = f.root();
  const h5::Group particles = root.open_group("particles");
  for (const std::string& name : particles.children()) {
    const h5::Group g = particles.open_group(name);
    r.snapshot_time_step[name] = {g.double_attribute("time"), g.int_attribute("step")};
    for (const std::string& ds : g.children())
      r.snapshots[name][ds] = g.open_dataset(ds).read_doubles();
  }
  if (root.contains("grid")) {
    const h5::Group grid = root.open_group("grid");
    for (const std::string& name : grid.children()) {
      if (name.rfind("step_", 0) != 0) continue;
      const h5::Group g = grid.open_group(name);
      for (const std::string& ds : g.children())
        r.grid[name][ds] = g.open_dataset(ds).read_doubles();
    }
  }
  const h5::Group series = root.open_group("series");
  std::string list = series.string_attribute("columns");
  std::stringstream in(list);
  for (std::string c; std::getline(in, c, ',');) {
    r.columns.push_back(c);
    r.series[c] = series.open_dataset(c).read_doubles();
  }
  return r;
}

bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

std::string first_diff(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size())
    return "sizes " + std::to_string(a.size()) + " vs " + std::to_string(b.size());
  for (std::size_t i = 0; i < a.size(); ++i)
    if (std::memcmp(&a[i], &b[i], sizeof(double)) != 0) {
      std::ostringstream s;
      s.precision(17);
      s << "entry " << i << ": " << a[i] << " vs " << b[i];
      return s.str();
    }
  return "none";
}

void expect_same_run(const RunFile& ref, const RunFile& got) {
  // Snapshots: the same steps, each bitwise equal.
  std::vector<std::string> a, b;
  for (const auto& [k, v] : ref.snapshots) a.push_back(k);
  for (const auto& [k, v] : got.snapshots) b.push_back(k);
  EXPECT_EQ(a, b) << "snapshot steps";
  EXPECT_GE(a.size(), 5u) << "the scene should write several snapshots";
  for (const auto& [name, datasets] : ref.snapshots) {
    if (!got.snapshots.count(name)) continue;
    const auto& other = got.snapshots.at(name);
    EXPECT_EQ(ref.snapshot_time_step.at(name), got.snapshot_time_step.at(name)) << name;
    for (const char* required : {"position", "velocity", "stress", "displacement"})
      EXPECT_TRUE(datasets.count(required)) << name << " lacks " << required;
    for (const auto& [ds, values] : datasets) {
      ASSERT_TRUE(other.count(ds)) << name << "/" << ds << " missing after restart";
      EXPECT_TRUE(same_bits(values, other.at(ds)))
          << name << "/" << ds << " differs: " << first_diff(values, other.at(ds));
    }
  }
  // Grid snapshots: the same steps and quantities, bitwise equal.
  EXPECT_EQ(ref.grid.size(), ref.snapshots.size()) << "a grid snapshot with every snapshot";
  EXPECT_EQ(ref.grid.size(), got.grid.size());
  for (const auto& [name, quantities] : ref.grid) {
    ASSERT_TRUE(got.grid.count(name)) << "grid " << name << " missing after restart";
    EXPECT_EQ(quantities.size(), got.grid.at(name).size()) << name;
    EXPECT_TRUE(quantities.count("velocity.a") && quantities.count("force.b")) << name;
    for (const auto& [q, values] : quantities) {
      ASSERT_TRUE(got.grid.at(name).count(q)) << name << "/" << q;
      EXPECT_TRUE(same_bits(values, got.grid.at(name).at(q)))
          << "grid " << name << "/" << q << ": " << first_diff(values, got.grid.at(name).at(q));
    }
  }
  // Series: same columns; all but the wall-clock timings bitwise equal.
  EXPECT_EQ(ref.columns, got.columns);
  int compared = 0;
  for (const auto& c : ref.columns) {
    if (c.rfind("stage_", 0) == 0) continue;
    if (!got.series.count(c)) continue;
    EXPECT_TRUE(same_bits(ref.series.at(c), got.series.at(c)))
        << "series " << c << ": " << first_diff(ref.series.at(c), got.series.at(c));
    ++compared;
  }
  for (const char* c :
       {"time", "step", "kinetic", "strain", "interface", "external_work", "damping"})
    EXPECT_TRUE(ref.series.count(c)) << "series column " << c;
  EXPECT_GE(compared, 7);
}

// The uninterrupted run of `scene` into dir (step 1 of both tests below).
json reference_run(const fs::path& scene, const fs::path& dir, double* seconds) {
  const CmdResult ref =
      run_mmpm({"run", scene.string(), "--out", dir.string(), "--threads", "1", "--quiet"});
  EXPECT_EQ(ref.exit_code, 0) << ref.describe();
  if (seconds) *seconds = ref.seconds;
  if (ref.exit_code != 0) return json();
  EXPECT_FALSE(fs::exists(dir / "checkpoint.bin")) << "a completed run removes its checkpoint";
  return json::parse(read_text(dir / "summary.json"));
}

// Runs the scene into dir (logs: <logs>.out, <logs>.err) and sends `sig`
// once dir/<ready> exists and `delay` seconds have passed. sent = false:
// the run ended before that.
struct SignalledRun {
  bool sent = false;
  CmdResult result;
};

SignalledRun signal_part_way(const fs::path& scene, const fs::path& dir, const fs::path& logs,
                             const char* ready, double delay, int sig) {
  Child child(
      {mmpm_binary(), "run", scene.string(), "--out", dir.string(), "--threads", "1", "--quiet"},
      logs.string() + ".out", logs.string() + ".err");
  const auto t0 = std::chrono::steady_clock::now();
  SignalledRun r;
  while (!child.poll_done()) {
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (fs::exists(dir / ready) && elapsed >= delay) {
      child.kill_and_wait(sig);
      r.sent = true;
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  r.result = child.result();
  return r;
}

void check_killed_run_continues_bitwise(const std::string& scene_text) {
  TempDir tmp;
  const fs::path scene = tmp / "restart_scene.toml";
  write_text(scene, scene_text);

  // 1. The uninterrupted run.
  const fs::path ref_dir = tmp / "ref";
  double ref_seconds = 0;
  const json ref_summary = reference_run(scene, ref_dir, &ref_seconds);
  ASSERT_FALSE(ref_summary.is_null());
  const long steps = ref_summary.at("steps").get<long>();
  ASSERT_GT(steps, 100);

  // 2. The same run, killed part-way (after its first checkpoint). If the
  // machine is so fast the run ends first, try again killing earlier.
  const fs::path dir = tmp / "killed";
  bool killed = false;
  for (double fraction : {0.4, 0.2, 0.08, 0.0}) {
    fs::remove_all(dir);
    const SignalledRun r = signal_part_way(scene, dir, tmp / "killed", "checkpoint.bin",
                                           fraction * ref_seconds, SIGKILL);
    killed = r.sent && r.result.signal == SIGKILL;
    if (killed) break;
    ASSERT_EQ(r.result.exit_code, 0)
        << "the run to be killed failed by itself: " << read_text(tmp / "killed.err");
  }
  ASSERT_TRUE(killed) << "could not kill the run before it finished";
  EXPECT_TRUE(fs::exists(dir / "checkpoint.bin"));
  EXPECT_FALSE(fs::exists(dir / "run.h5")) << "a killed run must not look finished";
  EXPECT_FALSE(fs::exists(dir / "summary.json")) << "a killed run must not look finished";
  EXPECT_TRUE(fs::exists(dir / "run.h5.partial"));

  // The checkpoint is from part-way through the run.
  const auto blobs = mmpm::io::read_checkpoint(dir / "checkpoint.bin");
  const long ckpt_step = mmpm::io::read_scalar_blob<long>(mmpm::io::find_blob(blobs, "step"));
  EXPECT_GT(ckpt_step, 0);
  EXPECT_LT(ckpt_step, steps);
  // ... and carries the wall time and stage times spent up to it.
  const double ckpt_wall =
      mmpm::io::read_scalar_blob<double>(mmpm::io::find_blob(blobs, "driver.wall_s"));
  EXPECT_GT(ckpt_wall, 0.0);

  // 2b. A checkpoint without one of the scene's columns (as one written
  // before the traction loads' face offsets, 2026-11-28) is refused: exit 2,
  // one message naming the file and the column, and the checkpoint stays.
  {
    std::vector<mmpm::io::Blob> lacking;
    for (const auto& b : blobs)
      if (b.name != "p.fofsx") lacking.push_back(b);
    ASSERT_EQ(lacking.size() + 1, blobs.size()) << "the scene has a traction load";
    mmpm::io::write_checkpoint(dir / "checkpoint.bin", lacking);
    const CmdResult refused =
        run_mmpm({"run", "--restart", dir.string(), "--threads", "1", "--quiet"});
    EXPECT_EQ(refused.exit_code, 2) << refused.describe();
    EXPECT_NE(refused.err.find("checkpoint.bin"), std::string::npos) << refused.err;
    EXPECT_NE(refused.err.find("p.fofsx"), std::string::npos) << refused.err;
    EXPECT_TRUE(fs::exists(dir / "checkpoint.bin"));
    EXPECT_FALSE(fs::exists(dir / "summary.json"));
    mmpm::io::write_checkpoint(dir / "checkpoint.bin", blobs);
  }

  // 2c. A scene.toml edited since the checkpoint (another E) is refused: the
  // checkpointed state would continue under other physics. Exit 2, the
  // message names the file and the edited line, and the checkpoint stays.
  const std::string resolved = read_text(dir / "scene.toml");
  {
    const std::size_t e_line = resolved.find("\nE = ");
    ASSERT_NE(e_line, std::string::npos) << resolved;
    std::string edited = resolved;
    edited.replace(e_line, resolved.find('\n', e_line + 1) - e_line, "\nE = 1234.5");
    write_text(dir / "scene.toml", edited);
    const CmdResult refused =
        run_mmpm({"run", "--restart", dir.string(), "--threads", "1", "--quiet"});
    EXPECT_EQ(refused.exit_code, 2) << refused.describe();
    EXPECT_TRUE(contains(refused.err, (dir / "scene.toml").string())) << refused.err;
    EXPECT_TRUE(contains(refused.err, "key 'material[0].E'")) << refused.err;
    EXPECT_TRUE(contains(refused.err, "`E = 1234.5`")) << refused.err;
    EXPECT_EQ(std::count(refused.err.begin(), refused.err.end(), '\n'), 1) << refused.err;
    EXPECT_TRUE(fs::exists(dir / "checkpoint.bin"));
    EXPECT_FALSE(fs::exists(dir / "summary.json"));
  }
  // A comment and blank lines change no value: the restart goes on.
  write_text(dir / "scene.toml", "# restarted by the test\n\n" + resolved);

  // 3. Restart and compare.
  const CmdResult again = run_mmpm({"run", "--restart", dir.string(), "--threads", "1", "--quiet"});
  ASSERT_EQ(again.exit_code, 0) << again.describe();
  ASSERT_TRUE(fs::exists(dir / "run.h5"));
  ASSERT_TRUE(fs::exists(dir / "summary.json"));
  EXPECT_TRUE(fs::exists(dir / "run.xdmf"));
  EXPECT_FALSE(fs::exists(dir / "run.h5.partial"));
  EXPECT_FALSE(fs::exists(dir / "checkpoint.bin"));

  expect_same_run(read_run(ref_dir / "run.h5"), read_run(dir / "run.h5"));

  const json got = json::parse(read_text(dir / "summary.json"));
  EXPECT_EQ(got.at("steps"), ref_summary.at("steps"));
  EXPECT_EQ(got.at("end_time").get<double>(), ref_summary.at("end_time").get<double>());
  EXPECT_EQ(got.at("particles"), ref_summary.at("particles"));
  for (const char* e : {"kinetic", "strain", "interface", "external_work", "damping"})
    EXPECT_EQ(got.at("energy").at(e).get<double>(), ref_summary.at("energy").at(e).get<double>())
        << e;
  EXPECT_EQ(got.at("multimaterial_nodes"), ref_summary.at("multimaterial_nodes"));
  // The summary's times cover every step of the result, as its step count
  // does: the segment before the checkpoint plus the resumed one (it took
  // only the resumed segment, so ns_per_particle_step read low).
  EXPECT_GT(got.at("wall_s").get<double>(), ckpt_wall);
  double stages = 0;
  for (const auto& [name, seconds] : got.at("stages_s").items()) stages += seconds.get<double>();
  EXPECT_NEAR(stages, got.at("wall_s").get<double>(), 1e-9 * got.at("wall_s").get<double>())
      << "stages_s (with other) add up to wall_s";
  EXPECT_GT(ref_summary.at("energy").at("interface").get<double>(), 0.0)
      << "the interface carries state";
}

TEST(Restart, KilledRunContinuesBitwise) {
  check_killed_run_continues_bitwise(kScene);
}

// A run stopped before its end (a full disk, a signal) looks unfinished,
// has a checkpoint from part-way through (or, stopped in its last writes,
// from its last step: `stopped_in_last_writes`), and `--restart` then ends
// with the uninterrupted run's results, bitwise.
void expect_stopped_then_restarts_bitwise(const fs::path& dir, const fs::path& ref_dir,
                                          const json& ref_summary,
                                          bool stopped_in_last_writes = false) {
  EXPECT_FALSE(fs::exists(dir / "run.h5")) << "a stopped run must not look finished";
  EXPECT_FALSE(fs::exists(dir / "summary.json")) << "a stopped run must not look finished";
  ASSERT_TRUE(fs::exists(dir / "checkpoint.bin"));
  const auto blobs = mmpm::io::read_checkpoint(dir / "checkpoint.bin");
  const long ckpt_step = mmpm::io::read_scalar_blob<long>(mmpm::io::find_blob(blobs, "step"));
  EXPECT_GT(ckpt_step, 0);
  if (stopped_in_last_writes)
    EXPECT_LE(ckpt_step, ref_summary.at("steps").get<long>());
  else
    EXPECT_LT(ckpt_step, ref_summary.at("steps").get<long>());

  const CmdResult again = run_mmpm({"run", "--restart", dir.string(), "--threads", "1", "--quiet"});
  ASSERT_EQ(again.exit_code, 0) << again.describe();
  expect_same_run(read_run(ref_dir / "run.h5"), read_run(dir / "run.h5"));
  const json got = json::parse(read_text(dir / "summary.json"));
  EXPECT_EQ(got.at("steps"), ref_summary.at("steps"));
  for (const char* e : {"kinetic", "strain", "interface", "external_work", "damping"})
    EXPECT_EQ(got.at("energy").at(e).get<double>(), ref_summary.at("energy").at(e).get<double>())
        << e;
  // The last step's counters, which a restart at the last step took from a
  // simulation that had taken no step (0) until 2026-12-01.
  for (const char* c : {"multimaterial_nodes", "nodes_3plus", "force_limited_nodes"})
    EXPECT_EQ(got.at(c), ref_summary.at(c)) << c;
}

// A run whose output cannot grow (a full disk; here a file size limit,
// `ulimit -f`, with SIGXFSZ ignored so that the write fails with EFBIG as
// it does with ENOSPC) stops with exit 3 and one line naming the file and
// the system's reason; it leaves no run.h5 or summary.json, and its last
// checkpoint restarts it, once there is room, to the uninterrupted run's
// results bitwise. HDF5's exit handler used to crash the process (SIGSEGV
// after the message) closing the file whose writes had failed (io/h5.cpp).
// The limit, 1500 KiB, is per file: each of the scene's 11 snapshot files
// (0.69 MB with its grid fields) and the checkpoint (0.46 MB) fit under
// it, and the write that fails is the assembly of run.h5 (7.4 MB) at the
// run's end (io/run_writer.hpp; until 2026-12-01 the snapshots went into
// one run.h5.partial file as they came, which passed the limit part-way
// through the run). HDF5's
// H5Ocopy crashed (SIGSEGV) when that write failed under it; the assembly
// copies through mmpm's own reads and writes. A disk that fills up
// part-way is the same failure in an earlier write: a snapshot's
// (IoRunWriter.FailedSnapshotWriteLeavesNoFile) or a checkpoint's.
TEST(Restart, RunStoppedByAFullDiskContinuesBitwise) {
  TempDir tmp;
  const fs::path scene = tmp / "restart_scene.toml";
  write_text(scene, kScene);
  const fs::path ref_dir = tmp / "ref";
  const json ref_summary = reference_run(scene, ref_dir, nullptr);
  ASSERT_FALSE(ref_summary.is_null());

  const fs::path dir = tmp / "full";
  const CmdResult full = run_command(
      {"/bin/bash", "-c",
       "trap '' XFSZ; ulimit -f 1500; exec \"$0\" run \"$1\" --out \"$2\" --threads 1 --quiet",
       mmpm_binary(), scene.string(), dir.string()});
  EXPECT_EQ(full.signal, 0) << full.describe();
  ASSERT_EQ(full.exit_code, 3) << full.describe();
  ASSERT_EQ(lines_of(full.err).size(), 1u) << full.describe();
  EXPECT_TRUE(contains(full.err, "run.h5.partial/run.h5")) << full.err;
  EXPECT_TRUE(contains(full.err, "File too large")) << full.err;
  expect_stopped_then_restarts_bitwise(dir, ref_dir, ref_summary, true);
}

// Ctrl-C or a batch system's SIGTERM (app/interrupt.hpp) stops the run
// between two steps with a checkpoint, even with checkpoint_minutes = 0 as
// here: exit 128 + signal, one stderr line that says how to continue, no
// run.h5 or summary.json; `--restart` then ends bitwise equal to the
// uninterrupted run. Until 2026-11-28 the signal killed the process and,
// without periodic checkpoints, lost the whole run. The signal is sent
// once the run has written its first snapshot and a third of the
// reference run's time has passed; a run that ends first is retried.
void check_interrupted_run_continues_bitwise(int sig, const char* name) {
  TempDir tmp;
  const fs::path scene = tmp / "restart_scene.toml";
  std::string text = kScene;
  const std::string every = "checkpoint_minutes = 1.0e-5";
  ASSERT_NE(text.find(every), std::string::npos);
  text.replace(text.find(every), every.size(), "checkpoint_minutes = 0");
  write_text(scene, text);
  const fs::path ref_dir = tmp / "ref";
  double ref_seconds = 0;
  const json ref_summary = reference_run(scene, ref_dir, &ref_seconds);
  ASSERT_FALSE(ref_summary.is_null());

  const fs::path dir = tmp / "stopped";
  bool stopped = false;
  for (double fraction : {0.33, 0.1, 0.0}) {
    fs::remove_all(dir);
    const SignalledRun r =
        signal_part_way(scene, dir, tmp / "stopped", "run.h5.partial", fraction * ref_seconds, sig);
    if (r.sent) {
      // A signal after the last step finds a finished run: try earlier.
      if (r.result.exit_code == 0 && fs::exists(dir / "summary.json")) continue;
      EXPECT_EQ(r.result.signal, 0) << name << " killed the process";
      EXPECT_EQ(r.result.exit_code, 128 + sig);
      stopped = true;
      break;
    }
    ASSERT_EQ(r.result.exit_code, 0) << read_text(tmp / "stopped.err");
  }
  ASSERT_TRUE(stopped) << "could not stop the run before it finished";
  const std::string err = read_text(tmp / "stopped.err");
  ASSERT_EQ(lines_of(err).size(), 1u) << err;
  EXPECT_TRUE(contains(err, std::string("interrupted by ") + name)) << err;
  EXPECT_TRUE(contains(err, "mmpm run --restart " + dir.string())) << err;
  expect_stopped_then_restarts_bitwise(dir, ref_dir, ref_summary);
}

TEST(Restart, SigtermStopsWithACheckpointAndContinuesBitwise) {
  check_interrupted_run_continues_bitwise(SIGTERM, "SIGTERM");
}

TEST(Restart, SigintStopsWithACheckpointAndContinuesBitwise) {
  check_interrupted_run_continues_bitwise(SIGINT, "SIGINT");
}

// The same in float, whose particles carry one more column per axis, the
// positions' low parts (kernels/position_sum.hpp): a restart that lost it
// would move every particle by up to half an ulp and differ in the bits.
TEST(Restart, KilledFloatRunContinuesBitwise) {
  std::string scene = kScene;
  const std::string at = "cfl = 0.5\n";
  scene.replace(scene.find(at), at.size(), at + "precision = \"float\"\n");
  check_killed_run_continues_bitwise(scene);
}

// With quadratic B-splines, and the support a plane under the bodies, a
// mirror (kernels/mirror_supports.hpp): its folds keep no state between
// steps, so the restart continues bitwise as well.
TEST(Restart, KilledBSplineRunWithAMirrorContinuesBitwise) {
  std::string scene = kScene;
  const auto swap = [&](const std::string& from, const std::string& to) {
    scene.replace(scene.find(from), from.size(), to);
  };
  swap("shape = \"gimp\"", "shape = \"bspline2\"");
  swap("where = \"y_min\"", "where = { y = 4.0 }");
  check_killed_run_continues_bitwise(scene);
}

// With XPIC(2) (kernels/xpic.hpp): the restart reads the resolved scene the
// checkpoint keeps, which did not write xpic_order until 2026-12-07, so the
// run went on as pure FLIP (an outside review's kill and restart: kinetic
// energy 0.0023431 against 0.0023027).
TEST(Restart, KilledXpicRunContinuesBitwise) {
  std::string scene = kScene;
  const std::string at = "cfl = 0.5\n";
  ASSERT_NE(scene.find(at), std::string::npos);
  scene.replace(scene.find(at), at.size(), at + "xpic_order = 2\n");
  check_killed_run_continues_bitwise(scene);
}

// With normal = "geometry" on bodies turned by 10 degrees: each step fits
// every body's rotation and translation from its particles' seeded and
// current positions (solver/geometry_normals.hpp), so a restart that lost
// the seeded positions, or numbered the particles' bodies otherwise,
// would turn the interface's normals and differ in the bits.
TEST(Restart, KilledGeometryNormalRunContinuesBitwise) {
  std::string scene = kScene;
  const auto swap = [&](const std::string& from, const std::string& to) {
    const auto at = scene.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    scene.replace(at, from.size(), to);
  };
  const std::string turned = "rotate = 10.0\npivot = [22.0, 13.0]\n";
  swap("velocity = [0.0, 2.0]\n", "velocity = [0.0, 2.0]\n" + turned);
  swap("velocity = [0.0, -2.0]\n", "velocity = [0.0, -2.0]\n" + turned);
  swap("normal = \"specified\"\nnormal_vector = [1.0, 0.0]\n", "normal = \"geometry\"\n");
  check_killed_run_continues_bitwise(scene);
}

}  // namespace
