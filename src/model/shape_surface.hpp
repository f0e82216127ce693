// A material's surface from its bodies' definitions (normal = "geometry",
// docs/contact_validation.md §18). Particles fill a grid-aligned lattice,
// so a face at an angle to the grid is a staircase, and the domain
// gradients of its particles turn by up to 25° from node to node (§4.4):
// enough to stop a block sliding down a rotated incline. The shapes
// themselves know their faces; each body carries them along with its
// motion (a rigid material's displacement, or a deformable body's best-fit
// rotation and translation, BodyMoments).
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include "model/bodies.hpp"
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
SurfaceDistance body_distance(const BodySpec& body, const BodyFrame& frame, const Vec3& x,
                              int dimension);

// Where a body has gone: x = c + R (X − C0) for X where it was seeded.
struct BodyMotion {
  std::array<double, 9> R{1, 0, 0, 0, 1, 0, 0, 0, 1};  // row-major
  Vec3 c{0, 0, 0}, C0{0, 0, 0};
  Vec3 to_reference(const Vec3& x) const;  // X = C0 + Rᵀ (x − c)
  Vec3 turned(const Vec3& v) const;        // R v
};

// Mass-weighted sums over a body's particles, seeded at X, now at x; the
// motion that fits them best (least squares: Kabsch, closed form in 2D).
struct BodyMoments {
  double m = 0;
  Vec3 mX{0, 0, 0}, mx{0, 0, 0};
  std::array<double, 9> mXx{};  // Σ m X xᵀ, row-major
  void add(double mass, const Vec3& X, const Vec3& x);
  BodyMotion motion(int dimension) const;
};

class ShapeSurface {
 public:
  // The region the bodies of `materials` fill: each body less the later
  // bodies of other materials, which took their own volume out of it, as
  // they took its particles (model/bodies.hpp). It points into
  // scene.bodies, which must outlive it.
  ShapeSurface(const Scene& scene, const std::vector<std::size_t>& materials);

  // Scene indices of the bodies that fill it, in scene order.
  const std::vector<std::size_t>& bodies() const { return bodies_; }

  // At x, each body where it was seeded, or moved by motion[k] (one per
  // bodies()).
  SurfaceDistance distance(const Vec3& x, const std::vector<BodyMotion>* motion = nullptr) const;

 private:
  struct Piece {
    const BodySpec* body;
    BodyFrame frame;
    std::vector<const BodySpec*> cuts;
    std::vector<BodyFrame> cut_frames;
    Vec3 center{0, 0, 0};  // of a sphere holding the body: distance ≥ |X − center| − radius
    double radius = 0;
  };
  std::vector<Piece> pieces_;
  std::vector<std::size_t> bodies_;
  int dimension_ = 2;
};

}  // namespace mmpm
