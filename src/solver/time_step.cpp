#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "model/material.hpp"
#include "scene/error.hpp"
#include "scene/format.hpp"
#include "scene/interaction_warning.hpp"
#include "solver/simulation.hpp"

namespace mmpm {
namespace {

// The fastest dilatational wave among the materials, or the fastest
// prescribed motion (a body's initial velocity, a rigid material's table),
// and whose it is.
struct Fastest {
  double speed = 0;
  std::string who;
};
Fastest fastest_wave(const Scene& scene) {
  Fastest f;
  for (const auto& m : scene.materials) {
    const double c =
        make_material(m, scene.simulation.dimension, scene.simulation.plane).wave_speed;
    if (c > f.speed) f.speed = c, f.who = "the wave speed of material '" + m.name + "'";
  }
  return f;
}
Fastest fastest_motion(const Scene& scene) {
  const int dim = scene.simulation.dimension;
  const auto norm = [dim](const auto& v) {
    double v2 = 0;
    for (int d = 0; d < dim; ++d) v2 += v[d] * v[d];
    return std::sqrt(v2);
  };
  Fastest f;
  for (const auto& b : scene.bodies)
    if (const double v = norm(b.velocity); v > f.speed)
      f.speed = v, f.who = "the velocity of body '" + b.name + "'";
  for (const auto& m : scene.materials)
    for (const auto& row : m.velocity.velocity)
      if (const double v = norm(row); v > f.speed)
        f.speed = v, f.who = "the velocity of rigid material '" + m.name + "'";
  return f;
}

// The smallest cell edge over the scene's dimensions.
double smallest_cell(const Scene& scene) {
  double h = scene.grid.cell[0];
  for (int d = 1; d < scene.simulation.dimension; ++d) h = std::min(h, scene.grid.cell[d]);
  return h;
}

// The time the fastest wave (plus the fastest body) needs to cross the
// smallest cell; end_time when nothing moves or carries waves.
double wave_time_step(const Scene& scene) {
  const double speed = fastest_wave(scene).speed + fastest_motion(scene).speed;
  return speed > 0 ? smallest_cell(scene) / speed : scene.simulation.end_time;
}

}  // namespace

// ALGORITHM §2: explicit integration is stable for dt below the time a
// dilatational wave needs to cross the smallest cell (moving bodies add
// their speed), and below 2 / grid.damping (damping_time_step).
double critical_time_step(const Scene& scene) {
  return std::min(wave_time_step(scene), damping_time_step(scene));
}

double fastest_wave_speed(const Scene& scene) {
  return fastest_wave(scene).speed;
}

// USL computes the strains from the grid velocity after the momentum
// update (symplectic Euler on the grid): the fastest grid mode, which
// couples the directions, bounds its step below the wave-crossing time
// that `cfl` counts. MUSL and USF read velocities re-extrapolated from the
// particles, which damp that mode, and run to cfl = 1. Measured for 2 ms on
// bars of 25 x 1 (x 1) mm, h = 0.5 mm, 2 particles per cell and direction,
// nu = 0, one end free and one on a support plane, and both free
// (docs/validation.md §3.5, remeasured 2026-11-28 after a sweep found uGIMP
// blowing up below the 0.75 measured before): uGIMP stable at 0.55, growing
// at 0.6 on a support (2D and 3D) and at 0.65 free; quadratic B-splines
// stable at 0.7, growing at 0.75 free; linear stable at 0.75 on a support
// and free (it broke at cell crossings at any step until USL's light-node
// mass, 2026-12-06), and the block sliding on the slanted staircase of
// inputs/rotated_incline.toml (rigid or elastic floor) runs at 0.72 and
// grows at 0.75 (K + U 13 times the work done on it), hence 0.7 (0.65
// until sliding pairs took the light nodes' left-out force, when the block
// grew at 0.7); cubic B-splines stable to 1.0. In 3D a block sliding
// under Coulomb friction on a rigid floor (G = 200 mm/ms^2 tilted 30
// degrees, h = 0.5 mm, the floor of
// ValidationContact.Block3DSlidesAlongASlantOfTheFloor) lowers two of
// these: linear shapes ran it at 0.55, were off by +0.15 % in a at 0.6 and
// grew at 0.65 (as uGIMP does); cubic B-splines ran it at 0.95 and grew at
// 1.0 (a +2.5 %). A warning, not a refusal: the limit is a measurement, and
// a scene that ends within a few wave passes may finish before the mode
// grows; the energy guard (app/energy_guard.hpp) stops one that does not.
double usl_cfl_limit(ShapeKind shape, int dimension) {
  const bool three_d = dimension == 3;
  switch (shape) {
    case ShapeKind::linear:
      return three_d ? 0.55 : 0.7;
    case ShapeKind::gimp:
      return 0.55;
    case ShapeKind::bspline2:
      return 0.7;
    case ShapeKind::bspline3:
      return three_d ? 0.95 : 1.0;
  }
  return 0.55;
}

std::string usl_time_step_warning(const Scene& scene, double dt) {
  if (scene.simulation.scheme != Scheme::USL) return {};
  const double limit = usl_cfl_limit(scene.grid.shape, scene.simulation.dimension);
  const double cfl = dt / critical_time_step(scene);
  if (!(cfl > limit * (1 + 1e-12))) return {};
  const Where& w = scene.simulation.step_where;
  std::ostringstream m;
  m << scene.source_file << ": warning: key '" << (w.key.empty() ? "simulation.cfl" : w.key)
    << "': scheme \"USL\" with shape \"" << scene_name(scene.grid.shape) << "\" is "
    << "stable only to about cfl = " << limit << " (measured); this step is cfl "
    << std::setprecision(3) << cfl
    << ". Use a smaller step, or scheme \"MUSL\" (stable to cfl = 1)";
  return m.str();
}

// docs/multimaterial.md §8, "Without the force limit". The explicit
// interface force is a spring of stiffness D A_i between the two fields'
// masses; at a node the interface halves (Omega_a = Omega_b = Omega / 2,
// A_i = Omega / h_perp, m_j = rho_j Omega / 2) its frequency is
//   omega^2 = D A_i / m_red = (2 D / h) (1 / rho_a + 1 / rho_b)
// (a rigid partner: 1 / rho = 0), and the explicit step integrates it only
// while omega dt < 2. h: the smallest cell edge (the largest omega).
// Measured with force_limit = false (0.05 ms of two_layer.toml, 0.012 ms
// of sphere_in_cube.toml at 100 um): two_layer stable at D = 3e4, unstable
// at 6e4 (step 86), bound 4.3e4; sphere_in_cube stable at 3e6, unstable at
// 1e7 (step 11), bound 2.2e6. Nodes the interface cuts unevenly have other
// frequencies, so the bound is where trouble starts, not a guarantee.
std::vector<std::string> stiff_interface_warnings(const Scene& scene, double dt) {
  std::vector<std::string> out;
  const double hmin = smallest_cell(scene);
  for (std::size_t i = 0; i < scene.interactions.size(); ++i) {
    const InteractionSpec& it = scene.interactions[i];
    if (it.law != Law::interface || it.force_limit || it.integration != Integration::explicit_)
      continue;
    double inverse_density = 0;
    for (const std::string& name : it.materials) {
      const int k = scene.material_index(name);
      if (k < 0) continue;
      const MaterialSpec& m = scene.materials[std::size_t(k)];
      if (m.type != MaterialType::rigid && m.density > 0) inverse_density += 1 / m.density;
    }
    // The stiffest finite direction (perfect directions stick, no spring).
    const char* key = nullptr;
    double D = 0;
    const auto consider = [&](double value, const char* name) {
      if (std::isfinite(value) && value > D) D = value, key = name;
    };
    consider(it.Dn, "Dn");
    consider(it.Dt, "Dt");
    if (it.traction_law == TractionLaw::bilinear) consider(it.Dn_compression, "Dn_compression");
    if (!key) continue;
    const double omega_dt = std::sqrt(2 * D / hmin * inverse_density) * dt;
    if (!(omega_dt > 2)) continue;
    const double bound = 4 / (dt * dt) * hmin / (2 * inverse_density);
    std::ostringstream m;
    m.precision(3);
    m << interaction_warning(scene, i, key) << "with force_limit = false, " << key << " = " << D
      << " is stiffer than this time step integrates: omega dt = " << omega_dt
      << " at a node the interface halves (explicit integration needs < 2, so " << key
      << " below about " << bound
      << "). Expect the run to go unstable; use force_limit = true (the paper's clip), "
         "integration = \"exact\", or a smaller step";
    out.push_back(m.str());
  }
  return out;
}

// Grid damping p <- p + dt (f - alpha p) multiplies a free node's momentum
// by 1 - alpha dt each step: it grows without bound once alpha dt > 2.
double damping_time_step(const Scene& scene) {
  const double alpha = scene.grid.damping;
  return alpha > 0 ? 2.0 / alpha : std::numeric_limits<double>::infinity();
}

namespace {

// More steps than any run can take: at a microsecond per step, 1e12 steps
// are eleven days, and past 2^52 steps t + dt no longer moves t.
constexpr double kMaxSteps = 1e12;

// The message for a time step that is 0, not finite, or too small for
// end_time (huge moduli, tiny densities), named at the key that set it:
// left alone, dt = 0 ran forever and `check` printed a negative step count.
[[noreturn]] void bad_time_step(const Scene& scene, double dt, double steps) {
  const Fastest wave = fastest_wave(scene), motion = fastest_motion(scene);
  const Fastest& fastest = motion.speed > wave.speed ? motion : wave;
  std::ostringstream msg;
  msg << "the time step is " << dt;
  if (dt > 0 && std::isfinite(dt))
    msg << ", so end_time / dt = " << steps << " steps; expected at most " << kMaxSteps;
  else
    msg << "; expected a positive time step";
  if (damping_time_step(scene) < wave_time_step(scene))
    msg << " (the step follows grid.damping = " << scene.grid.damping
        << ": explicit damping needs dt < 2 / damping; check grid.damping)";
  else if (!fastest.who.empty())
    msg << " (the step follows the fastest speed, " << fastest.who << ", " << fastest.speed
        << "; check "
        << (&fastest == &motion ? "that velocity" : "that material's modulus and density") << ")";
  fail_at_time_step_key(scene, msg.str());
}

}  // namespace

void fail_at_time_step_key(const Scene& scene, const std::string& message) {
  const Where& w = scene.simulation.step_where;
  throw InputError(located(w.file.empty() ? scene.source_file : w.file, w.line,
                           w.key.empty() ? "simulation.cfl" : w.key, message));
}

void check_step_count(const Scene& scene, double dt) {
  const double steps = scene.simulation.end_time / dt;
  if (!(steps <= kMaxSteps)) bad_time_step(scene, dt, steps);
}

double end_time_tolerance(double end_time, double dt) {
  // k steps summed one by one drift from k dt by up to k roundings of half
  // an ulp of the time each: 80 000 steps of inputs/stiff_platen.toml ended
  // 6.6e-13 ms short of end_time (5e-8 of a step), past the old tolerance of
  // 1e-9 dt, and the run took one more step that short. Its reactions, an
  // impulse over that step, read 6013 N against 10.97 (found by an outside
  // review). A last step below 1e-6 of a step is dropped the same way: its
  // impulses are round-off.
  const double steps = std::ceil(end_time / dt);
  const double drift = steps * std::numeric_limits<double>::epsilon() * end_time;
  return std::min(0.01 * dt, 1e-6 * std::min(dt, end_time) + drift);
}

long planned_steps(double end_time, double dt) {
  if (!(end_time > 0)) return 0;
  const double within = end_time_tolerance(end_time, dt) / dt;
  return std::max(1L, long(std::ceil(end_time / dt - within)));
}

double stable_time_step(const Scene& scene) {
  const double dt =
      scene.simulation.dt ? *scene.simulation.dt : scene.simulation.cfl * critical_time_step(scene);
  if (!(dt > 0 && std::isfinite(dt))) bad_time_step(scene, dt, 0);
  return dt;
}

}  // namespace mmpm
