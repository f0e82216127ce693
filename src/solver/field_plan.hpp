// Which material velocity fields exist and how each pair of fields interacts
// (ALGORITHM §1; SCENE.md: materials named in no interaction share one
// field; rigid materials always have their own; a pair without an
// interaction of its own uses [simulation] default_law).
#pragma once

#include <vector>

#include "scene/scene.hpp"

namespace mmpm {

struct FieldPlan {
  int fields = 1;
  std::vector<int> field_of_material;    // per material
  std::vector<unsigned char> rigid;      // per field
  std::vector<int> rigid_material;       // per field: material index, or -1
  std::vector<InteractionSpec> laws;     // the distinct interactions in use
  std::vector<int> pair;                 // fields x fields → index into laws, -1 = none
  bool multimaterial = false;            // a multimaterial pass exists
  bool position_separation = false;      // mx holds positions (else displacements)
  bool extrapolated_separation = false;  // mx moved from the centroid to the node
};

FieldPlan plan_fields(const Scene& scene);

// The materials (indices into scene.materials) whose particles move with
// `field`, in scene order.
inline std::vector<std::size_t> materials_in_field(const FieldPlan& plan, int field) {
  std::vector<std::size_t> out;
  for (std::size_t m = 0; m < plan.field_of_material.size(); ++m)
    if (plan.field_of_material[m] == field) out.push_back(m);
  return out;
}

// Whether some interaction computes its normal from the domain gradients
// g_i (P-33: mvg, avg, rigid) or reads an interface's area from them (the
// closed and gradient areas, docs/multimaterial.md §7.1, §7.2). Only then does
// P2G scatter g.
inline bool needs_domain_gradient(const FieldPlan& plan) {
  for (const InteractionSpec& it : plan.laws)
    if (it.normal == NormalMethod::mvg || it.normal == NormalMethod::avg ||
        it.normal == NormalMethod::rigid || it.normal == NormalMethod::geometry ||
        (it.law == Law::interface && it.area != ContactArea::paper))
      return true;
  return false;
}

}  // namespace mmpm
