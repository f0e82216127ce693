// Grid boundary conditions resolved to node lists (SCENE.md [[boundary]]).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "scene/scene.hpp"

namespace mmpm {

struct BoundaryNodes {
  std::string label;
  std::vector<std::uint32_t> nodes;  // ascending
  int plane_axis = -1;               // a plane { x = a }: its axis and node index along it; else -1
  long plane_index = 0;
  std::array<bool, 3> fix{false, false, false};
  Vec3 displacement{0, 0, 0};
  double ramp = 0;
  bool moving = false;
};

// The axis of a support on a grid plane that fixes the plane's normal
// component (a symmetry plane: a mirror, and where domain gradients lose
// their component across it); -1 for a box of nodes or a plane that leaves
// its normal free.
inline int symmetry_axis(const BoundaryNodes& b, int dimension) {
  const int ax = b.plane_axis;
  return ax >= 0 && ax < dimension && b.fix[std::size_t(ax)] ? ax : -1;
}

// Throws InputError when a plane does not lie on grid nodes or a boundary holds no node.
std::vector<BoundaryNodes> resolve_boundaries(const Scene& scene);

// Velocity of the fixed components over the step [t, t + dt]: the support's
// displacement follows displacement * min(t / ramp, 1), so the step velocity
// is the exact difference quotient and the final displacement is reached exactly.
Vec3 boundary_velocity(const BoundaryNodes& b, double t, double dt);

}  // namespace mmpm
