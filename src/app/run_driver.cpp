#include "app/run_driver.hpp"

#include <omp.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <ostream>
#include <sstream>
#include <string_view>

#include "app/build_info.hpp"
#include "app/energy_guard.hpp"
#include "app/interrupt.hpp"
#include "app/output_directory.hpp"
#include "app/start_warnings.hpp"
#include "app/timing_table.hpp"
#include "io/atomic_file.hpp"
#include "io/checkpoint.hpp"
#include "io/run_writer.hpp"
#include "io/summary.hpp"
#include "scene/error.hpp"
#include "scene/parse.hpp"
#include "solver/simulation.hpp"

namespace mmpm {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

const char* kAxes[3] = {"x", "y", "z"};
constexpr std::size_t kResidualWindow = 10;  // series rows

// State of the driver that a checkpoint must carry besides the simulation's.
struct DriverState {
  std::vector<std::string> names;
  std::vector<std::vector<double>> columns;
  long next_snapshot = 0;  // index k of the next snapshot time k * every
  long streak_start = -1;  // first step of the current run of low kinetic ratio
  long last_snapshot_step = -1;
  // A restarted run's earlier segments, up to the checkpoint it resumed
  // from: summary.json's wall_s and stages_s cover every step of the
  // result, as its step count does (the minutes between that checkpoint
  // and the kill were redone, and count once).
  double wall_before = 0;
  std::vector<double> stages_before = std::vector<double>(kStageCount, 0.0);
};

// Series names allow letters, digits, '_', '.', '-' (run.h5 dataset names).
std::string sanitize(std::string s) {
  for (char& c : s)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.' || c == '-')) c = '_';
  return s;
}

std::vector<std::string> series_names(const Simulation& sim) {
  std::vector<std::string> n = {"time",
                                "step",
                                "kinetic",
                                "strain",
                                "interface",
                                "external_work",
                                "damping",
                                "kinetic_unresolved",
                                "energy_balance",
                                "kinetic_ratio",
                                "stored_energy_residual"};
  const int dim = sim.snapshot({}).dimension;
  for (const auto& r : sim.reactions())
    for (int d = 0; d < dim; ++d) n.push_back(sanitize("reaction_" + r.name + "_" + kAxes[d]));
  for (const char* c : {"multimaterial_nodes", "nodes_3plus", "force_limited_nodes"})
    n.push_back(c);
  for (const char* s : kStageNames) n.push_back(std::string("stage_") + s + "_s");
  return n;
}

void add_series_row(Simulation& sim, DriverState& st,
                    const std::array<double, kStageCount>& stage_s, int dim, const Energies& e) {
  // energy_balance: energy now (incl. what damping removed) minus the
  // initial energy and the external work; zero for an exact integrator.
  const double total = e.kinetic + e.strain + e.interface + e.damping;
  const double initial = st.columns.empty()
                             ? total - e.external_work
                             : st.columns[2][0] + st.columns[3][0] + st.columns[4][0];
  std::vector<double> row = {sim.time(),
                             double(sim.step_count()),
                             e.kinetic,
                             e.strain,
                             e.interface,
                             e.external_work,
                             e.damping,
                             e.kinetic_unresolved,
                             total - e.external_work - initial};
  // Convergence monitor for static runs: kinetic / stored energy, and the
  // relative change of the stored energy over the last kResidualWindow rows.
  const double stored = e.strain + e.interface;
  row.push_back(stored > 0 ? e.kinetic / stored : (e.kinetic > 0 ? INFINITY : 0.0));
  double residual = INFINITY;
  if (!st.columns.empty() && st.columns[0].size() >= kResidualWindow && stored > 0) {
    const std::size_t k = st.columns[0].size() - kResidualWindow;
    residual = std::abs(stored - (st.columns[3][k] + st.columns[4][k])) / stored;
  }
  row.push_back(residual);
  for (const auto& r : sim.reactions())
    for (int d = 0; d < dim; ++d) row.push_back(r.force[d]);
  const StepCounters c = sim.counters();
  row.push_back(double(c.multimaterial_nodes));
  row.push_back(double(c.nodes_3plus));
  row.push_back(double(c.force_limited_nodes));
  for (double s : stage_s) row.push_back(s);
  if (st.columns.empty()) st.columns.resize(row.size());
  for (std::size_t k = 0; k < row.size(); ++k) st.columns[k].push_back(row[k]);
}

std::vector<io::Blob> driver_blobs(const DriverState& st, double wall_s,
                                   const std::array<double, kStageCount>& stages_s) {
  std::vector<io::Blob> b;
  b.push_back(io::make_scalar_blob("driver.wall_s", wall_s));
  b.push_back(
      io::make_blob("driver.stages_s", std::vector<double>(stages_s.begin(), stages_s.end())));
  b.push_back(io::make_scalar_blob("driver.next_snapshot", st.next_snapshot));
  b.push_back(io::make_scalar_blob("driver.streak_start", st.streak_start));
  b.push_back(io::make_scalar_blob("driver.last_snapshot_step", st.last_snapshot_step));
  for (std::size_t k = 0; k < st.columns.size(); ++k)
    b.push_back(io::make_blob("driver.series." + std::to_string(k), st.columns[k]));
  return b;
}

// The resolved scene the checkpointed run ran, kept with its state: a
// scene.toml edited since (another E, other cells) would continue that state
// under other physics and give a result that neither scene produces.
constexpr std::string_view kSceneBlob = "driver.scene";

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// The dotted key ("material[1].E") that line k of a resolved scene sets, or
// "" for a section header: format_scene() writes one `key = value` per line
// under `[section]` and `[[array]]` headers.
std::string resolved_key(const std::vector<std::string>& lines, std::size_t k) {
  std::map<std::string, int> seen;
  std::string section;
  for (std::size_t i = 0; i <= k && i < lines.size(); ++i) {
    const std::string& line = lines[i];
    if (line.rfind("[[", 0) == 0) {
      const std::string name = line.substr(2, line.find("]]") - 2);
      section = name + "[" + std::to_string(seen[name]++) + "]";
    } else if (line.rfind('[', 0) == 0) {
      section = line.substr(1, line.find(']') - 1);
    } else if (i == k) {
      const std::size_t eq = line.find(" =");
      if (eq == std::string::npos) return "";
      return section + "." + line.substr(0, eq);
    }
  }
  return "";
}

// Throws InputError naming the first setting of `scene_file` that differs
// from the scene stored in the checkpoint. Both sides are resolved scenes,
// so comments and spacing do not count. Checkpoints written before
// 2026-11-29 store no scene and are not checked.
void check_scene_unchanged(const fs::path& scene_file, const std::string& resolved,
                           const std::vector<io::Blob>& blobs) {
  const io::Blob* stored_blob = io::find_optional_blob(blobs, kSceneBlob);
  if (!stored_blob) return;
  const std::string stored = io::read_string_blob(*stored_blob);
  if (stored == resolved) return;
  const std::vector<std::string> now = lines_of(resolved), then = lines_of(stored);
  std::size_t k = 0;
  while (k < now.size() && k < then.size() && now[k] == then[k]) ++k;
  const auto shown = [](const std::vector<std::string>& lines, std::size_t i) {
    return i < lines.size() ? "`" + lines[i] + "`" : std::string("the end of the scene");
  };
  const std::string key = k < now.size() ? resolved_key(now, k) : resolved_key(then, k);
  throw InputError(scene_file.string() + ": " + (key.empty() ? "" : "key '" + key + "': ") +
                   "differs from the scene the checkpoint continues: " + shown(now, k) + ", was " +
                   shown(then, k) +
                   "; a restart continues the checkpointed run unchanged: restore the scene, or "
                   "run the edited scene from the start");
}

void load_driver_blobs(const std::vector<io::Blob>& blobs, DriverState& st) {
  st.next_snapshot = io::read_scalar_blob<long>(io::find_blob(blobs, "driver.next_snapshot"));
  st.streak_start = io::read_scalar_blob<long>(io::find_blob(blobs, "driver.streak_start"));
  st.last_snapshot_step =
      io::read_scalar_blob<long>(io::find_blob(blobs, "driver.last_snapshot_step"));
  // Checkpoints written before 2026-11-26 carry no times: the summary then
  // covers the resumed segment only, as it did.
  if (const io::Blob* b = io::find_optional_blob(blobs, "driver.wall_s"))
    st.wall_before = io::read_scalar_blob<double>(*b);
  if (const io::Blob* b = io::find_optional_blob(blobs, "driver.stages_s")) {
    io::read_blob(*b, st.stages_before);
    st.stages_before.resize(kStageCount, 0.0);
  }
  st.columns.assign(st.names.size(), {});
  for (std::size_t k = 0; k < st.names.size(); ++k)
    io::read_blob(io::find_blob(blobs, "driver.series." + std::to_string(k)), st.columns[k]);
}

class Progress {
 public:
  Progress(bool on, double end_time)
      : on_(on), end_(end_time), start_(Clock::now()), last_(start_) {}
  void update(long step, double t, bool force = false) {
    if (!on_) return;
    const auto now = Clock::now();
    if (!force && std::chrono::duration<double>(now - last_).count() < 0.25) return;
    last_ = now;
    const double el = std::chrono::duration<double>(now - start_).count();
    const double rate = el > 0 ? double(step - first_step_) / el : 0.0;
    const double frac = end_ > 0 ? t / end_ : 0.0;
    const double eta = frac > 0 && frac < 1 && el > 0
                           ? el * (1 - frac) / std::max(1e-12, frac - first_frac_)
                           : 0.0;
    std::fprintf(stderr, "\rstep %9ld  t = %.6g / %.6g  %9.0f steps/s  ETA %7.1f s   ", step, t,
                 end_, rate, eta);
    std::fflush(stderr);
  }
  void start_at(long step, double t) {
    first_step_ = step;
    first_frac_ = end_ > 0 ? t / end_ : 0.0;
  }
  void done() {
    if (on_) std::fprintf(stderr, "\n");
  }

 private:
  bool on_;
  double end_;
  Clock::time_point start_, last_;
  long first_step_ = 0;
  double first_frac_ = 0;
};

// True while the scene still drives the bodies at time t or later: a load
// or a support's displacement still ramping, or a rigid material moving now
// or at a later row of its table. The kinetic-ratio stop waits for the end
// of the drive: a slow ramp or punch keeps kinetic / stored energy small
// while it still loads. (Until 2026-11-27 a moving rigid material's
// particles counted in the kinetic energy, which kept the ratio up.)
bool still_driven(const Scene& scene, double t) {
  for (const auto& l : scene.loads)
    if (t < l.ramp) return true;
  for (const auto& b : scene.boundaries)
    if (b.has_displacement && t < b.ramp) return true;
  for (const auto& m : scene.materials) {
    if (m.type != MaterialType::rigid) continue;
    const auto& table = m.velocity;
    for (std::size_t k = 0; k < table.velocity.size(); ++k) {
      const bool now_or_later = k + 1 >= table.time.size() || table.time[k + 1] > t;
      const Vec3& v = table.velocity[k];
      if (now_or_later && (v[0] != 0 || v[1] != 0 || v[2] != 0)) return true;
    }
  }
  return false;
}

}  // namespace

double checked_time_step(const Scene& scene, bool force) {
  const double crit = critical_time_step(scene);
  const double dt = stable_time_step(scene);
  if (dt > crit * (1 + 1e-12) && !(force || scene.simulation.force)) {
    std::ostringstream m;
    m << "time step " << dt << " exceeds the stability limit " << crit << " (cfl " << dt / crit
      << " > 1";
    if (crit == damping_time_step(scene))
      m << "; the limit is 2 / grid.damping, of the damping " << scene.grid.damping;
    // `sweep` has no --force flag: the scene key serves both commands.
    m << "); lower it, or run with --force (or simulation.force = true)";
    fail_at_time_step_key(scene, m.str());
  }
  check_step_count(scene, dt);
  return dt;
}

namespace {

RunOutcome drive(const Scene& scene, const RunOptions& opt, std::ostream& log, const fs::path& dir,
                 const std::vector<io::Blob>* resume) {
  RunOutcome out;
  out.directory = dir;
  const auto wall0 = Clock::now();
  if (opt.threads > 0) omp_set_num_threads(opt.threads);
  const int threads = opt.threads > 0 ? opt.threads : omp_get_max_threads();

  const double dt = checked_time_step(scene, opt.force);
  std::unique_ptr<Simulation> sim = make_simulation(scene);
  if (!resume && opt.warnings) {
    const std::vector<std::string> warnings = start_warnings(scene, *sim, dt);
    if (opt.on_warnings)
      opt.on_warnings(warnings);
    else
      for (const std::string& w : warnings) std::cerr << w << "\n";
  }
  const int dim = scene.simulation.dimension;
  DriverState st;
  st.names = series_names(*sim);

  // Every requested output field must exist before anything is written.
  (void)sim->snapshot(scene.output.fields);
  // A directory the scene's key chose is blamed on that key's line.
  const Where& key = scene.output.directory_where;
  std::string chosen_by = "output.directory";
  if (!key.file.empty()) {
    chosen_by = located(key.file, key.line, key.key, "");
    while (!chosen_by.empty() && (chosen_by.back() == ' ' || chosen_by.back() == ':'))
      chosen_by.pop_back();
    chosen_by += ":";
  }
  prepare_output_directory(dir, resume ? "--restart" : opt.out.empty() ? chosen_by : "--out");
  std::unique_ptr<io::RunWriter> writer;
  if (resume) {
    try {
      sim->load_state(*resume);
    } catch (const std::runtime_error& e) {
      // A column or value the scene needs is missing or has another size:
      // the checkpoint came from another scene or another version of mmpm
      // (e.g. one from before 2026-11-28 lacks the traction face offsets).
      throw InputError((dir / "checkpoint.bin").string() + ": " + e.what() +
                       ": the checkpoint does not hold this scene's state as this mmpm stores "
                       "it (another scene, or written by another version of mmpm); run the "
                       "scene again");
    }
    load_driver_blobs(*resume, st);
    try {
      writer = std::make_unique<io::RunWriter>(io::RunWriter::reopen(dir, st.last_snapshot_step));
    } catch (const std::exception& e) {
      // The snapshots so far are part of what the restart directory must
      // hold, as the checkpoint is: missing or damaged, it is bad input.
      // (The message names the file.)
      throw InputError(std::string(e.what()) +
                       "; the restart needs the snapshots the run wrote before its checkpoint; "
                       "run the scene again from the start");
    }
  } else {
    fs::remove(dir / "summary.json");
    fs::remove(dir / "checkpoint.bin");
    io::write_file_atomic(dir / "scene.toml", scene.source_text);
    writer = std::make_unique<io::RunWriter>(dir);
  }
  writer->set_attribute("scene", scene.source_text);
  writer->set_attribute("build", build_description());
  writer->set_attribute("instantiation", sim->instantiation());

  const auto& o = scene.output;
  const double end_time = scene.simulation.end_time;
  const double every = o.every;
  const bool tty = opt.progress && !opt.quiet && isatty(STDERR_FILENO);
  Progress progress(tty, end_time);
  progress.start_at(sim->step_count(), sim->time());
  std::array<double, kStageCount> stage_s{};  // output stage is timed here
  auto sim_stages = [&] {
    auto s = sim->stage_seconds();
    s[kStageOutput] = stage_s[kStageOutput];
    for (int k = 0; k < kStageCount; ++k) s[std::size_t(k)] += st.stages_before[std::size_t(k)];
    return s;
  };
  auto wall_so_far = [&] {
    return st.wall_before + std::chrono::duration<double>(Clock::now() - wall0).count();
  };
  long output_calls = 0;
  auto snapshot_if_due = [&](bool final) {
    const double t = sim->time();
    // Half a step early counts as on time; with steps longer than `every`
    // half of `every` (every step is then due): half of a step of 1e308
    // put every snapshot time in the past, and the loop below never ended.
    const double early = 0.5 * std::min(sim->dt(), every);
    const bool due = every > 0 && t >= double(st.next_snapshot) * every - early;
    if (!(due || (final && st.last_snapshot_step != sim->step_count()))) return;
    const auto t0 = Clock::now();
    io::Snapshot snapshot = sim->snapshot(o.fields);
    snapshot.grid = sim->grid_snapshot(o.grid_fields);
    writer->write_snapshot(snapshot);
    st.last_snapshot_step = sim->step_count();
    if (every > 0) {
      // Jump straight to the first snapshot time after t: with `every` far
      // below dt a loop of single increments would run (t + dt / 2) / every
      // times (2.5e11 for every = 1e-12 ms, a hang); the loops after the
      // jump only absorb the division's rounding.
      const double k = std::floor((t + early) / every);
      if (k > double(st.next_snapshot)) st.next_snapshot = static_cast<long>(k);
      while (double(st.next_snapshot) * every - early <= t) ++st.next_snapshot;
    }
    stage_s[kStageOutput] += std::chrono::duration<double>(Clock::now() - t0).count();
    ++output_calls;
  };
  auto checkpoint = [&] {
    const auto t0 = Clock::now();
    writer->sync();  // the snapshots the checkpoint refers to reach the disk first
    std::vector<io::Blob> blobs = sim->save_state();
    for (auto& b : driver_blobs(st, wall_so_far(), sim_stages())) blobs.push_back(std::move(b));
    blobs.push_back(io::make_string_blob(std::string(kSceneBlob), scene.source_text));
    io::write_checkpoint(dir / "checkpoint.bin", blobs);
    stage_s[kStageOutput] += std::chrono::duration<double>(Clock::now() - t0).count();
  };

  if (!resume) {
    add_series_row(*sim, st, sim_stages(), dim, sim->energies());
    snapshot_if_due(false);
  }
  std::string stopped_by = "end_time";
  const long series_every = std::max(1, o.series);
  const long stop_check =
      scene.stop.enabled ? std::max(1L, std::min<long>(series_every, scene.stop.hold_steps / 4))
                         : 0;
  // The energy guard looks at every series row, and every 100 steps when
  // the rows are sparser (the default rows are 100 steps apart, so by
  // default it costs nothing: the rows compute the energies anyway).
  const long guard_every = std::min(series_every, 100L);
  const EnergyGuard guard = [&] {
    double mass = 0;
    for (const double m : sim->particle_field("mass").values) mass += m;
    // Step 0's row, which a restarted run carries over.
    const double initial = st.columns[2][0] + st.columns[3][0] + st.columns[4][0];
    return make_energy_guard(initial, mass, fastest_wave_speed(scene));
  }();
  const double ckpt_s = o.checkpoint_minutes * 60.0;
  auto last_ckpt = Clock::now();
  std::optional<Energies> final_energies;
  try {
    const double end_tolerance = end_time_tolerance(end_time, sim->dt());
    while (sim->time() < end_time - end_tolerance) {
      sim->step_within(end_time);
      const long s = sim->step_count();
      bool stop = false;
      std::optional<Energies> energies;
      auto energies_now = [&]() -> const Energies& {
        if (!energies) energies = sim->energies();
        return *energies;
      };
      if (s % guard_every == 0)
        if (const std::string why = guard.check(energies_now()); !why.empty())
          sim->fail_at_fastest_particle("energy check", why);
      if (stop_check > 0 && s % stop_check == 0) {
        // The kinetic energy of the grid's velocity field, not the
        // particles': pure FLIP (flip = 1, the default) keeps particle
        // velocities the grid cannot see, which no damping reaches, so the
        // particles' ratio of a static series_bars rose to 2.6e-5 and the
        // run never stopped (docs/validation.md 3.9).
        const Energies& e = energies_now();
        const double stored = e.strain + e.interface;
        const double moving = e.kinetic - e.kinetic_unresolved;
        const double ratio = stored > 0 ? moving / stored : INFINITY;
        if (ratio < scene.stop.kinetic_ratio && !still_driven(scene, sim->time())) {
          if (st.streak_start < 0) st.streak_start = s;
          if (s - st.streak_start >= scene.stop.hold_steps) stop = true;
        } else {
          st.streak_start = -1;
        }
      }
      // The last step's row is added here, before the checkpoint below, not
      // after the loop: its multimaterial node counts, reactions and
      // unresolved kinetic energy come from the step's grid, which a
      // checkpoint does not hold, so a restart from a checkpoint at the last
      // step used to write that row with 0 multimaterial nodes (2026-12-01).
      const bool last = !(sim->time() < end_time - end_tolerance);
      if (s % series_every == 0 || stop || last)
        add_series_row(*sim, st, sim_stages(), dim, energies_now());
      snapshot_if_due(false);
      if (stop) {
        stopped_by = "kinetic_ratio";
        break;
      }
      if (ckpt_s > 0 && std::chrono::duration<double>(Clock::now() - last_ckpt).count() >= ckpt_s) {
        checkpoint();
        last_ckpt = Clock::now();
      }
      if (const int sig = pending_interrupt()) {
        // Stopped from outside (app/interrupt.hpp): keep what was computed.
        checkpoint();
        progress.done();
        std::ostringstream m;
        m << "interrupted by " << signal_name(sig) << " at step " << s << " (t = " << sim->time()
          << " of " << end_time << "); checkpoint written: continue with `mmpm run --restart "
          << dir.string() << (opt.force ? " --force" : "") << "`";
        out.exit_code = 128 + sig;
        out.message = m.str();
        return out;
      }
      progress.update(s, sim->time());
    }
    // The last steps since the guard's last look; the final row reuses them.
    final_energies = sim->energies();
    if (const std::string why = guard.check(*final_energies); !why.empty())
      sim->fail_at_fastest_particle("energy check", why);
  } catch (const SimulationError& e) {
    progress.done();
    writer->abandon();
    out.exit_code = 3;
    out.message = e.what();
    return out;
  }
  progress.update(sim->step_count(), sim->time(), true);
  progress.done();
  if (st.columns.empty() || st.columns[1].back() != double(sim->step_count()))
    add_series_row(*sim, st, sim_stages(), dim, *final_energies);
  snapshot_if_due(true);
  writer->write_series(st.names, st.columns);

  const double wall = wall_so_far();
  auto stages = sim_stages();
  auto calls = sim->stage_calls();
  calls[kStageOutput] = output_calls;
  const Energies e = sim->energies();
  // The counters of the last step, from its series row: a run restarted
  // from a checkpoint at its last step takes no step, and the simulation's
  // own counters are then empty.
  const auto last_of = [&](const char* column) {
    for (std::size_t k = 0; k < st.names.size(); ++k)
      if (st.names[k] == column) return static_cast<long>(st.columns[k].back());
    throw std::logic_error(std::string("run driver: no series column ") + column);
  };
  nlohmann::json j;
  j["scene"] = scene.name;
  j["dimension"] = dim;
  j["precision"] = scene.simulation.precision == Precision::float64 ? "double" : "float";
  j["particles"] = sim->particle_count();
  j["nodes"] = sim->node_count();
  j["materials"] = scene.materials.size();
  j["steps"] = sim->step_count();
  j["end_time"] = sim->time();
  j["dt"] = sim->dt();
  j["threads"] = threads;
  j["wall_s"] = wall;
  const double ps = double(sim->particle_count()) * double(std::max(1L, sim->step_count()));
  j["ns_per_particle_step"] = wall * 1e9 / ps;
  nlohmann::json js;
  double timed = 0;
  for (int k = 0; k < kStageCount; ++k) {
    js[kStageNames[k]] = stages[k];
    timed += stages[k];
  }
  js["other"] = wall - timed;
  j["stages_s"] = js;
  j["energy"] = {{"kinetic", e.kinetic},
                 {"strain", e.strain},
                 {"interface", e.interface},
                 {"external_work", e.external_work},
                 {"damping", e.damping}};
  j["multimaterial_nodes"] = last_of("multimaterial_nodes");
  j["nodes_3plus"] = last_of("nodes_3plus");
  j["force_limited_nodes"] = last_of("force_limited_nodes");
  j["stopped_by"] = stopped_by;
  // summary.json is written before run.h5 gets its name, and removed again
  // if that fails: a run either leaves both, or neither and its partial
  // and checkpoint for a restart (a full disk, 2026-11-29).
  try {
    writer->finish([&] { io::write_summary(dir / "summary.json", j); });
  } catch (...) {
    std::error_code ignored;
    fs::remove(dir / "summary.json", ignored);
    throw;
  }
  fs::remove(dir / "checkpoint.bin");
  out.summary = j;
  if (opt.timing_table && !opt.quiet)
    print_timing_table(log, stages, calls, wall, sim->step_count(), sim->particle_count());
  return out;
}

fs::path output_dir(const Scene& scene, const RunOptions& opt) {
  if (!opt.out.empty()) return opt.out;
  if (!scene.output.directory.empty()) return scene.output.directory;
  return fs::path("results") / scene.name;
}

}  // namespace

RunOutcome run_scene(const Scene& scene, const RunOptions& options, std::ostream& log) {
  return drive(scene, options, log, output_dir(scene, options), nullptr);
}

RunOutcome restart_run(const fs::path& dir, const RunOptions& options, std::ostream& log) {
  const fs::path scene_file = dir / "scene.toml";
  if (!fs::exists(scene_file))
    throw InputError(scene_file.string() + ": no resolved scene to restart from");
  const fs::path ckpt = dir / "checkpoint.bin";
  if (!fs::exists(ckpt)) throw InputError(ckpt.string() + ": no checkpoint to restart from");
  // A directory opens as a stream and fails only in the read, whose message
  // ("basic_filebuf::underflow ...") names no file.
  if (!fs::is_regular_file(ckpt))
    throw InputError(ckpt.string() + ": expected a checkpoint file, found another kind of entry");
  Scene scene = parse_scene_file(scene_file.string());
  std::vector<io::Blob> blobs;
  try {
    blobs = io::read_checkpoint(ckpt);
  } catch (const std::exception& e) {
    throw InputError(e.what());
  }
  check_scene_unchanged(scene_file, scene.source_text, blobs);
  return drive(scene, options, log, dir, &blobs);
}

}  // namespace mmpm
