// A rigid material's surface from its bodies' definitions (normal =
// "geometry", docs/contact_validation.md §18). Particles fill a
// grid-aligned lattice, so a face at an angle to the grid is a staircase,
// and the domain gradients of its particles turn by up to 25° from node to
// node (§4.4): enough to stop a block sliding down a rotated incline. The
// shapes themselves know their faces.
#pragma once

#include <cstddef>
#include <vector>

#include "scene/scene.hpp"

namespace mmpm {

// Signed distance to a surface (negative inside) and its gradient, the
// outward unit normal of the nearest face (zero where it has no direction).
struct SurfaceDistance {
  double distance = 0;
  Vec3 gradient{0, 0, 0};
};

// One body's shape, its clip box included, in global coordinates.
SurfaceDistance body_distance(const BodySpec& body, const Vec3& x, int dimension);

class RigidSurface {
 public:
  // The region the bodies of `materials` fill, in scene order: a later body
  // of another material takes its own volume out of it, as it takes the
  // particles (model/bodies.hpp).
  RigidSurface(const Scene& scene, const std::vector<std::size_t>& materials);

  SurfaceDistance distance(const Vec3& x) const;
  // Outward unit normal of the nearest face at x (initial configuration),
  // or zero.
  Vec3 outward_normal(const Vec3& x) const { return distance(x).gradient; }

 private:
  struct Part {
    const BodySpec* body;
    bool adds;  // a body of the material, else one that takes volume away
  };
  std::vector<Part> parts_;
  int dimension_ = 2;
};

}  // namespace mmpm
