// mmpm command line: run, check, sweep, info (SCENE.md "Command line").
#include <CLI/CLI.hpp>
#include <cstdio>
#include <iostream>

#include "app/build_info.hpp"
#include "app/interrupt.hpp"
#include "app/run_driver.hpp"
#include "app/start_warnings.hpp"
#include "app/sweep.hpp"
#include "scene/error.hpp"
#include "scene/format.hpp"
#include "scene/parse.hpp"
#include "solver/simulation.hpp"

namespace {

int check_scene(const std::string& file, const std::vector<std::string>& sets, bool force) {
  using namespace mmpm;
  Scene scene = parse_scene_file(file, sets);
  auto sim = make_simulation(scene);  // builds particles: catches geometry errors
  const double crit = critical_time_step(scene), dt = sim->dt();
  // What `run` refuses, `check` refuses, with the same message (SCENE.md:
  // a time step above the stability limit is bad input, exit 2). Until
  // 2026-12-07 check only warned and exited 0, so a script validating
  // scenes with it passed one that run then refused (an outside review).
  // Before printing: bad input leaves stdout empty.
  checked_time_step(scene, force);
  std::cout << format_scene(scene);
  std::cout << "# instantiation: " << sim->instantiation() << "\n"
            << "# particles: " << sim->particle_count() << ", nodes: " << sim->node_count()
            << ", material fields: " << sim->field_count() << ", tile: " << sim->tile_edge()
            << " cells\n"
            << "# dt: " << dt << " (stability limit " << crit << ", cfl " << dt / crit
            << "), steps: " << planned_steps(scene.simulation.end_time, dt) << "\n";
  if (dt > crit * (1 + 1e-12))
    std::cerr
        << file << ": warning: key 'simulation." << (scene.simulation.dt ? "dt" : "cfl")
        << "': the time step exceeds the stability limit; `mmpm run` refuses it unless --force\n";
  for (const std::string& w : start_warnings(scene, *sim, dt)) std::cerr << w << "\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"mmpm: multimaterial material point method with contact and imperfect interfaces"};
  app.require_subcommand(1);
  // CLI11 answers an unknown first word with "A subcommand is required".
  if (argc > 1 && argv[1][0] != '-') {
    const std::string cmd = argv[1];
    if (cmd != "run" && cmd != "check" && cmd != "sweep" && cmd != "info") {
      std::cerr << "mmpm: unknown command '" << cmd
                << "'; expected run, check, sweep or info (mmpm --help)\n";
      return 2;
    }
  }
  // Thread and job counts: CLI::PositiveNumber's message printed DBL_MAX in full.
  const CLI::Range kCount(1, 4096);

  auto* run = app.add_subcommand("run", "run a scene");
  std::string scene_file, restart_dir, out_dir;
  std::vector<std::string> sets;
  int threads = 0;
  bool quiet = false, force = false;
  run->add_option("scene", scene_file, "scene file (TOML)");
  run->add_option("--restart", restart_dir, "continue the run in DIR from its last checkpoint");
  auto* out_option =
      run->add_option("--out", out_dir, "output directory (default results/<scene name>)");
  run->add_option("--threads", threads, "OpenMP threads")->check(kCount);
  run->add_option("--set", sets, "override a scene key: KEY=VALUE (TOML value)");
  run->add_flag("--quiet", quiet, "no progress line, no timing table");
  run->add_flag("--force", force, "run even when the time step exceeds the stability limit");

  auto* check = app.add_subcommand("check", "validate a scene and print it resolved");
  std::string check_file;
  std::vector<std::string> check_sets;
  check->add_option("scene", check_file, "scene file (TOML)")->required();
  check->add_option("--set", check_sets, "override a scene key: KEY=VALUE");
  bool check_force = false;
  check->add_flag("--force", check_force,
                  "accept a time step above the stability limit, as run --force does");

  auto* sweep = app.add_subcommand("sweep", "run a scene over a list of values of one key");
  mmpm::SweepOptions so;
  std::string values;
  sweep->add_option("scene", so.scene_file, "scene file (TOML)")->required();
  sweep->add_option("--param", so.param, "key to vary, as for --set")->required();
  sweep->add_option("--values", values, "comma-separated TOML values")->required();
  sweep->add_option("--jobs", so.jobs, "runs at once")->check(kCount);
  sweep->add_option("--threads", so.threads, "OpenMP threads per run (default cores / jobs)")
      ->check(kCount);
  sweep->add_option("--out", so.out, "output directory");
  sweep->add_option("--set", so.overrides, "override a scene key for every run");
  bool sweep_quiet = false;
  sweep->add_flag("--quiet", sweep_quiet, "no per-run lines");

  auto* info = app.add_subcommand("info", "build options, SIMD width, threads, library versions");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help prints the help; an error gets one line, as bad scene input does
    // (CLI11's own report adds a second line).
    if (e.get_exit_code() == 0) return app.exit(e);
    std::cerr << "mmpm: " << e.what() << " (mmpm --help, mmpm COMMAND --help)\n";
    return 2;
  }
  if (out_option->count() > 0 && out_dir.empty()) {
    std::cerr << "mmpm run: --out: expected a directory, got an empty name\n";
    return 2;
  }
  // A restart continues the scene stored with the run (DIR/scene.toml) in
  // DIR; a scene file, --set or --out given with it would be ignored.
  if (!restart_dir.empty() && (!scene_file.empty() || !sets.empty() || out_option->count() > 0)) {
    std::cerr << "mmpm run: --restart DIR continues the scene stored in DIR (DIR/scene.toml) and "
                 "writes to DIR; expected no scene file, --set or --out with it\n";
    return 2;
  }

  try {
    if (*info) {
      std::cout << mmpm::build_description();
      return 0;
    }
    if (*check) return check_scene(check_file, check_sets, check_force);
    mmpm::catch_interrupts();  // run and sweep stop between steps, with a checkpoint
    if (*sweep) {
      so.values = mmpm::split_values(values);
      if (so.values.empty()) {
        std::cerr << "mmpm sweep: --values: expected comma-separated TOML values, got none\n";
        return 2;
      }
      so.quiet = sweep_quiet;
      return mmpm::run_sweep(so);
    }
    mmpm::RunOptions ro;
    ro.out = out_dir;
    ro.threads = threads;
    ro.quiet = quiet;
    ro.force = force;
    mmpm::RunOutcome r;
    if (!restart_dir.empty()) {
      r = mmpm::restart_run(restart_dir, ro, std::cout);
    } else {
      if (scene_file.empty()) {
        std::cerr << "mmpm run: a scene file or --restart DIR is required\n";
        return 2;
      }
      r = mmpm::run_scene(mmpm::parse_scene_file(scene_file, sets), ro, std::cout);
    }
    if (r.exit_code != 0) {
      std::cerr << "mmpm: " << r.message << "\n";
      return r.exit_code;
    }
    if (!quiet) std::cout << "results in " << r.directory.string() << "\n";
    return 0;
  } catch (const mmpm::InputError& e) {
    std::cerr << e.what() << "\n";
    return 2;
  } catch (const std::bad_alloc&) {
    // Past the scene's memory estimate (scene/parse.cpp), e.g. a limit
    // the estimate cannot see; the run's outputs stay marked partial.
    std::cerr << "mmpm: error: out of memory: the scene needs more memory than this process "
                 "was given; use fewer particles or cells, or raise the limit\n";
    return 3;
  } catch (const std::exception& e) {
    std::cerr << "mmpm: error: " << e.what() << "\n";
    return 3;
  }
}
