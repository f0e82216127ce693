// `mmpm sweep`: one scene over a list of values of one key, several runs at
// once (TBB), each run keeping its own OpenMP threads.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace mmpm {

struct SweepOptions {
  std::string scene_file;
  std::vector<std::string> overrides;  // applied to every run
  std::string param;                   // key, as for --set
  std::vector<std::string> values;     // TOML values
  int jobs = 1;
  int threads = 0;  // per run; 0: cores / jobs
  std::filesystem::path out;
  bool quiet = true;
};

// Splits "a,b,[1,2],\"x,y\"" at top-level commas.
std::vector<std::string> split_values(const std::string& text);

// Returns the process exit code; writes DIR/sweep.csv and DIR/<k>/summary.json.
int run_sweep(const SweepOptions& options);

}  // namespace mmpm
