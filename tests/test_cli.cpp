// The `mmpm` command line through the real binary (MMPM_BINARY): exit codes,
// the one-line error messages of SCENE.md, what a failed run leaves behind,
// the summary.json contract, sweeps and --set.
//
// Scenes: inputs/bar_vibration.toml (400 particles), shortened with --set
// simulation.end_time (0.05 ms = 1267 steps, well under a second) or edited
// line by line for the bad-input cases. Tolerances: stages + other = wall_s
// and ns_per_particle_step = wall_s 1e9 / (particles steps) to 1e-9
// relative (both are computed from the same doubles; JSON keeps 17 digits).
#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "io/h5.hpp"
#include "test_util.hpp"

namespace {

using namespace mmpm_test;
using nlohmann::json;

std::string bar_scene() {
  return source_dir() + "/inputs/bar_vibration.toml";
}

// bar_vibration.toml with the line starting with `line_start` replaced by `replacement`.
std::string edited_bar(const std::string& line_start, const std::string& replacement) {
  const std::string text = read_text(bar_scene());
  std::istringstream in(text);
  std::string out, line;
  bool done = false;
  while (std::getline(in, line)) {
    if (!done && line.rfind(line_start, 0) == 0) {
      out += replacement + "\n";
      done = true;
    } else {
      out += line + "\n";
    }
  }
  EXPECT_TRUE(done) << "bar_vibration.toml has no line starting with " << line_start;
  return out;
}

void expect_no_result(const fs::path& dir) {
  EXPECT_FALSE(fs::exists(dir / "run.h5")) << dir;
  EXPECT_FALSE(fs::exists(dir / "summary.json")) << dir;
  EXPECT_FALSE(fs::exists(dir / "run.xdmf")) << dir;
}

TEST(Cli, InfoMentionsSimdAndOpenMP) {
  const CmdResult r = run_mmpm({"info"});
  ASSERT_EQ(r.exit_code, 0) << r.describe();
  EXPECT_TRUE(contains(lower(r.out), "simd")) << r.out;
  EXPECT_TRUE(contains(lower(r.out), "openmp")) << r.out;
  // Which 2D linear transfers this build runs (packed only with AVX-512).
#ifdef __AVX512F__
  EXPECT_TRUE(
      contains(r.out, "2d linear kernels: packed (2 particles per vector in double, 4 in float)"))
      << r.out;
#else
  EXPECT_TRUE(contains(r.out, "2d linear kernels: one particle per vector")) << r.out;
#endif
}

TEST(Cli, CheckShippedScene) {
  const CmdResult r = run_mmpm({"check", bar_scene()});
  ASSERT_EQ(r.exit_code, 0) << r.describe();
  EXPECT_TRUE(contains(r.out, "[simulation]")) << "prints the resolved scene";
  EXPECT_FALSE(contains(lower(r.err), "warning")) << r.err;
}

TEST(Cli, UsageErrorsExit2) {
  EXPECT_EQ(run_mmpm({}).exit_code, 2);
  EXPECT_EQ(run_mmpm({"run", "--bogus"}).exit_code, 2);
  const CmdResult r = run_mmpm({"run", "/nonexistent/scene.toml"});
  EXPECT_EQ(r.exit_code, 2) << r.describe();
  EXPECT_TRUE(contains(r.err, "/nonexistent/scene.toml")) << r.err;
}

// Command-line errors get one line, as scene errors do (CLI11's own report
// added "Run with --help for more information." on a second one).
TEST(Cli, CommandLineErrorsAreOneLine) {
  TempDir tmp;
  const std::string out = (tmp / "o").string();
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"run", bar_scene(), "--bogus"},
        {"run", bar_scene(), "--threads", "0"},
        {"sweep", bar_scene(), "--param", "material[0].E", "--values", "1", "--jobs", "0"},
        {"check"},
        {"run", bar_scene(), "--out", ""},
        // A restart continues DIR's own scene: --set, --out or a scene file
        // would have been ignored without a word.
        {"run", "--restart", out, "--set", "simulation.end_time=0.1"},
        {"run", "--restart", out, "--out", out},
        {"run", bar_scene(), "--restart", out}}) {
    const CmdResult r = run_mmpm(args);
    EXPECT_EQ(r.exit_code, 2) << args.back() << "\n" << r.describe();
    EXPECT_EQ(lines_of(r.err).size(), 1u) << r.describe();
    EXPECT_FALSE(fs::exists(out)) << r.describe();
  }
}

// A checkpoint.bin that is a directory failed in the read with
// "basic_filebuf::underflow error reading the file", naming no file.
TEST(Cli, RestartFromADirectoryNamedCheckpointNamesIt) {
  TempDir tmp;
  const fs::path out = tmp / "o";
  ASSERT_EQ(run_mmpm({"run", bar_scene(), "--out", out.string(), "--quiet", "--set",
                      "simulation.end_time=0.01"})
                .exit_code,
            0);
  fs::create_directory(out / "checkpoint.bin");
  const CmdResult r = run_mmpm({"run", "--restart", out.string(), "--quiet"});
  EXPECT_EQ(r.exit_code, 2) << r.describe();
  ASSERT_EQ(lines_of(r.err).size(), 1u) << r.describe();
  EXPECT_TRUE(contains(r.err, (out / "checkpoint.bin").string())) << r.err;
}

// A scene nested 20 000 levels deep overflowed toml11's recursive parser
// (SIGSEGV); nesting is now refused past 64 levels, in the file and in --set.
TEST(Cli, DeepNestingIsBadInputNotACrash) {
  TempDir tmp;
  const std::string deep = std::string(20000, '[') + std::string(20000, ']');
  const fs::path scene = tmp / "deep.toml";
  const std::string text = edited_bar("cells ", "cells  = " + deep);
  write_text(scene, text);
  const CmdResult r = run_mmpm({"check", scene.string()});
  EXPECT_EQ(r.exit_code, 2) << r.describe();
  ASSERT_EQ(lines_of(r.err).size(), 1u) << r.describe();
  EXPECT_TRUE(
      contains(r.err, scene.string() + ":" + std::to_string(line_of(text, "cells  = [[")) + ":"))
      << r.err;
  const CmdResult s = run_mmpm({"check", bar_scene(), "--set", "grid.cells=" + deep});
  EXPECT_EQ(s.exit_code, 2) << s.describe();
  EXPECT_TRUE(contains(s.err, "'grid.cells'")) << s.err;
  // Brackets inside strings and comments do not count.
  const fs::path quoted = tmp / "quoted.toml";
  write_text(quoted, edited_bar("name     = \"bar\"", "name     = \"" + std::string(100, '[') +
                                                          "\"  # " + std::string(100, '{')));
  const CmdResult q = run_mmpm({"check", quoted.string()});
  EXPECT_EQ(q.exit_code, 0) << q.describe();
}

// Two boundaries on one face (x fixed by one, y by the other) each report
// their reaction: the second one's columns get "_2" (the run used to stop
// with exit 3, "column 'reaction_x_min_x' given twice", after `check` had
// passed it).
TEST(Cli, TwoBoundariesOnOneFaceGetTheirOwnReactionColumns) {
  TempDir tmp;
  const fs::path scene = tmp / "two.toml";
  write_text(scene, edited_bar("fix ",
                               "fix   = [\"x\"]\n\n[[boundary]]\nwhere = { x = 0.0 }\n"
                               "fix   = [\"y\"]"));
  const fs::path out = tmp / "o";
  const CmdResult r = run_mmpm({"run", scene.string(), "--out", out.string(), "--quiet", "--set",
                                "simulation.end_time=0.05"});
  ASSERT_EQ(r.exit_code, 0) << r.describe();
  using namespace mmpm::io;
  const h5::File f = h5::File::open(out / "run.h5", h5::File::Mode::read_only);
  const h5::Group series = f.root().open_group("series");
  for (const char* c : {"reaction_plane_x_0_x", "reaction_plane_x_0_y", "reaction_plane_x_0_2_x",
                        "reaction_plane_x_0_2_y"})
    EXPECT_TRUE(series.contains(c)) << c;
}

// One bad-input case: the edited scene, the key the message must name and
// the text on the offending line (to find its number).
struct BadInput {
  const char* name;
  const char* line_start;   // line of bar_vibration.toml to replace
  const char* replacement;  // new line(s); the first line is the one blamed
  const char* key;          // dotted key path expected in the message
  const char* needle;       // text of the blamed line
};

const BadInput kBadInputs[] = {
    {"unknown_key", "nu ", "nu      = 0.0\ncolour  = \"red\"", "material[0].colour", "colour"},
    {"wrong_type", "E ", "E       = \"stiff\"", "material[0].E", "\"stiff\""},
    {"nu_half", "nu ", "nu      = 0.5", "material[0].nu", "nu      = 0.5"},
    {"body_outside_grid", "max ", "max      = [40.0, 1.0]", "body[0].max", "[40.0, 1.0]"},
    {"zero_cell", "cell ", "cell   = [0.0, 0.5]", "grid.cell", "[0.0, 0.5]"},
    {"missing_material", "material = ", "material = \"unobtainium\"", "body[0].material",
     "unobtainium"},
    // Found by a sanitizer run (2026-11-29): a tile edge of 65536 shifted a
    // 32-bit key by 32 (a crash or a hang); E = 1e-308 and thickness 1e308
    // passed `check` and stopped the run at step 0 with NaN in the message;
    // a NUL in a name cut the output directory's name short.
    {"tile_too_large", "shape  = ", "shape  = \"gimp\"\ntile   = 65536", "grid.tile", "65536"},
    {"E_subnormal", "E ", "E       = 1e-308", "material[0].E", "1e-308"},
    {"thickness_huge", "thickness ", "thickness = 1e308", "simulation.thickness", "1e308"},
    {"control_character", "name     = ", "name     = \"b\\u0000ar\"", "body[0].name", "u0000"},
    // Found by the same run: rotate = 1e308 lost the angle in the conversion
    // to radians and was blamed on 'grid' with no line; a cell count past 64
    // bits was reported as 9223372036854775807, as if the file said so.
    {"rotate_huge", "material = ", "material = \"steel\"\nrotate   = 1e308", "body[0].rotate",
     "rotate   = 1e308"},
    {"cells_beyond_64_bits", "cells  = ", "cells  = [99999999999999999999, 6]", "grid.cells",
     "99999999999999999999"},
    // Found by a fuzzing session (2026-11-29): a number key read such an
    // integer as 9.2e18 and ran with it.
    {"number_beyond_64_bits", "E ", "E       = 99999999999999999999", "material[0].E",
     "99999999999999999999"},
};

class CliBadInput : public ::testing::TestWithParam<BadInput> {};

TEST_P(CliBadInput, Exit2WithOneMessageNamingFileLineKey) {
  const BadInput& c = GetParam();
  TempDir tmp(c.name);
  const fs::path scene = tmp / (std::string(c.name) + ".toml");
  const std::string text = edited_bar(c.line_start, c.replacement);
  write_text(scene, text);
  const int line = line_of(text, c.needle);
  ASSERT_GT(line, 0);
  const std::string where = scene.string() + ":" + std::to_string(line) + ":";
  const std::string key = "'" + std::string(c.key) + "'";

  for (const char* sub : {"check", "run"}) {
    const fs::path out = tmp / (std::string("out_") + sub);
    std::vector<std::string> args{sub, scene.string()};
    if (std::string(sub) == "run") args.insert(args.end(), {"--out", out.string(), "--quiet"});
    const CmdResult r = run_mmpm(args);
    EXPECT_EQ(r.exit_code, 2) << sub << "\n" << r.describe();
    const auto lines = lines_of(r.err);
    ASSERT_EQ(lines.size(), 1u) << sub << ": exactly one message\n" << r.describe();
    EXPECT_TRUE(contains(lines[0], where)) << sub << ": names file and line " << where << "\n"
                                           << lines[0];
    EXPECT_TRUE(contains(lines[0], key)) << sub << ": names the key " << key << "\n" << lines[0];
    EXPECT_TRUE(r.out.empty()) << sub << ": nothing on stdout for bad input\n" << r.out;
    expect_no_result(out);
  }
}

INSTANTIATE_TEST_SUITE_P(Cli, CliBadInput, ::testing::ValuesIn(kBadInputs),
                         [](const ::testing::TestParamInfo<BadInput>& i) {
                           return std::string(i.param.name);
                         });

TEST(Cli, BadSetValueIsBlamedOnTheSetOption) {
  TempDir tmp;
  const CmdResult r =
      run_mmpm({"run", bar_scene(), "--set", "material[0].nu=0.5", "--out", (tmp / "o").string()});
  EXPECT_EQ(r.exit_code, 2) << r.describe();
  const auto lines = lines_of(r.err);
  ASSERT_EQ(lines.size(), 1u) << r.describe();
  EXPECT_TRUE(contains(lines[0], "--set material[0].nu")) << lines[0];
  expect_no_result(tmp / "o");
}

TEST(Cli, TimeStepAboveStabilityLimit) {
  TempDir tmp;
  const std::string scene = bar_scene();
  // run refuses it: exit 2, one message naming the file and the key, no output.
  {
    const CmdResult r =
        run_mmpm({"run", scene, "--set", "simulation.cfl=1.5", "--out", (tmp / "a").string()});
    EXPECT_EQ(r.exit_code, 2) << r.describe();
    const auto lines = lines_of(r.err);
    ASSERT_EQ(lines.size(), 1u) << r.describe();
    EXPECT_TRUE(contains(lines[0], "simulation.cfl")) << lines[0];
    EXPECT_TRUE(contains(lower(lines[0]), "stability")) << lines[0];
    expect_no_result(tmp / "a");
  }
  // An explicit dt above the limit is refused the same way, naming simulation.dt.
  {
    const CmdResult r =
        run_mmpm({"run", scene, "--set", "simulation.dt=1.0e-3", "--out", (tmp / "b").string()});
    EXPECT_EQ(r.exit_code, 2) << r.describe();
    EXPECT_TRUE(contains(r.err, "simulation.dt")) << r.err;
    expect_no_result(tmp / "b");
  }
  // --force runs it (3 steps: short enough that the instability stays small).
  {
    const CmdResult r = run_mmpm({"run", scene, "--set", "simulation.cfl=1.5", "--set",
                                  "simulation.end_time=0.0003", "--force", "--quiet", "--out",
                                  (tmp / "c").string()});
    EXPECT_EQ(r.exit_code, 0) << r.describe();
    EXPECT_TRUE(fs::exists(tmp / "c" / "summary.json"));
  }
  // check refuses it as run does (exit 2, one line, nothing printed); with
  // --force it prints the scene and warns on stderr.
  {
    const CmdResult r = run_mmpm({"check", scene, "--set", "simulation.cfl=1.5"});
    EXPECT_EQ(r.exit_code, 2) << r.describe();
    const auto lines = lines_of(r.err);
    ASSERT_EQ(lines.size(), 1u) << r.describe();
    EXPECT_TRUE(contains(lines[0], "simulation.cfl")) << lines[0];
    EXPECT_TRUE(contains(lower(lines[0]), "stability")) << lines[0];
    EXPECT_TRUE(r.out.empty()) << r.out;
  }
  {
    const CmdResult r = run_mmpm({"check", scene, "--set", "simulation.cfl=1.5", "--force"});
    EXPECT_EQ(r.exit_code, 0) << r.describe();
    EXPECT_TRUE(contains(lower(r.err), "warning")) << r.describe();
    EXPECT_TRUE(contains(r.err, "simulation.cfl")) << r.describe();
    EXPECT_TRUE(contains(r.out, "[simulation]")) << r.out;
  }
}

TEST(Cli, UnstableRunNamesStageStepParticleAndLeavesNoResult) {
  TempDir tmp;
  const fs::path out = tmp / "out";
  // A complete result from an earlier run in the same directory must not survive
  // a failed run there either: it would look like this run's result.
  const CmdResult ok = run_mmpm(
      {"run", bar_scene(), "--set", "simulation.end_time=0.002", "--quiet", "--out", out.string()});
  ASSERT_EQ(ok.exit_code, 0) << ok.describe();
  ASSERT_TRUE(fs::exists(out / "run.h5"));
  // 2000 mm/ms to the right: the bar reaches the grid edge after ~16 steps.
  const CmdResult r = run_mmpm({"run", bar_scene(), "--set", "body[0].velocity=[2000.0, 0.0]",
                                "--quiet", "--out", out.string()});
  EXPECT_NE(r.exit_code, 0) << r.describe();
  EXPECT_NE(r.exit_code, 2) << "not an input error: the scene is valid\n" << r.describe();
  const auto lines = lines_of(r.err);
  ASSERT_EQ(lines.size(), 1u) << r.describe();
  EXPECT_TRUE(
      std::regex_search(lines[0], std::regex(R"(stage [a-z0-9_]+, step [0-9]+, particle [0-9]+)")))
      << lines[0];
  expect_no_result(out);
  EXPECT_FALSE(fs::exists(out / "run.h5.partial"));
}

double number(const json& j, const char* key) {
  return j.at(key).get<double>();
}

TEST(Cli, RunWritesResultsAndSummaryContract) {
  TempDir tmp;
  const fs::path out = tmp / "bar";
  const CmdResult r = run_mmpm({"run", bar_scene(), "--set", "simulation.end_time=0.05",
                                "--threads", "2", "--out", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.describe();
  for (const char* f : {"run.h5", "run.xdmf", "summary.json"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  EXPECT_FALSE(fs::exists(out / "run.h5.partial"));
  EXPECT_FALSE(fs::exists(out / "checkpoint.bin"));
  EXPECT_TRUE(contains(read_text(out / "run.xdmf"), "run.h5"));

  const json j = json::parse(read_text(out / "summary.json"));
  std::set<std::string> keys;
  for (const auto& [k, v] : j.items()) keys.insert(k);
  const std::set<std::string> expected{"scene",
                                       "dimension",
                                       "precision",
                                       "particles",
                                       "nodes",
                                       "materials",
                                       "steps",
                                       "end_time",
                                       "dt",
                                       "threads",
                                       "wall_s",
                                       "ns_per_particle_step",
                                       "stages_s",
                                       "energy",
                                       "multimaterial_nodes",
                                       "nodes_3plus",
                                       "force_limited_nodes",
                                       "stopped_by"};
  EXPECT_EQ(keys, expected);
  std::set<std::string> stage_keys, energy_keys;
  for (const auto& [k, v] : j.at("stages_s").items()) stage_keys.insert(k);
  for (const auto& [k, v] : j.at("energy").items()) energy_keys.insert(k);
  EXPECT_EQ(stage_keys, (std::set<std::string>{"sort", "p2g", "multimaterial", "grid", "g2p",
                                               "constitutive", "output", "other"}));
  EXPECT_EQ(energy_keys,
            (std::set<std::string>{"kinetic", "strain", "interface", "external_work", "damping"}));

  EXPECT_EQ(j.at("scene"), "bar_vibration");
  EXPECT_EQ(j.at("dimension"), 2);
  EXPECT_EQ(j.at("precision"), "double");
  EXPECT_EQ(j.at("particles"), 400);  // 25 x 1 mm at 0.5 mm cells, 2 per cell and direction
  EXPECT_EQ(j.at("nodes"), 55 * 7);
  EXPECT_EQ(j.at("materials"), 1);
  EXPECT_EQ(j.at("threads"), 2);
  EXPECT_EQ(j.at("stopped_by"), "end_time");
  EXPECT_EQ(j.at("multimaterial_nodes"), 0);

  // --set reached the run: it stopped at 0.05 ms, not the file's 2.0 ms.
  const double dt = number(j, "dt"), end = number(j, "end_time");
  const long steps = j.at("steps").get<long>();
  EXPECT_GT(dt, 0.0);
  EXPECT_EQ(steps, long(std::ceil(0.05 / dt - 1e-9)));
  EXPECT_EQ(end, 0.05) << "the last step is shortened to land on end_time";

  const double wall = number(j, "wall_s");
  double sum = 0;
  for (const auto& [k, v] : j.at("stages_s").items()) {
    sum += v.get<double>();
    EXPECT_GE(v.get<double>(), 0.0) << k;
  }
  EXPECT_GT(wall, 0.0);
  EXPECT_NEAR(sum, wall, 1e-9 * wall) << "stages + other = wall_s";
  EXPECT_NEAR(number(j, "ns_per_particle_step"), wall * 1e9 / (400.0 * double(steps)),
              1e-9 * number(j, "ns_per_particle_step"));
  EXPECT_GT(number(j.at("energy"), "kinetic"), 0.0);
  EXPECT_GT(number(j.at("energy"), "strain"), 0.0);

  // run.h5 agrees: the series ends at the summary's step and time; the scene
  // stored with the results carries the override.
  using namespace mmpm::io;
  const h5::File f = h5::File::open(out / "run.h5", h5::File::Mode::read_only);
  const h5::Group root = f.root();
  const auto series = root.open_group("series");
  const auto time = series.open_dataset("time").read_doubles();
  const auto step = series.open_dataset("step").read_doubles();
  ASSERT_FALSE(time.empty());
  EXPECT_EQ(time.back(), end);
  EXPECT_EQ(step.back(), double(steps));
  EXPECT_TRUE(contains(root.string_attribute("scene"), "end_time = 0.05"))
      << root.string_attribute("scene");
  EXPECT_GE(root.open_group("particles").children().size(), 2u) << "initial and final snapshots";
}

// A modulus so large that the time step is 0 (E = 1e308: the wave speed
// overflows) or needs ~1e124 steps (E = 1e250): bad input at the key that
// sets the step. dt = 0 used to run forever, and `check` printed
// "steps: -9223372036854775808".
TEST(Cli, AbsurdModulusIsBadInputNotAHang) {
  TempDir tmp;
  // 1e308 and 1e250 are refused where E is read since 2026-11-29 (material
  // constants within 1e-30 .. 1e30); 1e30 passes that and meets the step
  // count's check.
  for (const char* modulus : {"1.0e308", "1.0e250", "1.0e30"}) {
    const bool in_range = std::string(modulus) == "1.0e30";
    const fs::path scene = tmp / "stiff.toml";
    write_text(scene, edited_bar("E ", std::string("E       = ") + modulus));
    for (const char* sub : {"check", "run"}) {
      const fs::path out = tmp / "out";
      std::vector<std::string> args{sub, scene.string()};
      if (std::string(sub) == "run") args.insert(args.end(), {"--out", out.string(), "--quiet"});
      const CmdResult r = run_mmpm(args);
      EXPECT_EQ(r.exit_code, 2) << modulus << " " << sub << "\n" << r.describe();
      const auto lines = lines_of(r.err);
      ASSERT_EQ(lines.size(), 1u) << r.describe();
      if (in_range) {
        EXPECT_TRUE(contains(lines[0], "'simulation.cfl'")) << lines[0];
        EXPECT_TRUE(contains(lines[0], "steel")) << "names the fastest material\n" << lines[0];
      } else {
        EXPECT_TRUE(contains(lines[0], "'material[0].E'")) << lines[0];
      }
      expect_no_result(out);
    }
  }
}

// What makes dt absurd is named: a body's velocity (dt = cfl h / (c + |v|))
// names the body, not a material; grid damping (dt < 2 / damping) names
// damping (1e308 was reported as "the wave speed of material 'steel'").
// The resolved scene is printed only for good input.
TEST(Cli, AbsurdStepIsBlamedOnWhatSetsIt) {
  struct Case {
    const char *set, *named, *not_named;
  };
  for (const Case c :
       {Case{"body[0].velocity=[1e30, 0.0]", "the velocity of body 'bar'", "modulus"},
        Case{"grid.damping=1e308", "the step follows grid.damping", "wave speed"}}) {
    const CmdResult r = run_mmpm({"check", bar_scene(), "--set", c.set});
    EXPECT_EQ(r.exit_code, 2) << r.describe();
    const auto lines = lines_of(r.err);
    ASSERT_EQ(lines.size(), 1u) << r.describe();
    EXPECT_TRUE(contains(lines[0], c.named)) << lines[0];
    EXPECT_FALSE(contains(lines[0], c.not_named)) << lines[0];
    EXPECT_TRUE(r.out.empty()) << r.out;
  }
}

// Grid damping is explicit, p <- p (1 - alpha dt) + dt f: unstable once
// alpha dt > 2. The time step respects 2 / alpha as well as the wave speed
// (the steel bar, h / c = 9.9e-5 ms, with alpha = 1e5 / ms: 2 / alpha =
// 2e-5 ms, so dt from the wave speed alone was 4.9x too large).
TEST(Cli, GridDampingLimitsTheTimeStep) {
  TempDir tmp;
  const std::string scene = bar_scene();
  const CmdResult c = run_mmpm({"check", scene, "--set", "grid.damping=1.0e5"});
  ASSERT_EQ(c.exit_code, 0) << c.describe();
  std::smatch m;
  ASSERT_TRUE(std::regex_search(c.out, m, std::regex(R"(# dt: ([0-9.eE+-]+))"))) << c.out;
  const double dt = std::stod(m[1].str());
  EXPECT_NEAR(dt, 0.4 * 2.0 / 1.0e5, 1e-15) << "cfl 0.4 times 2 / alpha";
  const fs::path out = tmp / "damped";
  const CmdResult r = run_mmpm({"run", scene, "--set", "grid.damping=1.0e5", "--set",
                                "simulation.end_time=0.002", "--quiet", "--out", out.string()});
  EXPECT_EQ(r.exit_code, 0) << r.describe();
  // An explicit dt above 2 / alpha is refused like any step above the limit.
  const CmdResult f = run_mmpm({"run", scene, "--set", "grid.damping=1.0e5", "--set",
                                "simulation.dt=5.0e-5", "--quiet", "--out", (tmp / "f").string()});
  EXPECT_EQ(f.exit_code, 2) << f.describe();
  EXPECT_TRUE(contains(f.err, "grid.damping")) << f.err;
}

// The last step is shortened so that the run ends at end_time, not up to
// a step past it (a sweep over values then compares runs at equal times).
TEST(Cli, RunEndsExactlyAtEndTime) {
  TempDir tmp;
  const fs::path out = tmp / "bar";
  const double end = 0.0123;  // not a multiple of the bar's dt
  const CmdResult r = run_mmpm({"run", bar_scene(), "--set", "simulation.end_time=0.0123",
                                "--quiet", "--out", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.describe();
  const json j = json::parse(read_text(out / "summary.json"));
  const double dt = j.at("dt").get<double>();
  EXPECT_EQ(j.at("end_time").get<double>(), end);
  EXPECT_EQ(j.at("steps").get<long>(), long(std::ceil(end / dt)));
  EXPECT_GT(std::ceil(end / dt) - end / dt, 0.01) << "the scene must need a shortened last step";
  using namespace mmpm::io;
  const h5::File f = h5::File::open(out / "run.h5", h5::File::Mode::read_only);
  const auto time = f.root().open_group("series").open_dataset("time").read_doubles();
  ASSERT_FALSE(time.empty());
  EXPECT_EQ(time.back(), end);
}

// A snapshot interval far below dt writes one snapshot per step and ends:
// the driver used to step its snapshot counter one `every` at a time,
// (t + dt / 2) / every increments per snapshot (with every = 1e-9 ms and
// the bar's dt ~4e-5 ms, ~4e4 per step growing to ~1e6; collision.toml
// with every = 1e-12 did not end in a minute). An interval below
// end_time * 1e-12 is bad input (the counter is a long).
TEST(Cli, SnapshotIntervalBelowTheStepWritesEveryStep) {
  TempDir tmp;
  const fs::path out = tmp / "bar";
  const CmdResult r = run_mmpm({"run", bar_scene(), "--set", "simulation.end_time=0.002", "--set",
                                "output.every=1e-9", "--set", "output.fields=[\"velocity\"]",
                                "--quiet", "--out", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.describe();
  const json j = json::parse(read_text(out / "summary.json"));
  const long steps = j.at("steps").get<long>();
  ASSERT_GT(steps, 10);
  using namespace mmpm::io;
  const h5::File f = h5::File::open(out / "run.h5", h5::File::Mode::read_only);
  EXPECT_EQ(long(f.root().open_group("particles").children().size()), steps + 1)
      << "the initial state and one snapshot per step";

  const CmdResult bad = run_mmpm({"check", bar_scene(), "--set", "output.every=1e-20"});
  EXPECT_EQ(bad.exit_code, 2) << bad.describe();
  const auto lines = lines_of(bad.err);
  ASSERT_EQ(lines.size(), 1u) << bad.describe();
  EXPECT_TRUE(contains(lines[0], "output.every")) << lines[0];
  EXPECT_TRUE(contains(lines[0], "end_time * 1e-12")) << lines[0];
}

// Sizes no run could allocate are refused before anything is allocated,
// naming the key: a 10^8 x 10^8 grid (was std::bad_alloc, exit 3) and 10^5
// particles per cell and direction (10^10 per cell: `check` did not end).
TEST(Cli, SizesBeyondTheMachineAreBadInput) {
  TempDir tmp;
  struct Case {
    const char* set;
    const char* key;
  };
  for (const Case c : {Case{"grid.cells=[100000000, 100000000]", "'grid.cells'"},
                       Case{"body[0].particles_per_cell=100000", "particles_per_cell"}}) {
    const CmdResult r = run_mmpm({"check", bar_scene(), "--set", c.set});
    EXPECT_EQ(r.exit_code, 2) << c.set << "\n" << r.describe();
    const auto lines = lines_of(r.err);
    ASSERT_EQ(lines.size(), 1u) << r.describe();
    EXPECT_TRUE(contains(lines[0], c.key)) << lines[0];
    EXPECT_TRUE(contains(lines[0], "memory")) << lines[0];
  }
  // Particles that need ~300 B each in 2D double (`check` measured 310) at
  // 150 B of this machine's memory each: the guard's old count of 96 B let
  // such a scene pass, and the kernel killed it (SIGKILL at 24 GB). The bar
  // holds 100 cells, so ppc^2 * 100 particles.
  const double memory = double(sysconf(_SC_PHYS_PAGES)) * double(sysconf(_SC_PAGESIZE));
  const int ppc = int(std::sqrt(memory / 150.0 / 100.0));
  const CmdResult r = run_mmpm(
      {"check", bar_scene(), "--set", "body[0].particles_per_cell=" + std::to_string(ppc)});
  EXPECT_EQ(r.exit_code, 2) << ppc << "\n" << r.describe();
  EXPECT_TRUE(contains(r.err, "memory")) << r.err;
}

TEST(Cli, DeformationGradientOutputNeedsAFiniteStrainMaterial) {
  TempDir tmp;
  const fs::path scene = tmp / "f.toml";
  const std::string text = edited_bar("fields ", "fields = [\"deformation_gradient\"]");
  write_text(scene, text);
  const std::string where =
      scene.string() + ":" + std::to_string(line_of(text, "fields = [")) + ":";
  for (const char* sub : {"check", "run"}) {
    std::vector<std::string> args{sub, scene.string()};
    if (std::string(sub) == "run") args.insert(args.end(), {"--out", (tmp / "o").string()});
    const CmdResult r = run_mmpm(args);
    EXPECT_EQ(r.exit_code, 2) << sub << "\n" << r.describe();
    EXPECT_TRUE(contains(r.err, where)) << r.err;
    EXPECT_TRUE(contains(r.err, "'output.fields'")) << r.err;
    EXPECT_TRUE(contains(r.err, "neohookean")) << r.err;
  }
}

TEST(Cli, CommandLineMistakesGetOneClearMessage) {
  TempDir tmp;
  const CmdResult dir = run_mmpm({"run", tmp.path().string(), "--out", (tmp / "o").string()});
  EXPECT_EQ(dir.exit_code, 2) << dir.describe();
  EXPECT_TRUE(contains(dir.err, "is a directory")) << dir.err;
  const CmdResult unknown = run_mmpm({"frobnicate"});
  EXPECT_EQ(unknown.exit_code, 2);
  EXPECT_TRUE(contains(unknown.err, "unknown command 'frobnicate'")) << unknown.err;
  const CmdResult threads = run_mmpm({"run", bar_scene(), "--threads", "0"});
  EXPECT_EQ(threads.exit_code, 2);
  EXPECT_LT(threads.err.size(), 200u) << threads.err;
  const CmdResult none = run_mmpm({"sweep", bar_scene(), "--param", "simulation.cfl", "--values",
                                   "", "--out", (tmp / "s").string()});
  EXPECT_EQ(none.exit_code, 2) << none.describe();
  EXPECT_FALSE(fs::exists(tmp / "s" / "sweep.csv"));
}

// An output directory that cannot be made or written is bad input, said
// before the first step: a path under a regular file, and /proc, which
// refuses even root (it used to end with a filesystem_error, exit 3).
TEST(Cli, UnwritableOutputDirectoryIsBadInput) {
  TempDir tmp;
  write_text(tmp / "plain_file", "x");
  const std::vector<std::string> dirs{(tmp / "plain_file" / "o").string(),
                                      (tmp / "plain_file").string(), "/proc/mmpm_out"};
  for (const std::string& out : dirs) {
    for (const char* sub : {"run", "sweep"}) {
      std::vector<std::string> args{sub, bar_scene(), "--out", out, "--quiet"};
      if (std::string(sub) == "sweep")
        args.insert(args.end(), {"--param", "simulation.end_time", "--values", "0.001"});
      const CmdResult r = run_mmpm(args);
      EXPECT_EQ(r.exit_code, 2) << sub << " " << out << "\n" << r.describe();
      const auto lines = lines_of(r.err);
      ASSERT_EQ(lines.size(), 1u) << r.describe();
      EXPECT_TRUE(contains(lines[0], "--out " + out + ": cannot write the output directory"))
          << lines[0];
    }
  }
}

// The one warning `check` printed, about interaction[0].KEY of `scene`,
// with the interaction's file:line in front; empty (after a failure) if
// there is not exactly one.
std::string one_interaction_warning(const CmdResult& r, const std::string& scene,
                                    const std::string& key = "separation") {
  EXPECT_EQ(r.exit_code, 0) << r.describe();
  const auto lines = lines_of(r.err);
  EXPECT_EQ(lines.size(), 1u) << r.describe();
  if (lines.size() != 1) return {};
  const std::string where =
      scene + ":" + std::to_string(line_of(read_text(scene), "[[interaction]]")) + ":";
  EXPECT_TRUE(contains(lines[0], where + " warning: key 'interaction[0]." + key + "'")) << lines[0];
  return lines[0];
}

// The position method registers contact below contact_offset h⊥; two flush
// faces put their particles' centroids at a node c_a + c_b apart
// (app/start_warnings.cpp): 0.75 h for uGIMP at 2 ppc, 0.844 h for bspline2
// at 2 ppc, 0.875 h for uGIMP with one body at 1 ppc. Above the offset
// `check` warns and names the value to raise it to; inputs/platen.toml
// (uGIMP, 2 ppc) does not warn with the position method, nor bspline2 with
// contact_offset = 0.9 (docs/contact_validation.md §11).
TEST(Cli, PositionContactOffsetBelowTheTouchingGapWarns) {
  const std::string platen = source_dir() + "/inputs/platen.toml";
  const std::string position = "interaction[0].separation=\"position\"";
  const std::string spline = one_interaction_warning(
      run_mmpm({"check", platen, "--set", position, "--set", "grid.shape=\"bspline2\""}), platen,
      "contact_offset");
  EXPECT_TRUE(contains(spline, "centroids 0.844 h apart")) << spline;
  EXPECT_TRUE(contains(spline, "raise contact_offset to 0.894")) << spline;
  const std::string one_per_cell = one_interaction_warning(
      run_mmpm({"check", platen, "--set", position, "--set", "body[0].particles_per_cell=1"}),
      platen, "contact_offset");
  EXPECT_TRUE(contains(one_per_cell, "centroids 0.875 h apart")) << one_per_cell;
  for (const std::vector<std::string>& quiet :
       {std::vector<std::string>{"check", platen, "--set", position},
        std::vector<std::string>{"check", platen, "--set", position, "--set",
                                 "grid.shape=\"bspline2\"", "--set",
                                 "interaction[0].contact_offset=0.9"}}) {
    const CmdResult r = run_mmpm(quiet);
    EXPECT_EQ(r.exit_code, 0) << r.describe();
    EXPECT_FALSE(contains(r.err, "warning")) << r.describe();
  }
}

// Contact with separation = "displacement" assumes bodies that touch at the
// start (ALGORITHM §3); `check` and `run` warn when a contact pair starts
// apart (solver/contact_gap.hpp). collision.toml's blocks (h = 0.5 mm,
// 2 x 2 ppc: spacing 0.25, "touching" up to 1.5 spacings = 0.375 mm),
// switched to the displacement method: 0.5 mm apart (the second block
// from x = 12.25: nearest particles 11.875 and 12.375) warns and names the
// interaction's line; from x = 12.0 (nearest 0.25 mm) it does not; the
// shipped scenes (position method, or bodies that touch) do not.
TEST(Cli, ContactPairsThatStartApartWarnWithDisplacementSeparation) {
  const std::string collision = source_dir() + "/inputs/collision.toml";
  const std::string disp = "interaction[0].separation=\"displacement\"";
  const std::string apart = one_interaction_warning(
      run_mmpm({"check", collision, "--set", disp, "--set", "body[1].min=[12.25, 2.0]"}),
      collision);
  EXPECT_TRUE(contains(apart, "nearest particles are 0.5 apart")) << apart;
  EXPECT_TRUE(contains(apart, "at most 0.375")) << apart;

  const CmdResult touching =
      run_mmpm({"check", collision, "--set", disp, "--set", "body[1].min=[12.0, 2.0]"});
  EXPECT_EQ(touching.exit_code, 0) << touching.describe();
  EXPECT_EQ(touching.err, "") << touching.describe();
  for (const char* scene : {"collision.toml", "incline_block.toml", "incline_disk.toml",
                            "sphere_in_cube.toml", "two_layer.toml"}) {
    const CmdResult r = run_mmpm({"check", source_dir() + "/inputs/" + scene});
    EXPECT_EQ(r.err, "") << scene << "\n" << r.describe();
  }
}

// separation = "extrapolated" needs 2 or more particles per cell per
// direction (kernels/separation_extrapolation.hpp): `check` warns once per
// body of the pair's materials seeded 1 per cell, naming the interaction's
// line; two_layer.toml's own 2 per cell do not warn.
TEST(Cli, ExtrapolatedSeparationWithOneParticlePerCellWarns) {
  const std::string scene = source_dir() + "/inputs/two_layer.toml";
  const std::string extrapolated = "interaction[0].separation=\"extrapolated\"";
  const std::string one = one_interaction_warning(
      run_mmpm({"check", scene, "--set", extrapolated, "--set", "body[1].particles_per_cell=1"}),
      scene);
  EXPECT_TRUE(contains(one, "has 1")) << one;
  const CmdResult two = run_mmpm({"check", scene, "--set", extrapolated});
  EXPECT_EQ(two.exit_code, 0) << two.describe();
  EXPECT_EQ(two.err, "") << two.describe();
}

// docs/multimaterial.md §7.2, app/start_warnings.cpp. With B-splines, (P-20)
// named in the scene warns (it counts each row of interface nodes in full);
// the default gradient area warns for a body thinner than the shape's two
// reaches with the partner on both faces: the DLS's 2-cell central lap at
// h = 0.5 mm (not its outer laps, free on one face), and nothing at h = 0.25.
TEST(Cli, BSplineInterfaceAreaWarnings) {
  const std::string bars = source_dir() + "/inputs/series_bars.toml";
  const std::string paper =
      one_interaction_warning(run_mmpm({"check", bars, "--set", "grid.shape=\"bspline3\"", "--set",
                                        "interaction[0].area=\"paper\""}),
                              bars, "area");
  EXPECT_TRUE(contains(paper, "0.65 of the exact")) << paper;
  const CmdResult bars_default = run_mmpm({"check", bars, "--set", "grid.shape=\"bspline3\""});
  EXPECT_EQ(bars_default.exit_code, 0) << bars_default.describe();
  EXPECT_EQ(bars_default.err, "") << bars_default.describe();

  const std::string dls = source_dir() + "/inputs/dls.toml";
  const std::string thin = one_interaction_warning(
      run_mmpm({"check", dls, "--set", "grid.shape=\"bspline2\""}), dls, "area");
  EXPECT_TRUE(contains(thin, "body 'central' is 2 cells thick along x")) << thin;
  const CmdResult fine = run_mmpm({"check", dls, "--set", "grid.shape=\"bspline2\"", "--set",
                                   "grid.cell=[0.25,0.25]", "--set", "grid.cells=[20,148]"});
  EXPECT_EQ(fine.exit_code, 0) << fine.describe();
  EXPECT_EQ(fine.err, "") << fine.describe();
}

// docs/validation.md §3.11 (open): USF with linear shapes warns, naming the
// scheme key; USF with uGIMP and MUSL with linear shapes do not.
TEST(Cli, UsfWithLinearShapesWarns) {
  const std::string scene = source_dir() + "/inputs/bar_vibration.toml";
  const CmdResult usf = run_mmpm(
      {"check", scene, "--set", "grid.shape=\"linear\"", "--set", "simulation.scheme=\"USF\""});
  EXPECT_EQ(usf.exit_code, 0) << usf.describe();
  EXPECT_TRUE(contains(usf.err, "warning: key 'simulation.scheme': \"USF\" with shape \"linear\""))
      << usf.describe();
  for (const std::vector<std::string>& sets :
       {std::vector<std::string>{"grid.shape=\"gimp\"", "simulation.scheme=\"USF\""},
        std::vector<std::string>{"grid.shape=\"linear\"", "simulation.scheme=\"MUSL\""}}) {
    const CmdResult quiet = run_mmpm({"check", scene, "--set", sets[0], "--set", sets[1]});
    EXPECT_EQ(quiet.exit_code, 0) << quiet.describe();
    EXPECT_FALSE(contains(quiet.err, "simulation.scheme")) << quiet.describe();
  }
}

// An interface between bodies that start bonded, with separation =
// "position": the centroids' offset loads it from the first step (two_layer
// with Dn = 1000 made 5.2 mJ from 0.0019 mJ of work in 0.01 ms), so `check`
// warns, naming the interaction's line; the default (displacement) does not,
// nor position on bodies that start apart (collision.toml's own scene).
TEST(Cli, PositionSeparationOnABondedInterfaceWarns) {
  const std::string scene = source_dir() + "/inputs/two_layer.toml";
  const std::string bonded = one_interaction_warning(
      run_mmpm({"check", scene, "--set", "interaction[0].separation=\"position\"", "--set",
                "interaction[0].Dn=1000.0"}),
      scene);
  EXPECT_TRUE(contains(bonded, "start bonded")) << bonded;
  const CmdResult apart =
      run_mmpm({"check", source_dir() + "/inputs/collision.toml", "--set",
                "interaction[0].law=\"interface\"", "--set", "interaction[0].Dn=1000.0", "--set",
                "interaction[0].Dt=1000.0"});
  EXPECT_EQ(apart.exit_code, 0) << apart.describe();
  EXPECT_EQ(apart.err, "") << apart.describe();
}

// An interface with a perfect direction and a computed normal (mvg, the
// default, or avg) and no edge screening: where the interface meets a free
// edge the normal tilts and the perfect direction locks it (paper 2.5;
// series_bars with mvg: 1.2 % of the exact interface energy), so `check`
// warns, naming the interaction's line. The shipped scene (specified
// normal), screening (min_volume > 0) and finite stiffnesses do not.
// (The scene's normal_vector is set back to its default with the computed
// normals: otherwise it warns too, as a key the normal never reads.)
TEST(Cli, ComputedNormalOnAPerfectInterfaceWarns) {
  const std::string scene = source_dir() + "/inputs/series_bars.toml";
  const std::string unset = "interaction[0].normal_vector=[1.0, 0.0]";
  const std::string mvg = one_interaction_warning(
      run_mmpm({"check", scene, "--set", "interaction[0].normal=\"mvg\"", "--set", unset}), scene,
      "normal");
  EXPECT_TRUE(contains(mvg, "normal = \"mvg\" (mvg is the default) with Dt = \"perfect\"")) << mvg;
  EXPECT_TRUE(contains(mvg, "min_volume")) << mvg;
  const std::string avg = one_interaction_warning(
      run_mmpm({"check", scene, "--set", "interaction[0].normal=\"avg\"", "--set", unset}), scene,
      "normal");
  EXPECT_TRUE(contains(avg, "normal = \"avg\" with Dt")) << avg;
  for (const std::vector<std::string>& quiet : {std::vector<std::string>{},
                                                {"--set", "interaction[0].normal=\"mvg\"", "--set",
                                                 unset, "--set", "interaction[0].min_volume=0.75"},
                                                {"--set", "interaction[0].normal=\"mvg\"", "--set",
                                                 unset, "--set", "interaction[0].Dt=10.0"}}) {
    std::vector<std::string> args{"check", scene};
    args.insert(args.end(), quiet.begin(), quiet.end());
    const CmdResult r = run_mmpm(args);
    EXPECT_EQ(r.exit_code, 0) << r.describe();
    EXPECT_EQ(r.err, "") << r.describe();
  }
}

// A contact with a computed normal on a body with a face at an angle to
// the grid: the staircase normals stop or slow a slide along it
// (docs/contact_validation.md §4.4), so `check` warns, names the first
// such body and normal = "geometry". The shipped scene (geometry) and the
// specified normal do not, nor do a floor and a block turned by 180 degrees
// (faces on grid lines).
TEST(Cli, ComputedNormalOnASlantedFaceWarns) {
  const std::string scene = source_dir() + "/inputs/rotated_incline.toml";
  for (const char* normal : {"mvg", "avg", "rigid"}) {
    const std::string w =
        one_interaction_warning(run_mmpm({"check", scene, "--set",
                                          std::string("interaction[0].normal=\"") + normal + "\""}),
                                scene, "normal");
    EXPECT_TRUE(contains(w, std::string("normal = \"") + normal + "\" on body 'body0'")) << w;
    EXPECT_TRUE(contains(w, "normal = \"geometry\"")) << w;
  }
  for (const std::vector<std::string>& quiet :
       {std::vector<std::string>{},
        {"--set", "interaction[0].normal=\"specified\"", "--set",
         "interaction[0].normal_vector=[0.3420201433256687, -0.9396926207859084]"},
        {"--set", "interaction[0].normal=\"mvg\"", "--set", "body[0].rotate=180.0", "--set",
         "body[1].rotate=180.0"}}) {
    std::vector<std::string> args{"check", scene};
    args.insert(args.end(), quiet.begin(), quiet.end());
    const CmdResult r = run_mmpm(args);
    EXPECT_EQ(r.exit_code, 0) << r.describe();
    EXPECT_EQ(r.err, "") << r.describe();
  }
}

// Interaction keys the law or the normal never reads (scene/unused_keys.hpp):
// two_layer's interface switched to stick keeps Dn = "perfect" and Dt = 5,
// which then do nothing, so `check` names both, on the interaction's line;
// a Coulomb coefficient and a normal_vector under collision's frictionless
// law and avg normal, a center under a specified normal and Dn_compression
// under the linear traction law warn the same way. The resolved scene
// `check` prints warns with the same words (it writes every key; a key
// warns only when it differs from its default), and every shipped scene,
// and its resolved form, warns about none.
TEST(Cli, InteractionKeysTheLawNeverReadsWarn) {
  const std::string two_layer = source_dir() + "/inputs/two_layer.toml";
  const std::string where =
      two_layer + ":" + std::to_string(line_of(read_text(two_layer), "[[interaction]]")) + ":";
  const CmdResult stick = run_mmpm({"check", two_layer, "--set", "interaction[0].law=\"stick\""});
  ASSERT_EQ(stick.exit_code, 0) << stick.describe();
  const auto lines = lines_of(stick.err);
  ASSERT_EQ(lines.size(), 2u) << stick.describe();
  EXPECT_EQ(lines[0], where +
                          " warning: key 'interaction[0].Dn': Dn = \"perfect\" has no effect: law "
                          "= \"stick\" does not read it (it applies to law = \"interface\")");
  EXPECT_TRUE(contains(lines[1], where + " warning: key 'interaction[0].Dt': Dt = 5 has no effect"))
      << lines[1];

  const std::string collision = source_dir() + "/inputs/collision.toml";
  const std::string friction = one_interaction_warning(
      run_mmpm({"check", collision, "--set", "interaction[0].friction=0.3"}), collision,
      "friction");
  EXPECT_TRUE(contains(friction, "friction = 0.3 has no effect: law = \"frictionless\""))
      << friction;
  const std::string vector = one_interaction_warning(
      run_mmpm({"check", collision, "--set", "interaction[0].normal_vector=[0.0, 1.0]"}), collision,
      "normal_vector");
  EXPECT_TRUE(contains(vector, "normal_vector = [0, 1] has no effect: normal = \"avg\"")) << vector;
  const std::string center = one_interaction_warning(
      run_mmpm({"check", two_layer, "--set", "interaction[0].center=[4.0, 0.0]"}), two_layer,
      "center");
  EXPECT_TRUE(contains(center, "center = [4, 0] has no effect: normal = \"specified\"")) << center;
  const std::string compression = one_interaction_warning(
      run_mmpm({"check", two_layer, "--set", "interaction[0].Dn_compression=100.0"}), two_layer,
      "Dn_compression");
  EXPECT_TRUE(contains(compression, "traction_law = \"linear\" uses Dn in compression"))
      << compression;

  // The resolved scene warns with the same words, at its own line.
  TempDir tmp;
  const fs::path resolved = tmp / "resolved.toml";
  write_text(resolved, stick.out);
  const CmdResult again = run_mmpm({"check", resolved.string()});
  ASSERT_EQ(again.exit_code, 0) << again.describe();
  const auto again_lines = lines_of(again.err);
  ASSERT_EQ(again_lines.size(), 2u) << again.describe();
  for (std::size_t k = 0; k < 2; ++k) {
    const std::string tail = lines[k].substr(lines[k].find(" warning: "));
    EXPECT_TRUE(again_lines[k].starts_with(resolved.string() + ":")) << again_lines[k];
    EXPECT_TRUE(again_lines[k].ends_with(tail)) << again_lines[k];
  }

  for (const auto& entry : fs::directory_iterator(source_dir() + "/inputs")) {
    if (entry.path().extension() != ".toml") continue;
    const CmdResult r = run_mmpm({"check", entry.path().string()});
    ASSERT_EQ(r.exit_code, 0) << r.describe();
    EXPECT_FALSE(contains(r.err, "has no effect")) << r.describe();
    write_text(resolved, r.out);
    const CmdResult rr = run_mmpm({"check", resolved.string()});
    ASSERT_EQ(rr.exit_code, 0) << entry.path() << "\n" << rr.describe();
    EXPECT_FALSE(contains(rr.err, "has no effect")) << entry.path() << "\n" << rr.describe();
  }
}

// Pairs without an [[interaction]] of their own fall back on [simulation]
// default_law (stick unless set): the same check applies to them. A third
// material, named in no interaction, lies 1 mm above both blocks of
// collision.toml (nearest particles 1.25 apart; spacing 0.25, so at most
// 0.375 counts as touching): two warnings, one per pair, naming the default
// law; none once default_law = "separate"; one (the pair with block b) when
// the third body touches block a.
TEST(Cli, DefaultLawPairsThatStartApartWarnToo) {
  TempDir tmp;
  const fs::path scene = tmp / "three.toml";
  std::string text = read_text(source_dir() + "/inputs/collision.toml");
  const std::string third = R"([[material]]
name    = "strip"
type    = "isotropic"
density = 1.0e-3
E       = 100.0
nu      = 0.0

[[body]]
name     = "c"
material = "strip"
shape    = "box"
min      = [2.0, 7.0]
max      = [22.5, 7.5]
particles_per_cell = 2

)";
  text.insert(text.find("[[interaction]]"), third);
  write_text(scene, text);
  const std::string disp = "interaction[0].separation=\"displacement\"";
  const std::string touch_ab = "body[1].min=[12.0, 2.0]";
  const CmdResult apart = run_mmpm({"check", scene.string(), "--set", disp, "--set", touch_ab});
  ASSERT_EQ(apart.exit_code, 0) << apart.describe();
  const auto lines = lines_of(apart.err);
  ASSERT_EQ(lines.size(), 2u) << apart.describe();
  for (const std::string& line : lines) {
    // collision.toml does not set default_law: no line to name.
    EXPECT_TRUE(contains(line, scene.string() + ": warning: key 'simulation.default_law' (stick"))
        << line;
    // The search looks one cell (0.5) around each particle: beyond that,
    // "more than" the threshold.
    EXPECT_TRUE(contains(line, "nearest particles are more than 0.375 apart")) << line;
    EXPECT_TRUE(contains(line, "'strip'")) << line;
  }
  EXPECT_NE(contains(lines[0], "'block_a'"), contains(lines[1], "'block_a'")) << apart.err;
  EXPECT_NE(contains(lines[0], "'block_b'"), contains(lines[1], "'block_b'")) << apart.err;
  // A scene that sets default_law: the warning names its line (it named
  // the file alone until 2026-12-07).
  {
    std::string with_key = text;
    const std::size_t at = with_key.find("[simulation]\n");
    ASSERT_NE(at, std::string::npos);
    with_key.insert(at + 13, "default_law = \"stick\"\n");
    const long line = 2 + long(std::count(with_key.begin(), with_key.begin() + long(at), '\n'));
    const fs::path keyed = tmp / "keyed.toml";
    write_text(keyed, with_key);
    const CmdResult r = run_mmpm({"check", keyed.string(), "--set", disp, "--set", touch_ab});
    ASSERT_EQ(r.exit_code, 0) << r.describe();
    for (const std::string& l : lines_of(r.err))
      EXPECT_TRUE(contains(l, keyed.string() + ":" + std::to_string(line) +
                                  ": warning: key 'simulation.default_law' (stick"))
          << l;
  }

  const CmdResult separate = run_mmpm({"check", scene.string(), "--set", disp, "--set", touch_ab,
                                       "--set", "simulation.default_law=\"separate\""});
  EXPECT_EQ(separate.exit_code, 0) << separate.describe();
  EXPECT_EQ(separate.err, "") << separate.describe();

  const CmdResult one =
      run_mmpm({"check", scene.string(), "--set", disp, "--set", touch_ab, "--set",
                "body[2].max=[10.0, 7.5]", "--set", "body[2].min=[2.0, 6.0]"});
  EXPECT_EQ(one.exit_code, 0) << one.describe();
  const auto one_lines = lines_of(one.err);
  ASSERT_EQ(one_lines.size(), 1u) << one.describe();
  EXPECT_TRUE(contains(one_lines[0], "'strip' and 'block_b'")) << one_lines[0];
}

// scheme = "USL" has a step limit per shape (docs/validation.md §3.5: 0.55
// with uGIMP; the bars grow at 0.6 on a support): check and run warn above
// it, once, at the key that set the step, and still run (run refuses only
// cfl > 1; the run here ends after 6 steps, before the mode has grown).
// MUSL at the same cfl, and USL at the limit, say nothing.
TEST(Cli, UslAboveItsLimitWarns) {
  const std::string usl = "simulation.scheme=\"USL\"";
  for (const char* command : {"check", "run"}) {
    TempDir tmp;
    std::vector<std::string> args = {
        command, bar_scene(),          "--set", usl,
        "--set", "simulation.cfl=0.9", "--set", "simulation.end_time=0.0005"};
    if (std::string(command) == "run") args.insert(args.end(), {"--out", (tmp / "o").string()});
    const CmdResult fast = run_mmpm(args);
    ASSERT_EQ(fast.exit_code, 0) << fast.describe();
    const auto lines = lines_of(fast.err);
    ASSERT_EQ(lines.size(), 1u) << fast.describe();
    EXPECT_TRUE(contains(lines[0], bar_scene() + ": warning: key 'simulation.cfl': scheme \"USL\" "
                                                 "with shape \"gimp\" is stable only to about "
                                                 "cfl = 0.55 (measured)"))
        << lines[0];
    EXPECT_TRUE(contains(lines[0], "this step is cfl 0.9")) << lines[0];
  }
  // The limit is the shape's (docs/validation.md §3.5): cubic B-splines ran
  // the bar stable at 1.0, so 0.9 is quiet for them.
  for (const std::vector<std::string>& sets :
       {std::vector<std::string>{"--set", usl, "--set", "simulation.cfl=0.55"},
        std::vector<std::string>{"--set", usl, "--set", "simulation.cfl=0.9", "--set",
                                 "grid.shape=\"bspline3\""},
        std::vector<std::string>{"--set", "simulation.scheme=\"MUSL\"", "--set",
                                 "simulation.cfl=0.9"}}) {
    std::vector<std::string> args = {"check", bar_scene()};
    args.insert(args.end(), sets.begin(), sets.end());
    const CmdResult quiet = run_mmpm(args);
    ASSERT_EQ(quiet.exit_code, 0) << quiet.describe();
    EXPECT_TRUE(quiet.err.empty()) << quiet.describe();
  }
}

// A run that blows up without a particle check tripping stops at the energy
// guard (app/energy_guard.hpp): USL with uGIMP at cfl 0.75 grew the bar's
// K + U to ~800 times its initial energy in 0.2 ms (2701 steps) at finite J
// and ended with exit 0 before. Now exit 3, the stage, step and fastest
// particle named, and no summary.json (an abandoned run's outputs).
TEST(Cli, EnergyGrowthStopsAnUnstableRun) {
  TempDir tmp;
  const CmdResult r = run_mmpm({"run", bar_scene(), "--quiet", "--out", (tmp / "o").string(),
                                "--set", "simulation.scheme=\"USL\"", "--set",
                                "simulation.cfl=0.75", "--set", "simulation.end_time=0.2"});
  ASSERT_EQ(r.exit_code, 3) << r.describe();
  EXPECT_TRUE(contains(r.err, "unstable: stage energy check, step ")) << r.err;
  EXPECT_TRUE(contains(r.err, ", particle ")) << r.err;
  EXPECT_TRUE(contains(r.err, "times what the run was given (initial energy 0.02438")) << r.err;
  EXPECT_TRUE(contains(r.err, "this is the fastest particle")) << r.err;
  EXPECT_FALSE(std::filesystem::exists(tmp / "o" / "summary.json"));
  // The same bar at the shape's limit runs to the end.
  TempDir ok;
  const CmdResult stable = run_mmpm({"run", bar_scene(), "--quiet", "--out", (ok / "o").string(),
                                     "--set", "simulation.scheme=\"USL\"", "--set",
                                     "simulation.cfl=0.55", "--set", "simulation.end_time=0.2"});
  EXPECT_EQ(stable.exit_code, 0) << stable.describe();
}

// An interface with force_limit = false too stiff for the step
// (docs/multimaterial.md §8: omega dt > 2 at a node the interface halves)
// is named at its [[interaction]] line and key by `check` and `run`, once.
// two_layer.toml: bound Dn = 4.3e4 MPa/mm; 6e4 gives omega dt = 2.36 (it
// goes unstable at step 86; these runs stop after 24 steps). No warning
// with the limit on, below the bound, with the exact integration, or for a
// perfect direction.
TEST(Cli, StiffInterfaceWithoutForceLimitWarns) {
  const std::string scene = source_dir() + "/inputs/two_layer.toml";
  const std::vector<std::string> stiff = {"--set", "interaction[0].Dn=6e4", "--set",
                                          "interaction[0].force_limit=false"};
  for (const char* command : {"check", "run"}) {
    TempDir tmp;
    std::vector<std::string> args = {command, scene, "--set", "simulation.end_time=0.002"};
    args.insert(args.end(), stiff.begin(), stiff.end());
    if (std::string(command) == "run") args.insert(args.end(), {"--out", (tmp / "o").string()});
    const CmdResult r = run_mmpm(args);
    ASSERT_EQ(r.exit_code, 0) << r.describe();
    const auto lines = lines_of(r.err);
    ASSERT_EQ(lines.size(), 1u) << r.describe();
    EXPECT_TRUE(contains(lines[0], scene + ":51: warning: key 'interaction[0].Dn': with "
                                           "force_limit = false, Dn = 6e+04 is stiffer"))
        << lines[0];
    EXPECT_TRUE(contains(lines[0], "omega dt = 2.36")) << lines[0];
    EXPECT_TRUE(contains(lines[0], "Dn below about 4.31e+04")) << lines[0];
  }
  for (const std::vector<std::string>& sets :
       {std::vector<std::string>{"--set", "interaction[0].Dn=6e4"},
        std::vector<std::string>{"--set", "interaction[0].Dn=3e4", "--set",
                                 "interaction[0].force_limit=false"},
        std::vector<std::string>{"--set", "interaction[0].Dn=6e4", "--set",
                                 "interaction[0].force_limit=false", "--set",
                                 "interaction[0].integration=\"exact\""},
        std::vector<std::string>{"--set", "interaction[0].force_limit=false"}}) {
    std::vector<std::string> args = {"check", scene};
    args.insert(args.end(), sets.begin(), sets.end());
    const CmdResult quiet = run_mmpm(args);
    ASSERT_EQ(quiet.exit_code, 0) << quiet.describe();
    EXPECT_TRUE(quiet.err.empty()) << quiet.describe();
  }
}

// An interface spring in an undamped scene under a scheme whose opening reads
// another motion than its strain (docs/interface_validation.md Findings 14,
// 15): USF, or MUSL without the force limit, warns once at the interaction's
// line. inputs/wave_interface.toml has no damping. Quiet: the defaults (MUSL
// under the limit), the exact integration, grid damping, USL, pure PIC and
// perfect directions (no spring).
TEST(Cli, UndampedInterfaceSpringThatGainsEnergyWarns) {
  const std::string scene = source_dir() + "/inputs/wave_interface.toml";
  const std::string usf = one_interaction_warning(
      run_mmpm({"check", scene, "--set", "simulation.scheme=\"USF\""}), scene, "law");
  EXPECT_TRUE(contains(usf, "under scheme \"USF\" with no grid damping")) << usf;
  EXPECT_TRUE(contains(usf, "Finding 15")) << usf;
  const std::string no_limit = one_interaction_warning(
      run_mmpm({"check", scene, "--set", "interaction[0].force_limit=false"}), scene,
      "force_limit");
  EXPECT_TRUE(contains(no_limit, "force_limit = false with no grid damping")) << no_limit;
  EXPECT_TRUE(contains(no_limit, "Finding 14")) << no_limit;
  for (const std::vector<std::string>& sets :
       {std::vector<std::string>{},
        {"interaction[0].force_limit=false", "interaction[0].integration=\"exact\""},
        {"interaction[0].force_limit=false", "grid.damping=10.0"},
        {"simulation.scheme=\"USF\"", "grid.damping=10.0"},
        {"interaction[0].force_limit=false", "simulation.scheme=\"USL\""},
        {"simulation.scheme=\"USF\"", "simulation.flip=0.0"},
        {"simulation.scheme=\"USF\"", "interaction[0].Dn=\"perfect\"",
         "interaction[0].Dt=\"perfect\""}}) {
    std::vector<std::string> args = {"check", scene};
    for (const std::string& set : sets) args.insert(args.end(), {"--set", set});
    const CmdResult quiet = run_mmpm(args);
    ASSERT_EQ(quiet.exit_code, 0) << quiet.describe();
    EXPECT_FALSE(contains(quiet.err, "no grid damping")) << quiet.describe();
  }
}

// The kinetic-ratio stop waits until the scene no longer drives the bodies
// (run_driver.cpp still_driven): inputs/gripped_bar.toml, whose rigid grip
// pulls the bar until 0.1 ms. With kinetic_ratio = 0.1, a threshold the
// slow pull itself stays below (K / U ~ 1e-2 while loading), the run
// stopped at 0.04 ms with 11 % of the final strain energy when the guard
// was switched off; it must stop after 0.1 ms (measured 0.106), by the
// ratio, with the bar at its full strain energy E A d^2 / (2L) =
// 1.25e-3 mJ (1 %).
TEST(Cli, KineticRatioStopWaitsForTheDriveToEnd) {
  TempDir tmp;
  const fs::path out = tmp / "grip";
  const CmdResult r =
      run_mmpm({"run", source_dir() + "/inputs/gripped_bar.toml", "--set", "stop.kinetic_ratio=0.1",
                "--set", "stop.hold_steps=20", "--quiet", "--out", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.describe();
  const json j = json::parse(read_text(out / "summary.json"));
  EXPECT_EQ(j.at("stopped_by"), "kinetic_ratio");
  const double t = j.at("steps").get<double>() * j.at("dt").get<double>();
  EXPECT_GT(t, 0.1) << "stopped while the grip still moved";
  EXPECT_LT(t, 0.3);
  EXPECT_NEAR(number(j.at("energy"), "strain") / 1.25e-3, 1.0, 0.01);
}

// CSV fields of one line (RFC 4180 quotes).
std::vector<std::string> csv_fields(const std::string& line) {
  std::vector<std::string> out(1);
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (c == '"') {
      if (quoted && i + 1 < line.size() && line[i + 1] == '"') {
        out.back() += '"';
        ++i;
      } else {
        quoted = !quoted;
      }
    } else if (c == ',' && !quoted) {
      out.emplace_back();
    } else {
      out.back() += c;
    }
  }
  return out;
}

// A failed variant's row has the header's columns: its message in the last
// one, its directory where the header says (it had one field too many).
TEST(Cli, SweepFailedRowKeepsTheColumns) {
  TempDir tmp;
  const fs::path out = tmp / "sweep";
  // cfl 20 with force: the second variant goes unstable.
  const CmdResult r =
      run_mmpm({"sweep", bar_scene(), "--param", "simulation.cfl", "--values", "0.4,20.0", "--set",
                "simulation.force=true", "--set", "simulation.end_time=0.2", "--jobs", "1",
                "--quiet", "--out", out.string()});
  EXPECT_EQ(r.exit_code, 3) << r.describe();
  const auto rows = lines_of(read_text(out / "sweep.csv"));
  ASSERT_EQ(rows.size(), 3u);
  const auto header = csv_fields(rows[0]);
  const auto dir_col = std::find(header.begin(), header.end(), "directory") - header.begin();
  const auto msg_col = std::find(header.begin(), header.end(), "message") - header.begin();
  ASSERT_LT(std::size_t(msg_col), header.size());
  for (int k = 1; k <= 2; ++k) {
    const auto row = csv_fields(rows[std::size_t(k)]);
    ASSERT_EQ(row.size(), header.size()) << rows[std::size_t(k)];
    EXPECT_EQ(row[std::size_t(dir_col)], (out / std::to_string(k - 1)).string());
  }
  EXPECT_TRUE(contains(rows[2], ",failed,")) << rows[2];
  EXPECT_TRUE(contains(csv_fields(rows[2])[std::size_t(msg_col)], "unstable")) << rows[2];
  EXPECT_TRUE(csv_fields(rows[1])[std::size_t(msg_col)].empty()) << rows[1];
}

// SIGTERM to a sweep (a batch system's wall-time limit): the row running
// stops with a checkpoint (app/interrupt.hpp), the rows not started are
// not run, sweep.csv says so row by row ("interrupted"), and the sweep
// exits 128 + 15. Rows: bar_vibration.toml (400 particles) for 100 ms,
// ~2.5 M steps, minutes each; one job, so rows 1 and 2 wait.
TEST(Cli, InterruptedSweepMarksItsRows) {
  TempDir tmp;
  const fs::path out = tmp / "sweep";
  Child child({mmpm_binary(), "sweep", bar_scene(), "--param", "simulation.end_time", "--values",
               "100,101,102", "--jobs", "1", "--threads", "1", "--quiet", "--out", out.string()},
              tmp / "sweep.out", tmp / "sweep.err");
  const auto t0 = std::chrono::steady_clock::now();
  while (!fs::exists(out / "0" / "run.h5.partial") && !child.poll_done() &&
         std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60))
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  ASSERT_FALSE(child.poll_done()) << read_text(tmp / "sweep.err");
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  child.kill_and_wait(SIGTERM);
  EXPECT_EQ(child.result().signal, 0);
  EXPECT_EQ(child.result().exit_code, 128 + SIGTERM) << read_text(tmp / "sweep.err");
  const auto rows = lines_of(read_text(out / "sweep.csv"));
  ASSERT_EQ(rows.size(), 4u);
  const auto header = csv_fields(rows[0]);
  const auto msg_col =
      std::size_t(std::find(header.begin(), header.end(), "message") - header.begin());
  ASSERT_LT(msg_col, header.size());
  EXPECT_TRUE(contains(rows[1], ",interrupted,")) << rows[1];
  EXPECT_TRUE(
      contains(csv_fields(rows[1])[msg_col],
               "checkpoint written: continue with `mmpm run --restart " + (out / "0").string()))
      << rows[1];
  EXPECT_TRUE(fs::exists(out / "0" / "checkpoint.bin"));
  EXPECT_FALSE(fs::exists(out / "0" / "summary.json"));
  for (std::size_t k = 2; k <= 3; ++k) {
    EXPECT_TRUE(contains(rows[k], ",interrupted,")) << rows[k];
    EXPECT_EQ(csv_fields(rows[k])[msg_col], "not run: interrupted by SIGTERM") << rows[k];
  }
}

// A sweep prints each distinct scene warning once, with the row that first
// gave it: warnings that depend on the swept value are not hidden behind
// row 0's (which is all a sweep printed before 2026-11-29). Over the normal
// of series_bars, two rows at a time: mvg and avg each warn (two different
// lines, rows 1 and 2, in row order), the specified normal does not, and
// row 4's mvg warnings are row 1's, not repeated. Rows 1 and 2 each give
// two lines: the scene's normal_vector, which a computed normal never
// reads (scene/unused_keys.hpp), then the normal's own warning.
TEST(Cli, SweepPrintsEachRowsOwnWarningsOnce) {
  TempDir tmp;
  const std::string scene = source_dir() + "/inputs/series_bars.toml";
  const CmdResult r =
      run_mmpm({"sweep", scene, "--param", "interaction[0].normal", "--values",
                "\"mvg\",\"avg\",\"specified\",\"mvg\"", "--set", "simulation.end_time=0.002",
                "--jobs", "2", "--quiet", "--out", (tmp / "sweep").string()});
  ASSERT_EQ(r.exit_code, 0) << r.describe();
  const auto lines = lines_of(r.err);
  ASSERT_EQ(lines.size(), 4u) << r.describe();
  for (std::size_t k = 0; k < 4; ++k) {
    const std::string normal = k < 2 ? "mvg" : "avg";
    const std::string label =
        "[" + std::to_string(k / 2 + 1) + "/4] interaction[0].normal=\"" + normal + "\": " + scene;
    EXPECT_EQ(lines[k].rfind(label, 0), 0u) << lines[k];
    EXPECT_TRUE(contains(lines[k], "normal = \"" + normal + "\"")) << lines[k];
    const std::string key = k % 2 == 0 ? "normal_vector" : "normal";
    EXPECT_TRUE(contains(lines[k], "key 'interaction[0]." + key + "'")) << lines[k];
  }
}

TEST(Cli, SweepWritesTableAndOneSummaryPerValue) {
  TempDir tmp;
  const fs::path out = tmp / "sweep";
  const CmdResult r = run_mmpm({"sweep", bar_scene(), "--param", "simulation.end_time", "--values",
                                "0.01,0.02", "--jobs", "2", "--quiet", "--out", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.describe();
  const auto rows = lines_of(read_text(out / "sweep.csv"));
  ASSERT_EQ(rows.size(), 3u) << "header + 2 rows";
  EXPECT_TRUE(contains(rows[0], "status"));
  const double values[2] = {0.01, 0.02};
  for (int k = 0; k < 2; ++k) {
    EXPECT_TRUE(contains(rows[std::size_t(k) + 1], ",ok,")) << rows[std::size_t(k) + 1];
    const fs::path summary = out / std::to_string(k) / "summary.json";
    ASSERT_TRUE(fs::exists(summary)) << summary;
    const json j = json::parse(read_text(summary));
    const double dt = number(j, "dt");
    EXPECT_GE(number(j, "end_time"), values[k] - 1e-9 * dt) << "value " << k << " reached its run";
    EXPECT_EQ(number(j, "end_time"), values[k]) << "the last step lands on end_time";
    EXPECT_TRUE(fs::exists(out / std::to_string(k) / "run.h5"));
  }
}

}  // namespace
