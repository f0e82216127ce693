#include "solver/boundary.hpp"

#include <algorithm>
#include <cmath>

#include "scene/error.hpp"
#include "solver/ramp.hpp"

namespace mmpm {

std::vector<BoundaryNodes> resolve_boundaries(const Scene& scene) {
  const int dim = scene.simulation.dimension;
  const auto& g = scene.grid;
  std::array<std::size_t, 3> n{1, 1, 1};
  for (int d = 0; d < dim; ++d) n[d] = std::size_t(g.cells[d]) + 1;
  const std::size_t total = n[0] * n[1] * n[2];
  std::vector<BoundaryNodes> out;
  for (const auto& spec : scene.boundaries) {
    BoundaryNodes b;
    b.label = spec.label;
    b.fix = spec.fix;
    b.displacement = spec.displacement;
    b.ramp = spec.ramp;
    b.moving = spec.has_displacement;
    int plane_index = -1;
    if (spec.kind == BoundaryWhere::plane) {
      const int ax = spec.plane_axis;
      const double k = (spec.plane_value - g.origin[ax]) / g.cell[ax];
      plane_index = int(std::lround(k));
      if (std::abs(k - plane_index) > 1e-6 || plane_index < 0 || plane_index > g.cells[ax])
        throw InputError(located(spec.where.file, spec.where.line, spec.where.key + ".where",
                                 "the plane must lie on a grid node plane inside the grid"));
      b.plane_axis = ax;
      b.plane_index = plane_index;
    }
    for (std::size_t i = 0; i < total; ++i) {
      std::array<std::size_t, 3> k{i % n[0], (i / n[0]) % n[1], i / (n[0] * n[1])};
      bool on = false;
      switch (spec.kind) {
        case BoundaryWhere::face: {
          const int ax = spec.face_axis;
          on = spec.face_max ? k[ax] == n[ax] - 1 : k[ax] == 0;
          break;
        }
        case BoundaryWhere::plane:
          on = k[spec.plane_axis] == std::size_t(plane_index);
          break;
        case BoundaryWhere::box: {
          on = true;
          for (int d = 0; d < dim; ++d) {
            const double x = g.origin[d] + double(k[d]) * g.cell[d];
            const double tol = 1e-9 * g.cell[d];
            on = on && x >= spec.box_min[d] - tol && x <= spec.box_max[d] + tol;
          }
          break;
        }
      }
      if (on) b.nodes.push_back(std::uint32_t(i));
    }
    if (b.nodes.empty())
      throw InputError(located(spec.where.file, spec.where.line, spec.where.key + ".where",
                               "no grid node lies in this boundary"));
    out.push_back(std::move(b));
  }
  return out;
}

Vec3 boundary_velocity(const BoundaryNodes& b, double t, double dt) {
  Vec3 v{0, 0, 0};
  if (!b.moving) return v;
  const double df = ramp_fraction(t + dt, b.ramp) - ramp_fraction(t, b.ramp);
  for (int d = 0; d < 3; ++d) v[d] = b.fix[d] ? b.displacement[d] * df / dt : 0.0;
  return v;
}

}  // namespace mmpm
