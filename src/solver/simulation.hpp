// The solver seen from outside: one object per run, built from a resolved
// scene. The templated stepper (solver/stepper.hpp) implements it for every
// (dimension, shape function, precision) instantiation; the run driver,
// tests and benchmarks use only this interface.
#pragma once

#include <array>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "io/checkpoint.hpp"
#include "io/run_writer.hpp"
#include "scene/scene.hpp"

namespace mmpm {

// A run that went unstable: names the stage, step and particle or node.
class SimulationError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Energies {
  double kinetic = 0;             // deformable particles: sum m v^2 / 2
  double strain = 0;              // state function of the stresses / F
  double interface = 0;           // sum over multimaterial nodes (ALGORITHM §3.2)
  double external_work = 0;       // tractions, gravity, moving supports, rigid materials
  double damping = 0;             // removed by grid damping
  double kinetic_unresolved = 0;  // particle KE minus the KE of the grid velocity field
};

struct StepCounters {
  long multimaterial_nodes = 0;
  long nodes_3plus = 0;
  long force_limited_nodes = 0;
  // The last step scattered mx, Omega, g with its first P2G (else apart,
  // from the tiles reaching a multimaterial node; [simulation] mm_fields_share).
  bool mm_fields_with_p2g = false;
  // Steps of this process whose P2G the previous step's fused tail had
  // already done ([simulation] fuse_step_tail).
  long p2g_from_tail = 0;
};

struct Reaction {
  std::string name;  // "y_min", "rigid:<material>"
  Vec3 force{0, 0, 0};
};

inline constexpr std::array<const char*, 7> kStageNames = {
    "sort", "p2g", "multimaterial", "grid", "g2p", "constitutive", "output"};
enum Stage {
  kStageSort,
  kStageP2G,
  kStageMultimaterial,
  kStageGrid,
  kStageG2P,
  kStageConstitutive,
  kStageOutput,
  kStageCount
};

class Simulation {
 public:
  virtual ~Simulation() = default;
  virtual void step() = 0;  // throws SimulationError
  // One step, shortened to end at t_end when a whole one would pass it: a
  // run's last step lands on its end_time (the step after stays dt()).
  virtual void step_within(double t_end) = 0;
  virtual long step_count() const = 0;
  virtual double time() const = 0;
  virtual double dt() const = 0;
  virtual std::size_t particle_count() const = 0;
  virtual std::size_t node_count() const = 0;
  virtual int field_count() const = 0;
  virtual int tile_edge() const = 0;
  virtual Energies energies() const = 0;  // evaluated now (not cached)
  // Throws the SimulationError of a run that went unstable without a
  // particle check tripping (app/energy_guard.hpp), naming `stage`, the step
  // and the fastest deformable particle (or the first with a non-finite
  // velocity); `why` says what was found.
  [[noreturn]] virtual void fail_at_fastest_particle(const char* stage,
                                                     const std::string& why) const = 0;
  virtual StepCounters counters() const = 0;
  virtual std::vector<Reaction> reactions() const = 0;  // from the last step
  // Particle quantities by name: position, displacement, velocity, stress,
  // material, mass, volume, body (components per particle, particle-major,
  // particles in seed order: a particle keeps its row for the whole run).
  virtual io::ParticleField particle_field(const std::string& name) const = 0;
  virtual io::Snapshot snapshot(const std::vector<std::string>& fields) const = 0;
  // Nodal quantities of the particles as they are now (output.grid_fields:
  // mass, momentum, velocity, force), each summed over the velocity fields
  // and, with more than one field, also per field ("velocity.<material>").
  virtual io::GridSnapshot grid_snapshot(const std::vector<std::string>& quantities) const = 0;
  // Sets a per-particle quantity (velocity: D values per particle, in seed
  // order as particle_field) — for initial conditions the scene keys cannot express.
  virtual void set_particle_field(const std::string& name, const std::vector<double>& values) = 0;
  virtual std::array<double, kStageCount> stage_seconds() const = 0;
  virtual std::array<long, kStageCount> stage_calls() const = 0;
  virtual std::vector<io::Blob> save_state() const = 0;
  virtual void load_state(const std::vector<io::Blob>& blobs) = 0;
  virtual std::string instantiation() const = 0;  // e.g. "2D gimp double"
};

// Picks the instantiation from the scene. Throws InputError for scenes the
// kernels cannot run.
std::unique_ptr<Simulation> make_simulation(const Scene& scene);

// Stable time step for the scene: cfl * min cell / (max wave speed + max body speed).
double stable_time_step(const Scene& scene);
double critical_time_step(const Scene& scene);  // the same with cfl = 1
double damping_time_step(const Scene& scene);   // 2 / grid.damping (its own limit)
double fastest_wave_speed(const Scene& scene);  // the materials' fastest dilatational wave
// The largest cfl at which USL ran the bars and sliding blocks of
// docs/validation.md §3.5 stable, per shape and dimension (1.0 for the
// cubic B-spline in 2D: MUSL's and USF's bound).
double usl_cfl_limit(ShapeKind shape, int dimension);
// `run` and `check`: a warning (one line, empty if none) when scheme = "USL"
// takes a step above usl_cfl_limit.
std::string usl_time_step_warning(const Scene& scene, double dt);
// `run` and `check`: one warning per interface with force_limit = false whose
// stiffest finite D makes omega dt > 2 at a node the interface halves
// (docs/multimaterial.md §8).
std::vector<std::string> stiff_interface_warnings(const Scene& scene, double dt);
// `run` and `check`: an end_time / dt beyond any run (1e12 steps) is bad
// input. (The library steps on past end_time for as long as it is asked.)
void check_step_count(const Scene& scene, double dt);
// How close to end_time a run counts as there: the rounding of the summed
// steps (their count times end_time's epsilon) plus 1e-6 of a step, or of
// end_time when that is shorter, at most 1 % of a step. With the step
// alone, an end_time below the tolerance ended before the first step (0
// steps, reported as a finished run).
double end_time_tolerance(double end_time, double dt);
// The steps a run to end_time takes (the last one shortened to land on it):
// at least one for any end_time > 0.
long planned_steps(double end_time, double dt);
// An InputError at the key that set the time step (simulation.dt or .cfl).
[[noreturn]] void fail_at_time_step_key(const Scene& scene, const std::string& message);

}  // namespace mmpm
