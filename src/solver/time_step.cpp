#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <string>

#include "model/material.hpp"
#include "scene/error.hpp"
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

}  // namespace

// ALGORITHM §2: explicit integration is stable for dt below the time a
// dilatational wave needs to cross the smallest cell (moving bodies add
// their speed), and below 2 / grid.damping (damping_time_step).
double critical_time_step(const Scene& scene) {
  const int dim = scene.simulation.dimension;
  double hmin = scene.grid.cell[0];
  for (int d = 1; d < dim; ++d) hmin = std::min(hmin, scene.grid.cell[d]);
  const double speed = fastest_wave(scene).speed + fastest_motion(scene).speed;
  const double wave = speed > 0 ? hmin / speed : scene.simulation.end_time;
  return std::min(wave, damping_time_step(scene));
}

// USL computes the strains from the grid velocity after the momentum
// update (symplectic Euler on the grid): the fastest grid mode, which
// couples the directions, bounds its step below the wave-crossing time
// that `cfl` counts. MUSL and USF read velocities re-extrapolated from the
// particles, which damp that mode, and run to cfl = 1. Measured for 2 ms on
// bars of 25 x 1 (x 1) mm, h = 0.5 mm, nu = 0 (docs/validation.md §3.5):
// USL stable at cfl 0.75 in 2D (uGIMP, linear) and 3D (uGIMP), unstable at
// 0.78 (2D uGIMP, step 412) and 0.8 (2D linear, 3D uGIMP); MUSL and USF
// stable at 1.0. A warning, not a refusal: the limit is a measurement, and
// a scene that ends within a few wave passes may finish before the mode
// grows.
constexpr double kUslCflLimit = 0.75;

std::string usl_time_step_warning(const Scene& scene, double dt) {
  if (scene.simulation.scheme != Scheme::USL) return {};
  const double limit = kUslCflLimit;
  const double cfl = dt / critical_time_step(scene);
  if (!(cfl > limit * (1 + 1e-12))) return {};
  const Where& w = scene.simulation.step_where;
  std::ostringstream m;
  m << scene.source_file << ": warning: key '" << (w.key.empty() ? "simulation.cfl" : w.key)
    << "': scheme \"USL\" is "
    << "stable only to about cfl = " << limit << " (measured); this step is cfl "
    << std::setprecision(3) << cfl
    << ". Use a smaller step, or scheme \"MUSL\" (stable to cfl = 1)";
  return m.str();
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
  if (!fastest.who.empty())
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

double stable_time_step(const Scene& scene) {
  const double dt =
      scene.simulation.dt ? *scene.simulation.dt : scene.simulation.cfl * critical_time_step(scene);
  if (!(dt > 0 && std::isfinite(dt))) bad_time_step(scene, dt, 0);
  return dt;
}

}  // namespace mmpm
