// Bodies → particles: each body fills the grid-aligned lattice of
// particles_per_cell^D points per cell that lie inside its shape. Where
// bodies overlap, the later body replaces the earlier one's particles.
#pragma once

#include <array>
#include <utility>
#include <vector>

#include "scene/scene.hpp"

namespace mmpm {

struct ParticleSeeds {
  std::vector<Vec3> x;
  std::vector<Vec3> v;
  std::vector<double> volume;    // area * thickness in 2D
  std::vector<Vec3> half_width;  // uGIMP half-width in cell units per direction
  std::vector<int> material;
  std::vector<int> body;
  std::vector<Vec3> traction_force;  // external force on the particle (before the ramp)
  std::vector<int> load;             // index of the traction load acting on it, or -1
  // Loaded particles: from the particle to the edge of its domain along the
  // face's outward normal, where the load acts (kernels/face_traction.hpp).
  std::vector<Vec3> traction_offset;
};

// Throws InputError when a body holds no particle or a traction load has
// no particle on its face.
ParticleSeeds make_particles(const Scene& scene);

// A body's turn by `rotate` degrees about its pivot, or its centre (2D; the
// identity when rotate = 0), its sine and cosine computed once: global →
// body frame for points, body → global for vectors.
struct BodyFrame {
  explicit BodyFrame(const BodySpec& b);
  Vec3 to_body(const Vec3& x) const;
  Vec3 to_global(const Vec3& v) const;
  bool turned = false;
  double cos_a = 1, sin_a = 0;
  Vec3 origin{0, 0, 0};
};

// The bounding box of a body in global coordinates, within its clip box.
std::pair<Vec3, Vec3> body_bounds(const BodySpec& b, int dimension);

// The bounding box of a body's shape, its clip box left out.
std::pair<Vec3, Vec3> shape_bounds(const BodySpec& b, int dimension);

// Whether (x, y) lies inside the polygon (even–odd rule).
bool inside_polygon(const std::vector<Vec3>& points, double x, double y);

// Whether point x lies inside body b (in global coordinates).
bool inside_body(const BodySpec& b, const Vec3& x, int dimension);

}  // namespace mmpm
