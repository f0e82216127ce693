// Bad input found by a fuzzing session (2026-11-29, ~10 400 mutated scenes
// and command lines): each case below hung, crashed at the end of a run,
// exited 3 for bad input, or ran a scene that could not be what was meant.
// Each test runs the real binary (MMPM_BINARY) under coreutils' timeout, so
// a hang fails the test (exit 124) instead of stalling the suite.
//
// Scene: inputs/bar_vibration.toml (400 particles, dt ~4e-5 ms).
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>

#include <chrono>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "test_util.hpp"

namespace {

using namespace mmpm_test;
using nlohmann::json;

std::string bar_scene() {
  return source_dir() + "/inputs/bar_vibration.toml";
}

CmdResult run_mmpm_within(const std::vector<std::string>& args, int seconds) {
  std::vector<std::string> all{"/usr/bin/timeout", std::to_string(seconds), mmpm_binary()};
  all.insert(all.end(), args.begin(), args.end());
  return run_command(all);
}

void expect_one_line(const CmdResult& r, const std::string& needle) {
  const auto lines = lines_of(r.err);
  ASSERT_EQ(lines.size(), 1u) << r.describe();
  EXPECT_TRUE(contains(lines[0], needle)) << needle << "\n" << lines[0];
}

// A forced step of 1e308 with snapshots every 0.002 ms: half a step before
// each snapshot time was past every time the run could reach, so the
// snapshot counter's loop never ended (100 % CPU, SIGTERM not seen). Now
// the single shortened step runs and the energy check stops it (exit 3).
TEST(CliRobustness, ForcedHugeStepWithSnapshotsEnds) {
  TempDir tmp;
  const CmdResult r =
      run_mmpm_within({"run", bar_scene(), "--force", "--quiet", "--threads", "1", "--out",
                       (tmp / "o").string(), "--set", "simulation.dt=1e308", "--set",
                       "simulation.end_time=0.004", "--set", "output.every=0.002"},
                      60);
  ASSERT_NE(r.exit_code, 124) << "timed out: the run did not end\n" << r.describe();
  EXPECT_EQ(r.exit_code, 3) << r.describe();
  expect_one_line(r, "unstable");
}

// end_time below 1e-9 of a step: the run loop counted it reached before the
// first step and reported a finished run of 0 steps (exit 0).
TEST(CliRobustness, EndTimeBelowOneStepTakesOneStep) {
  TempDir tmp;
  const CmdResult c =
      run_mmpm_within({"check", bar_scene(), "--set", "simulation.end_time=1e-14"}, 60);
  ASSERT_EQ(c.exit_code, 0) << c.describe();
  EXPECT_TRUE(contains(c.out, "steps: 1\n")) << c.out;
  const fs::path out = tmp / "o";
  const CmdResult r = run_mmpm_within(
      {"run", bar_scene(), "--quiet", "--out", out.string(), "--set", "simulation.end_time=1e-14"},
      60);
  ASSERT_EQ(r.exit_code, 0) << r.describe();
  const json j = json::parse(read_text(out / "summary.json"));
  EXPECT_EQ(j.at("steps").get<long>(), 1);
  EXPECT_EQ(j.at("end_time").get<double>(), 1e-14);
}

// 20 000 steps of 1.25e-5 ms summed one by one reach 0.24999999999997452,
// 2e-9 of a step short of end_time = 0.25: the run loop took one more step
// of that length, whose impulses over dt are round-off (in
// inputs/stiff_platen.toml's last row a support reaction of 6013 N against
// 10.97). end_time_tolerance now counts the summation's drift.
TEST(CliRobustness, StepsSummedShortOfEndTimeTakeNoSliverStep) {
  TempDir tmp;
  const std::vector<std::string> sets{"--set", "simulation.dt=1.25e-5",
                                      "--set", "simulation.end_time=0.25",
                                      "--set", "output.every=0"};
  std::vector<std::string> check{"check", bar_scene()};
  check.insert(check.end(), sets.begin(), sets.end());
  const CmdResult c = run_mmpm_within(check, 60);
  ASSERT_EQ(c.exit_code, 0) << c.describe();
  EXPECT_TRUE(contains(c.out, "steps: 20000\n")) << c.out;
  const fs::path out = tmp / "o";
  std::vector<std::string> run{"run", bar_scene(), "--quiet",   "--threads",
                               "1",   "--out",     out.string()};
  run.insert(run.end(), sets.begin(), sets.end());
  const CmdResult r = run_mmpm_within(run, 120);
  ASSERT_EQ(r.exit_code, 0) << r.describe();
  const json j = json::parse(read_text(out / "summary.json"));
  EXPECT_EQ(j.at("steps").get<long>(), 20000);
  EXPECT_NEAR(j.at("end_time").get<double>(), 0.25, 1e-6 * 1.25e-5);
}

// A device or a pipe was read until it ended: /dev/zero filled the memory
// (the kernel killed mmpm), a FIFO with no writer blocked for ever.
TEST(CliRobustness, SceneThatIsNotARegularFileIsBadInput) {
  TempDir tmp;
  const fs::path fifo = tmp / "scene.toml";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  for (const std::string& path : {std::string("/dev/zero"), fifo.string()}) {
    const CmdResult r = run_mmpm_within({"check", path}, 30);
    EXPECT_EQ(r.exit_code, 2) << path << "\n" << r.describe();
    expect_one_line(r, path + ": is not a regular file");
  }
}

// toml11 reads a line in time growing with the square of its length (a
// 2 MB line of polygon points did not finish in a minute): longer lines
// than 64 KiB are refused with the way round, and quickly.
TEST(CliRobustness, OverlongLineIsRefused) {
  TempDir tmp;
  std::string array = "padding = [";
  while (array.size() < 70000) array += "[0.123456, 0.654321], ";
  array += "[0.0, 0.0]]\n";
  const fs::path scene = tmp / "long.toml";
  write_text(scene, array + read_text(bar_scene()));
  const auto t0 = std::chrono::steady_clock::now();
  const CmdResult r = run_mmpm_within({"check", scene.string()}, 30);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(r.exit_code, 2) << r.describe();
  expect_one_line(r, scene.string() + ":1: line of ");
  EXPECT_LT(seconds, 5.0) << "the refusal reads no TOML";
}

// A scene's name defaults to its file's stem; one that is not UTF-8 made the
// run fail at its very end (the JSON writer refused the name, exit 3), with
// a scene.toml that could not be read back.
TEST(CliRobustness, FileNameThatIsNotUtf8NeedsASceneName) {
  TempDir tmp;
  const fs::path scene = tmp /
                         "n\xff"
                         "ame.toml";
  write_text(scene, read_text(bar_scene()));
  const CmdResult r = run_mmpm_within({"check", scene.string()}, 30);
  EXPECT_EQ(r.exit_code, 2) << r.describe();
  expect_one_line(r, "'simulation.name'");
  const CmdResult named =
      run_mmpm_within({"check", scene.string(), "--set", "simulation.name=\"bar\""}, 30);
  EXPECT_EQ(named.exit_code, 0) << named.describe();
}

// toml11 names its own function in some messages ("parse_ml_basic_string:
// invalid utf8 sequence found"); the message keeps what the user can act on.
TEST(CliRobustness, SyntaxErrorsDoNotNameTheReadersFunctions) {
  TempDir tmp;
  const fs::path scene = tmp / "bad_utf8.toml";
  write_text(scene, "[simulation]\nname = \"a\xff\"\n");
  const CmdResult r = run_mmpm_within({"check", scene.string()}, 30);
  EXPECT_EQ(r.exit_code, 2) << r.describe();
  expect_one_line(r, scene.string() + ":2: TOML syntax error: invalid utf8");
  EXPECT_FALSE(contains(r.err, "parse_")) << r.err;
}

// A traction on a body the later bodies replace everywhere acted on nothing
// (exit 0, external work 0). The covered body alone stays allowed (an
// inclusion inside a later, larger one: Bodies.ManyOverlaps*).
TEST(CliRobustness, TractionOnABodyReplacedEverywhereIsBadInput) {
  TempDir tmp;
  std::string text = read_text(bar_scene());
  text +=
      "\n[[body]]\nname = \"cover\"\nmaterial = \"steel\"\nshape = \"box\"\n"
      "min = [0.0, 0.0]\nmax = [25.0, 1.0]\nparticles_per_cell = 2\n";
  const fs::path covered = tmp / "covered.toml";
  write_text(covered, text);
  EXPECT_EQ(run_mmpm_within({"check", covered.string()}, 30).exit_code, 0);
  const fs::path loaded = tmp / "loaded.toml";
  write_text(loaded, text +
                         "\n[[load]]\nkind = \"traction\"\nwhere = { body = \"bar\", face = "
                         "\"x_max\" }\ntraction = [1.0, 0.0]\n");
  const CmdResult r = run_mmpm_within({"check", loaded.string()}, 30);
  EXPECT_EQ(r.exit_code, 2) << r.describe();
  expect_one_line(r, "'load[0].where': body \"bar\" holds no particle");
}

// In float, constants each within [1e-30, 1e30] still multiplied into a
// particle mass of 1e58: `check` passed it and the run stopped at step 1 as
// "unstable" with NaN energies. The same scene in double runs.
TEST(CliRobustness, FloatScalesOutsideItsRangeAreBadInput) {
  const std::vector<std::string> huge{"--set", "material[0].density=1e30", "--set",
                                      "simulation.thickness=1e30"};
  std::vector<std::string> args{"check", bar_scene(), "--set", "simulation.precision=\"float\""};
  args.insert(args.end(), huge.begin(), huge.end());
  const CmdResult r = run_mmpm_within(args, 30);
  EXPECT_EQ(r.exit_code, 2) << r.describe();
  expect_one_line(r, "particle mass");
  args = {"check", bar_scene()};
  args.insert(args.end(), huge.begin(), huge.end());
  EXPECT_EQ(run_mmpm_within(args, 30).exit_code, 0);
}

// The memory guard compared the scene's estimate with the machine's RAM; under
// `ulimit -v` the particles were built until std::bad_alloc (exit 3, "error:
// std::bad_alloc"). 400^2 particles per cell over the bar's 100 cells, ~5 GB,
// against a 3 GB limit.
TEST(CliRobustness, AddressSpaceLimitIsSeenByTheMemoryGuard) {
  const CmdResult r =
      run_command({"/bin/sh", "-c",
                   "ulimit -v 3000000 && exec /usr/bin/timeout 60 " + mmpm_binary() + " check " +
                       bar_scene() + " --set body[0].particles_per_cell=400"});
  EXPECT_EQ(r.exit_code, 2) << r.describe();
  expect_one_line(r, "more than the memory this process may use");
}

// A restart directory whose run.h5.partial is missing or damaged: exit 3
// with HDF5's message before; it is bad input like a damaged checkpoint.
// The message names the file (for a damaged snapshot, its own file).
TEST(CliRobustness, RestartWithDamagedSnapshotsIsBadInput) {
  TempDir tmp;
  const fs::path dir = tmp / "stopped";
  {
    Child child({mmpm_binary(), "run", bar_scene(), "--out", dir.string(), "--threads", "1",
                 "--quiet", "--set", "simulation.end_time=1000"},
                tmp / "run.out", tmp / "run.err");
    const auto t0 = std::chrono::steady_clock::now();
    while (!fs::exists(dir / "run.h5.partial") &&
           std::chrono::steady_clock::now() - t0 < std::chrono::seconds(30))
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    child.kill_and_wait(SIGTERM);
    ASSERT_EQ(child.result().exit_code, 128 + SIGTERM) << read_text(tmp / "run.err");
  }
  ASSERT_TRUE(fs::exists(dir / "checkpoint.bin"));
  struct Damage {
    const char* name;
    void (*apply)(const fs::path&);
  };
  // The partial is a directory of snapshot files (io/run_writer.hpp); the
  // first one, step 0's, is one every restart keeps.
  const Damage damages[] = {
      {"missing", [](const fs::path& p) { fs::remove_all(p); }},
      {"truncated",
       [](const fs::path& p) {
         const fs::path first = p / "step_0000000000.h5";
         fs::resize_file(first, fs::file_size(first) / 2);
       }},
      {"garbage",
       [](const fs::path& p) { write_text(p / "step_0000000000.h5", std::string(4096, 'x')); }},
      {"a file, as an older mmpm left it",
       [](const fs::path& p) {
         fs::remove_all(p);
         write_text(p, std::string(4096, 'x'));
       }},
  };
  for (const Damage& d : damages) {
    const fs::path copy = tmp / ("damaged_" + std::to_string(&d - damages));
    fs::copy(dir, copy, fs::copy_options::recursive);
    d.apply(copy / "run.h5.partial");
    const CmdResult r = run_mmpm_within({"run", "--restart", copy.string(), "--quiet"}, 60);
    EXPECT_EQ(r.exit_code, 2) << d.name << "\n" << r.describe();
    expect_one_line(r, "run.h5.partial");
  }
}

}  // namespace

namespace {

// Three messages that named the wrong thing: a --set into an array of
// numbers was told the array held tables; a --set that put a number into
// [[interaction]] was blamed on the file's line; an unwritable
// output.directory from the scene had no file or line.
TEST(CliRobustness, MessagesNameWhatWasWritten) {
  TempDir tmp;
  const std::string two_layer = source_dir() + "/inputs/two_layer.toml";
  const CmdResult cell = run_mmpm_within({"check", bar_scene(), "--set", "grid.cell.x=1"}, 30);
  EXPECT_EQ(cell.exit_code, 2) << cell.describe();
  expect_one_line(cell, "\"cell\" is an array of values, not a table");
  const CmdResult element = run_mmpm_within({"check", two_layer, "--set", "interaction[0]=1"}, 30);
  EXPECT_EQ(element.exit_code, 2) << element.describe();
  expect_one_line(element, "--set interaction[0]: key 'interaction[0]'");
  const std::string text = read_text(bar_scene());
  const std::string section = "[output]\n";
  const auto at = text.find(section);
  ASSERT_NE(at, std::string::npos);
  const fs::path scene = tmp / "out_dir.toml";
  write_text(scene, text.substr(0, at + section.size()) + "directory = \"/dev/null/x\"\n" +
                        text.substr(at + section.size()));
  const int line = line_of(read_text(scene), "directory =");
  const CmdResult r = run_mmpm_within({"run", scene.string(), "--quiet"}, 30);
  EXPECT_EQ(r.exit_code, 2) << r.describe();
  expect_one_line(r, scene.string() + ":" + std::to_string(line) +
                         ": key 'output.directory': /dev/null/x: cannot write");
}

}  // namespace

namespace {

// A swept value that makes the step unstable (or the run endless) was a
// failed row, exit 3, after the other rows had run; `run` calls it bad
// input. It is now refused before any row runs, naming the row.
TEST(CliRobustness, SweepValueWithAnUnstableStepIsBadInputBeforeAnyRun) {
  TempDir tmp;
  const fs::path out = tmp / "sweep";
  const CmdResult r =
      run_mmpm_within({"sweep", bar_scene(), "--param", "simulation.dt", "--values", "1e-5,1",
                       "--set", "simulation.end_time=0.001", "--out", out.string()},
                      60);
  EXPECT_EQ(r.exit_code, 2) << r.describe();
  expect_one_line(r, "[2/2] simulation.dt=1: ");
  EXPECT_TRUE(contains(r.err, "stability limit")) << r.err;
  EXPECT_FALSE(fs::exists(out / "0")) << "no row may run";
  // The remedy it names works in a sweep (which has no --force flag): both
  // rows run. The forced row's one step is shortened to end_time (0.001,
  // 10x the limit), which stays inside the energy check: exit 0.
  EXPECT_TRUE(contains(r.err, "or simulation.force = true")) << r.err;
  const CmdResult forced =
      run_mmpm_within({"sweep", bar_scene(), "--param", "simulation.dt", "--values", "1e-5,1",
                       "--set", "simulation.end_time=0.001", "--set", "simulation.force=true",
                       "--out", (tmp / "forced").string()},
                      60);
  EXPECT_EQ(forced.exit_code, 0) << forced.describe();
  EXPECT_TRUE(fs::exists(tmp / "forced" / "1" / "summary.json")) << forced.describe();
}

// More jobs than cores: TBB kept one worker per core, ran fewer rows at
// once and printed its own warning ("TBB Warning: The number of workers is
// currently limited to 1"). The rows' lines are whole lines.
TEST(CliRobustness, SweepWithMoreJobsThanCoresRunsThemAll) {
  TempDir tmp;
  const fs::path out = tmp / "sweep";
  const CmdResult r = run_mmpm_within(
      {"sweep", bar_scene(), "--param", "material[0].E", "--values", "1e5,2e5,3e5,4e5", "--set",
       "simulation.end_time=0.001", "--jobs", "4", "--out", out.string()},
      120);
  EXPECT_EQ(r.exit_code, 0) << r.describe();
  EXPECT_FALSE(contains(r.err, "TBB")) << r.err;
  const auto lines = lines_of(r.err);
  ASSERT_EQ(lines.size(), 5u) << r.err;  // four rows and "wrote"
  for (const std::string& line : lines)
    EXPECT_TRUE(line.starts_with("[") || line.starts_with("wrote ")) << line;
}

}  // namespace
