// `mmpm run`: drives a Simulation to its end, writing snapshots, the time
// series, checkpoints, summary.json and the timing table.
#pragma once

#include <filesystem>
#include <functional>
#include <iosfwd>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "scene/scene.hpp"

namespace mmpm {

struct RunOptions {
  std::filesystem::path out;  // empty: scene.output.directory
  int threads = 0;            // 0: OpenMP default
  bool quiet = false;
  bool force = false;    // run even above the stability limit
  bool progress = true;  // progress line when stderr is a terminal
  bool timing_table = true;
  bool warnings = true;  // scene warnings (start_warnings) on stderr before a fresh start
  // When set, the scene warnings go here instead of stderr (a sweep prints
  // each distinct one once, naming the row that first gave it).
  std::function<void(const std::vector<std::string>&)> on_warnings;
};

struct RunOutcome {
  int exit_code = 0;       // 0 ok, 2 bad input, 3 unstable / failed, 128 + signal interrupted
  std::string message;     // error text when exit_code != 0
  nlohmann::json summary;  // summary.json contents when the run completed
  std::filesystem::path directory;
};

// The scene's time step, checked as `run` checks it before anything is
// built: above the stability limit without force, or more steps than any
// run, is an InputError.
double checked_time_step(const Scene& scene, bool force);

// Runs a scene from its start, or (restart_dir non-empty) continues the run
// whose checkpoint and resolved scene are in restart_dir.
RunOutcome run_scene(const Scene& scene, const RunOptions& options, std::ostream& log);
RunOutcome restart_run(const std::filesystem::path& restart_dir, const RunOptions& options,
                       std::ostream& log);

}  // namespace mmpm
