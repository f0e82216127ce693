#include "solver/field_plan.hpp"

#include <algorithm>

#include "scene/error.hpp"

namespace mmpm {

FieldPlan plan_fields(const Scene& scene) {
  FieldPlan plan;
  const std::size_t nm = scene.materials.size();
  std::vector<bool> named(nm, false);
  for (const auto& it : scene.interactions)
    for (const auto& n : it.materials) {
      const int m = scene.material_index(n);
      if (m >= 0) named[std::size_t(m)] = true;
    }
  for (std::size_t m = 0; m < nm; ++m)
    if (scene.materials[m].type == MaterialType::rigid) named[m] = true;

  // Field 0 is shared by every material named nowhere (if any such exists).
  plan.field_of_material.assign(nm, -1);
  int next = 0;
  bool shared = false;
  for (std::size_t m = 0; m < nm; ++m)
    if (!named[m]) {
      plan.field_of_material[m] = 0;
      shared = true;
    }
  if (shared) next = 1;
  for (std::size_t m = 0; m < nm; ++m)
    if (named[m]) plan.field_of_material[m] = next++;
  plan.fields = std::max(1, next);
  if (plan.fields > 255)
    throw InputError(located(scene.source_file, 0, "material", "at most 255 material fields"));
  plan.rigid.assign(std::size_t(plan.fields), 0);
  plan.rigid_material.assign(std::size_t(plan.fields), -1);
  for (std::size_t m = 0; m < nm; ++m)
    if (scene.materials[m].type == MaterialType::rigid) {
      plan.rigid[std::size_t(plan.field_of_material[m])] = 1;
      plan.rigid_material[std::size_t(plan.field_of_material[m])] = int(m);
    }
  plan.multimaterial = plan.fields > 1;
  const std::size_t F = std::size_t(plan.fields);
  plan.pair.assign(F * F, -1);
  if (!plan.multimaterial) return plan;

  // Separation method: one for the whole scene (mx holds one kind of data).
  Separation method = Separation::displacement;
  bool any = false;
  for (const auto& it : scene.interactions) {
    if (any && it.separation != method)
      throw InputError(located(it.where.file, it.where.line, "separation",
                               "every interaction of a scene must use the same separation method"));
    method = it.separation;
    any = true;
  }
  plan.position_separation = method == Separation::position;
  plan.extrapolated_separation = method == Separation::extrapolated;
  for (const auto& it : scene.interactions) {
    const int a = plan.field_of_material[std::size_t(scene.material_index(it.materials[0]))];
    const int b = plan.field_of_material[std::size_t(scene.material_index(it.materials[1]))];
    const int law = int(plan.laws.size());
    plan.laws.push_back(it);
    plan.pair[std::size_t(a) * F + std::size_t(b)] = law;
    plan.pair[std::size_t(b) * F + std::size_t(a)] = law;
  }
  // Pairs with no interaction of their own: the default law.
  int default_law = -1;
  for (std::size_t a = 0; a < F; ++a)
    for (std::size_t b = 0; b < F; ++b) {
      if (a == b || plan.pair[a * F + b] >= 0) continue;
      if (scene.simulation.default_law == Law::separate) continue;
      if (default_law < 0) {
        InteractionSpec d;
        d.law = scene.simulation.default_law;
        d.separation = method;
        d.normal = NormalMethod::mvg;
        d.materials = {"*", "*"};
        default_law = int(plan.laws.size());
        plan.laws.push_back(d);
      }
      plan.pair[a * F + b] = default_law;
    }
  // A pair with a rigid field and the "rigid" normal method is fine; the
  // same method between two deformable fields has no rigid gradient to use.
  for (std::size_t a = 0; a < F; ++a)
    for (std::size_t b = 0; b < F; ++b) {
      const int l = plan.pair[a * F + b];
      if (l < 0 || a == b) continue;
      if (plan.laws[std::size_t(l)].normal == NormalMethod::rigid && !plan.rigid[a] &&
          !plan.rigid[b]) {
        const auto& w = plan.laws[std::size_t(l)].where;
        throw InputError(
            located(w.file, w.line, "normal", "\"rigid\" needs one rigid material in the pair"));
      }
    }
  return plan;
}

}  // namespace mmpm
