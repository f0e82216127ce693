#include "model/rigid_surface.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "model/bodies.hpp"

namespace mmpm {
namespace {

double length(const Vec3& v, int dim) {
  double s = 0;
  for (int d = 0; d < dim; ++d) s += v[d] * v[d];
  return std::sqrt(s);
}

// An axis-aligned box [lo, hi] in the coordinates of u: outside, the
// distance to its nearest point (its gradient turns round edges and
// corners); inside, minus the distance to the nearest face.
SurfaceDistance box_distance(const Vec3& lo, const Vec3& hi, const Vec3& u, int dim) {
  Vec3 q{}, side{}, out{};
  bool outside = false;
  int nearest = 0;
  for (int d = 0; d < dim; ++d) {
    const double c = 0.5 * (lo[d] + hi[d]);
    side[d] = u[d] < c ? -1.0 : 1.0;
    q[d] = std::abs(u[d] - c) - 0.5 * (hi[d] - lo[d]);
    out[d] = side[d] * std::max(q[d], 0.0);
    outside |= q[d] > 0;
    if (q[d] > q[nearest]) nearest = d;
  }
  SurfaceDistance s;
  if (outside) {
    s.distance = length(out, dim);
    for (int d = 0; d < dim; ++d) s.gradient[d] = out[d] / s.distance;
  } else {
    s.distance = q[nearest];
    s.gradient[nearest] = side[nearest];
  }
  return s;
}

// A polygon (body frame): the nearest point of its edges.
SurfaceDistance polygon_distance(const std::vector<Vec3>& pts, const Vec3& u) {
  double best = std::numeric_limits<double>::infinity();
  Vec3 near{};
  for (std::size_t i = 0, j = pts.size() - 1; i < pts.size(); j = i++) {
    const double ex = pts[i][0] - pts[j][0], ey = pts[i][1] - pts[j][1];
    const double e2 = ex * ex + ey * ey;
    double t = e2 > 0 ? ((u[0] - pts[j][0]) * ex + (u[1] - pts[j][1]) * ey) / e2 : 0.0;
    t = std::clamp(t, 0.0, 1.0);
    const double px = pts[j][0] + t * ex, py = pts[j][1] + t * ey;
    const double d = std::hypot(u[0] - px, u[1] - py);
    if (d < best) best = d, near = {px, py, 0};
  }
  const double sign = inside_polygon(pts, u[0], u[1]) ? -1.0 : 1.0;
  SurfaceDistance s;
  s.distance = sign * best;
  if (best > 0)
    for (int d = 0; d < 2; ++d) s.gradient[d] = sign * (u[d] - near[d]) / best;
  return s;
}

// The cylinder of model/bodies (scene/cylinder.hpp) as a rectangle in its
// (radial, axial) plane.
SurfaceDistance cylinder_distance(const BodySpec& b, const Vec3& x) {
  Vec3 r{};
  double along = 0;
  for (int d = 0; d < 3; ++d) {
    r[d] = x[d] - b.center[d];
    along += r[d] * b.axis[d];
  }
  Vec3 radial{};
  for (int d = 0; d < 3; ++d) radial[d] = r[d] - along * b.axis[d];
  const double rho = length(radial, 3);
  const SurfaceDistance plane =
      box_distance({-b.radius, 0, 0}, {b.radius, b.length, 0}, {rho, along, 0}, 2);
  SurfaceDistance s;
  s.distance = plane.distance;
  for (int d = 0; d < 3; ++d)
    s.gradient[d] =
        (rho > 0 ? plane.gradient[0] * radial[d] / rho : 0.0) + plane.gradient[1] * b.axis[d];
  return s;
}

SurfaceDistance shape_distance(const BodySpec& b, const Vec3& x, int dim) {
  switch (b.shape) {
    case BodyShape::box: {
      SurfaceDistance s = box_distance(b.min, b.max, to_body_frame(b, x), dim);
      s.gradient = rotate_vector(b, s.gradient);
      return s;
    }
    case BodyShape::disk:
    case BodyShape::sphere: {
      Vec3 r{};
      for (int d = 0; d < dim; ++d) r[d] = x[d] - b.center[d];
      const double l = length(r, dim);
      SurfaceDistance s;
      s.distance = l - b.radius;
      if (l > 0)
        for (int d = 0; d < dim; ++d) s.gradient[d] = r[d] / l;
      return s;
    }
    case BodyShape::cylinder:
      return cylinder_distance(b, x);
    case BodyShape::polygon: {
      SurfaceDistance s = polygon_distance(b.points, to_body_frame(b, x));
      s.gradient = rotate_vector(b, s.gradient);
      return s;
    }
  }
  return {};
}

}  // namespace

SurfaceDistance body_distance(const BodySpec& body, const Vec3& x, int dim) {
  const SurfaceDistance shape = shape_distance(body, x, dim);
  if (!body.clip) return shape;
  // The clip box cuts the shape: the intersection's distance is the larger.
  const SurfaceDistance clip = box_distance(body.clip->first, body.clip->second, x, dim);
  return clip.distance > shape.distance ? clip : shape;
}

RigidSurface::RigidSurface(const Scene& scene, const std::vector<std::size_t>& materials)
    : dimension_(scene.simulation.dimension) {
  bool started = false;
  for (const BodySpec& b : scene.bodies) {
    const auto m = std::size_t(scene.material_index(b.material));
    const bool adds = std::find(materials.begin(), materials.end(), m) != materials.end();
    // A body of another material before the first of ours takes nothing away.
    if (adds || started) parts_.push_back({&b, adds});
    started |= adds;
  }
}

SurfaceDistance RigidSurface::distance(const Vec3& x) const {
  SurfaceDistance region;
  region.distance = std::numeric_limits<double>::infinity();
  for (const Part& part : parts_) {
    const SurfaceDistance s = body_distance(*part.body, x, dimension_);
    if (part.adds) {
      if (s.distance < region.distance) region = s;  // union: the nearer surface
    } else if (-s.distance > region.distance) {      // difference: the body's inside turned out
      region.distance = -s.distance;
      for (int d = 0; d < 3; ++d) region.gradient[d] = -s.gradient[d];
    }
  }
  return region;
}

}  // namespace mmpm
