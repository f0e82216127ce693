#include "model/shape_surface.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

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

SurfaceDistance shape_distance(const BodySpec& b, const BodyFrame& frame, const Vec3& x, int dim) {
  switch (b.shape) {
    case BodyShape::box: {
      SurfaceDistance s = box_distance(b.min, b.max, frame.to_body(x), dim);
      s.gradient = frame.to_global(s.gradient);
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
      SurfaceDistance s = polygon_distance(b.points, frame.to_body(x));
      s.gradient = frame.to_global(s.gradient);
      return s;
    }
  }
  return {};
}

}  // namespace

SurfaceDistance body_distance(const BodySpec& body, const Vec3& x, int dim) {
  return body_distance(body, BodyFrame(body), x, dim);
}

SurfaceDistance body_distance(const BodySpec& body, const BodyFrame& frame, const Vec3& x,
                              int dim) {
  const SurfaceDistance shape = shape_distance(body, frame, x, dim);
  if (!body.clip) return shape;
  // The clip box cuts the shape: the intersection's distance is the larger.
  const SurfaceDistance clip = box_distance(body.clip->first, body.clip->second, x, dim);
  return clip.distance > shape.distance ? clip : shape;
}

Vec3 BodyMotion::to_reference(const Vec3& x) const {
  Vec3 X = C0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) X[i] += R[3 * j + i] * (x[j] - c[j]);
  return X;
}

Vec3 BodyMotion::turned(const Vec3& v) const {
  Vec3 w{0, 0, 0};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) w[i] += R[3 * i + j] * v[j];
  return w;
}

void BodyMoments::add(double mass, const Vec3& X, const Vec3& x) {
  m += mass;
  for (int i = 0; i < 3; ++i) {
    mX[i] += mass * X[i];
    mx[i] += mass * x[i];
    for (int j = 0; j < 3; ++j) mXx[3 * i + j] += mass * X[i] * x[j];
  }
}

BodyMotion BodyMoments::motion(int dim) const {
  BodyMotion out;
  if (!(m > 0)) return out;
  for (int i = 0; i < 3; ++i) out.C0[i] = mX[i] / m, out.c[i] = mx[i] / m;
  // H = Σ m (X − C0)(x − c)ᵀ, the covariance the rotation must turn X into x by.
  Eigen::Matrix3d H;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) H(i, j) = mXx[3 * i + j] - m * out.C0[i] * out.c[j];
  if (dim == 2) {
    // The angle maximising Σ m (x − c)·R(θ)(X − C0).
    const double th = std::atan2(H(0, 1) - H(1, 0), H(0, 0) + H(1, 1));
    out.R = {std::cos(th), -std::sin(th), 0, std::sin(th), std::cos(th), 0, 0, 0, 1};
    return out;
  }
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d& U = svd.matrixU();
  const Eigen::Matrix3d& V = svd.matrixV();
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
  S(2, 2) = (V * U.transpose()).determinant() < 0 ? -1.0 : 1.0;  // a rotation, not a mirror
  const Eigen::Matrix3d Rm = V * S * U.transpose();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) out.R[3 * i + j] = Rm(i, j);
  return out;
}

ShapeSurface::ShapeSurface(const Scene& scene, const std::vector<std::size_t>& materials)
    : dimension_(scene.simulation.dimension) {
  const auto ours = [&](const BodySpec& b) {
    const auto m = std::size_t(scene.material_index(b.material));
    return std::find(materials.begin(), materials.end(), m) != materials.end();
  };
  for (std::size_t k = 0; k < scene.bodies.size(); ++k) {
    const BodySpec& b = scene.bodies[k];
    if (!ours(b)) continue;
    Piece piece{&b, BodyFrame(b), {}, {}, {0, 0, 0}, 0};
    for (std::size_t later = k + 1; later < scene.bodies.size(); ++later)
      if (!ours(scene.bodies[later])) {
        piece.cuts.push_back(&scene.bodies[later]);
        piece.cut_frames.emplace_back(scene.bodies[later]);
      }
    const auto [lo, hi] = shape_bounds(b, dimension_);  // the clip only raises the distance
    for (int d = 0; d < dimension_; ++d) {
      piece.center[d] = 0.5 * (lo[d] + hi[d]);
      piece.radius += 0.25 * (hi[d] - lo[d]) * (hi[d] - lo[d]);
    }
    piece.radius = std::sqrt(piece.radius);
    pieces_.push_back(std::move(piece));
    bodies_.push_back(k);
  }
}

SurfaceDistance ShapeSurface::distance(const Vec3& x, const std::vector<BodyMotion>* motion) const {
  SurfaceDistance region;
  region.distance = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < pieces_.size(); ++k) {
    const Piece& piece = pieces_[k];
    const Vec3 X = motion != nullptr ? (*motion)[k].to_reference(x) : x;
    Vec3 r{0, 0, 0};
    for (int d = 0; d < dimension_; ++d) r[d] = X[d] - piece.center[d];
    // Cuts only raise a body's distance: one that cannot come nearer is skipped.
    if (length(r, dimension_) - piece.radius >= region.distance) continue;
    SurfaceDistance s = body_distance(*piece.body, piece.frame, X, dimension_);
    for (std::size_t j = 0; j < piece.cuts.size(); ++j) {
      const SurfaceDistance c = body_distance(*piece.cuts[j], piece.cut_frames[j], X, dimension_);
      if (-c.distance > s.distance) {  // the difference: the cut's inside turned out
        s.distance = -c.distance;
        for (int d = 0; d < 3; ++d) s.gradient[d] = -c.gradient[d];
      }
    }
    if (s.distance < region.distance) {  // the union: the nearer surface
      region = s;
      if (motion != nullptr) region.gradient = (*motion)[k].turned(s.gradient);
    }
  }
  return region;
}

}  // namespace mmpm
