#include <algorithm>
#include <cmath>

#include "model/material.hpp"
#include "solver/simulation.hpp"

namespace mmpm {

// ALGORITHM §2: explicit integration is stable for dt below the time a
// dilatational wave needs to cross the smallest cell (moving bodies add their speed).
double critical_time_step(const Scene& scene) {
  const int dim = scene.simulation.dimension;
  double hmin = scene.grid.cell[0];
  for (int d = 1; d < dim; ++d) hmin = std::min(hmin, scene.grid.cell[d]);
  double c = 0;
  for (const auto& m : scene.materials)
    c = std::max(c, make_material(m, dim, scene.simulation.plane).wave_speed);
  double vmax = 0;
  for (const auto& b : scene.bodies) {
    double v2 = 0;
    for (int d = 0; d < dim; ++d) v2 += b.velocity[d] * b.velocity[d];
    vmax = std::max(vmax, std::sqrt(v2));
  }
  for (const auto& m : scene.materials)
    for (const auto& v : m.velocity.velocity) {
      double v2 = 0;
      for (int d = 0; d < dim; ++d) v2 += v[d] * v[d];
      vmax = std::max(vmax, std::sqrt(v2));
    }
  const double speed = c + vmax;
  return speed > 0 ? hmin / speed : scene.simulation.end_time;
}

double stable_time_step(const Scene& scene) {
  if (scene.simulation.dt) return *scene.simulation.dt;
  return scene.simulation.cfl * critical_time_step(scene);
}

}  // namespace mmpm
