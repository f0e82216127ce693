#include "app/sweep.hpp"

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <fstream>
#include <functional>
#include <iostream>
#include <mutex>
#include <optional>
#include <set>
#include <sstream>
#include <thread>

#include "app/interrupt.hpp"
#include "app/output_directory.hpp"
#include "app/run_driver.hpp"
#include "io/atomic_file.hpp"
#include "scene/error.hpp"
#include "scene/parse.hpp"

namespace mmpm {

std::vector<std::string> split_values(const std::string& text) {
  std::vector<std::string> out;
  std::string cur;
  int depth = 0;
  bool quoted = false;
  for (char c : text) {
    if (c == '"') quoted = !quoted;
    if (!quoted && (c == '[' || c == '{')) ++depth;
    if (!quoted && (c == ']' || c == '}')) --depth;
    if (c == ',' && depth == 0 && !quoted) {
      out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  if (!cur.empty()) out.push_back(cur);
  return out;
}

// RFC 4180 field: quoted, inner quotes doubled.
static std::string csv_quoted(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

namespace {

// The rows' scene warnings, printed in row order whatever order the rows
// run in (--jobs), each distinct line once, behind the label of the first
// row that gave it. A row's first delivery counts (its warnings, or none if
// it ended before them); later rows wait in `rows_` until the earlier ones
// have delivered.
class SweepWarnings {
 public:
  // `print`: the lock of every line the sweep writes to stderr.
  SweepWarnings(std::size_t n, std::function<std::string(std::size_t)> label, std::mutex& print)
      : rows_(n), label_(std::move(label)), mutex_(print) {}

  void deliver(std::size_t k, const std::vector<std::string>& warnings) {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (!rows_[k]) rows_[k] = warnings;
    for (; next_ < rows_.size() && rows_[next_]; ++next_)
      for (const std::string& w : *rows_[next_])
        if (printed_.insert(w).second) std::cerr << label_(next_) + w + "\n" << std::flush;
  }

 private:
  std::vector<std::optional<std::vector<std::string>>> rows_;
  std::size_t next_ = 0;
  std::set<std::string> printed_;
  std::function<std::string(std::size_t)> label_;
  std::mutex& mutex_;
};

}  // namespace

int run_sweep(const SweepOptions& opt) {
  namespace fs = std::filesystem;
  const std::size_t n = opt.values.size();
  // Parse every variant first: a bad value fails before anything runs.
  std::vector<Scene> scenes;
  for (const auto& v : opt.values) {
    auto ov = opt.overrides;
    ov.push_back(opt.param + "=" + v);
    scenes.push_back(parse_scene_file(opt.scene_file, ov));
  }
  // "[k/n] KEY=VALUE: ", the label of a row's lines.
  const auto row_label = [&](std::size_t k) {
    return "[" + std::to_string(k + 1) + "/" + std::to_string(n) + "] " + opt.param + "=" +
           opt.values[k] + ": ";
  };
  // And every variant's time step, as `run` checks it: a value that makes
  // the step unstable or the run endless was a failed row (exit 3) after
  // the others had run.
  for (std::size_t k = 0; k < n; ++k) {
    try {
      (void)checked_time_step(scenes[k], false);
    } catch (const InputError& e) {
      throw InputError(row_label(k) + e.what());
    }
  }
  const fs::path dir =
      opt.out.empty() ? fs::path("results") / (scenes.front().name + "_sweep") : opt.out;
  prepare_output_directory(dir, opt.out.empty() ? "sweep directory" : "--out");
  const int jobs = std::max(1, std::min<int>(opt.jobs, int(n)));
  const int cores = int(std::max(1u, std::thread::hardware_concurrency()));
  const int threads = opt.threads > 0 ? opt.threads : std::max(1, cores / jobs);
  std::vector<RunOutcome> results(n);
  std::mutex print_mutex;
  // Each distinct scene warning once, from the first row that gives it:
  // warnings that depend on the swept value (the cfl, the normal, the
  // particles per cell) name their row; row 0 alone would hide them.
  SweepWarnings warnings(n, row_label, print_mutex);
  // TBB keeps one worker per core beyond the caller; more jobs than cores
  // (asked for) then ran fewer at once, behind a TBB warning on stderr.
  const tbb::global_control allow_jobs(tbb::global_control::max_allowed_parallelism,
                                       std::size_t(jobs));
  tbb::task_arena arena(jobs);
  arena.execute([&] {
    tbb::parallel_for(std::size_t(0), n, [&](std::size_t k) {
      RunOptions ro;
      ro.out = dir / std::to_string(k);
      ro.threads = threads;
      ro.quiet = true;
      ro.progress = false;
      ro.on_warnings = [&, k](const std::vector<std::string>& w) { warnings.deliver(k, w); };
      std::ostringstream log;
      try {
        if (const int sig = pending_interrupt()) {  // the rows not started yet
          results[k].exit_code = 128 + sig;
          results[k].message = std::string("not run: interrupted by ") + signal_name(sig);
        } else {
          results[k] = run_scene(scenes[k], ro, log);
        }
      } catch (const InputError& e) {
        results[k].exit_code = 2;
        results[k].message = e.what();
      } catch (const std::exception& e) {
        results[k].exit_code = 3;
        results[k].message = e.what();
      }
      warnings.deliver(k, {});  // a row that ended before its warnings has none
      if (!opt.quiet) {
        // One write per line under the lock: rows ending together had
        // their lines interleaved piece by piece.
        const std::string line =
            row_label(k) + (results[k].exit_code == 0 ? "done" : results[k].message) + "\n";
        const std::lock_guard<std::mutex> lock(print_mutex);
        std::cerr << line << std::flush;
      }
    });
  });
  std::ostringstream csv;
  csv << "index,value,status,steps,end_time,wall_s,ns_per_particle_step,kinetic,strain,interface,"
         "external_work,damping,multimaterial_nodes,force_limited_nodes,stopped_by,directory,"
         "message\n";
  int code = 0, interrupted_code = 0;  // an interruption's 128 + signal wins over 3
  for (std::size_t k = 0; k < n; ++k) {
    const auto& r = results[k];
    const bool interrupted = r.exit_code > 128;
    csv << k << "," << csv_quoted(opt.values[k]) << ","
        << (r.exit_code == 0 ? "ok"
            : interrupted    ? "interrupted"
                             : "failed")
        << ",";
    if (r.exit_code == 0) {
      const auto& j = r.summary;
      const auto& e = j["energy"];
      csv << j["steps"] << "," << j["end_time"] << "," << j["wall_s"] << ","
          << j["ns_per_particle_step"] << "," << e["kinetic"] << "," << e["strain"] << ","
          << e["interface"] << "," << e["external_work"] << "," << e["damping"] << ","
          << j["multimaterial_nodes"] << "," << j["force_limited_nodes"] << ","
          << j["stopped_by"].get<std::string>();
    } else {
      csv << ",,,,,,,,,,,";  // the 12 columns steps .. stopped_by, empty
      if (interrupted)
        interrupted_code = r.exit_code;
      else
        code = 3;
    }
    // The message last, so that every row has the header's columns.
    csv << "," << (dir / std::to_string(k)).string() << ","
        << (r.exit_code == 0 ? "" : csv_quoted(r.message.substr(0, 200))) << "\n";
  }
  io::write_file_atomic(dir / "sweep.csv", csv.str());
  if (!opt.quiet) std::cerr << "wrote " << (dir / "sweep.csv").string() << "\n";
  return interrupted_code != 0 ? interrupted_code : code;
}

}  // namespace mmpm
