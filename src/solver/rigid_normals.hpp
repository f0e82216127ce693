// normal = "geometry" (docs/contact_validation.md §18): before pass A, a
// rigid field's domain gradient at each multimaterial node is turned to its
// bodies' outward normal there, its length kept. Pass A's rigid normal
// (RMVG, kernels/mm_normals.hpp) then reads the faces of the shapes, not
// the staircase of their particles, and whatever else reads the gradient's
// length (the presence test, the closed area) is unchanged.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "kernels/grid_view.hpp"
#include "kernels/mm_normals.hpp"
#include "model/material.hpp"
#include "model/rigid_surface.hpp"
#include "solver/field_plan.hpp"

namespace mmpm {

struct RigidSurfaceField {
  int field = 0;
  std::size_t material = 0;  // its rigid material: the motion of the surface
  RigidSurface surface;
};

// The rigid fields some pair with normal = "geometry" reads.
std::vector<RigidSurfaceField> rigid_surface_fields(const Scene& scene, const FieldPlan& plan);

template <int D, class Real>
void orient_rigid_gradients(GridView<D, Real>& grid, const std::vector<std::uint32_t>& nodes,
                            const std::vector<RigidSurfaceField>& surfaces, const Scene& scene,
                            double time) {
  for (const RigidSurfaceField& s : surfaces) {
    // The particles moved with the material; the shapes are where they started.
    const Vec3 moved = rigid_displacement(scene.materials[s.material], time);
    for (const std::uint32_t node : nodes) {
      const std::size_t at = grid.at(s.field, node);
      double g2 = 0;
      for (int d = 0; d < D; ++d) g2 += double(grid.g[d][at]) * double(grid.g[d][at]);
      if (!(g2 > 0)) continue;  // no particle of the field reaches the node
      const std::array<Real, 3> x = grid.position(node);
      Vec3 x0{0, 0, 0};
      for (int d = 0; d < D; ++d) x0[d] = double(x[d]) - moved[d];
      const Vec3 n = s.surface.outward_normal(x0);
      const double length = std::sqrt(g2) * double(kDomainGradientOutward);
      if (n[0] != 0 || n[1] != 0 || n[2] != 0)
        for (int d = 0; d < D; ++d) grid.g[d][at] = Real(length * n[d]);
    }
  }
}

}  // namespace mmpm
