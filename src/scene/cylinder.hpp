#pragma once
// A 3D cylinder body: the disk of `radius` about the segment from `center`
// along the unit `axis` for `length` (axis [0, 0, 1] unless the scene names
// another, so that fibres can run along any direction).
#include <algorithm>
#include <cmath>
#include <utility>

#include "scene/scene.hpp"

namespace mmpm {

// Whether x lies in the cylinder (closed, like the other shapes' tests).
inline bool inside_cylinder(const BodySpec& b, const Vec3& x) {
  double along = 0, r2 = 0;
  Vec3 r{};
  for (int d = 0; d < 3; ++d) {
    r[d] = x[d] - b.center[d];
    along += r[d] * b.axis[d];
  }
  if (along < 0 || along > b.length) return false;
  for (int d = 0; d < 3; ++d) {
    const double off = r[d] - along * b.axis[d];
    r2 += off * off;
  }
  return r2 <= b.radius * b.radius;
}

// Its bounding box: the two end disks' extents, R sqrt(1 - a_d^2) about
// each end point in direction d (exact for a cylinder).
inline std::pair<Vec3, Vec3> cylinder_bounds(const BodySpec& b) {
  Vec3 lo{}, hi{};
  for (int d = 0; d < 3; ++d) {
    const double end = b.center[d] + b.length * b.axis[d];
    const double reach = b.radius * std::sqrt(std::max(0.0, 1.0 - b.axis[d] * b.axis[d]));
    lo[d] = std::min(b.center[d], end) - reach;
    hi[d] = std::max(b.center[d], end) + reach;
  }
  return {lo, hi};
}

}  // namespace mmpm
