#include "solver/rigid_normals.hpp"

namespace mmpm {

std::vector<RigidSurfaceField> rigid_surface_fields(const Scene& scene, const FieldPlan& plan) {
  std::vector<RigidSurfaceField> out;
  const auto F = std::size_t(plan.fields);
  for (std::size_t f = 0; f < F; ++f) {
    if (!plan.rigid[f]) continue;
    bool read = false;
    for (std::size_t o = 0; o < F; ++o) {
      const int l = plan.pair[f * F + o];
      read |= o != f && l >= 0 && plan.laws[std::size_t(l)].normal == NormalMethod::geometry;
    }
    if (read)
      out.push_back({int(f), std::size_t(plan.rigid_material[f]),
                     RigidSurface(scene, materials_in_field(plan, int(f)))});
  }
  return out;
}

}  // namespace mmpm
