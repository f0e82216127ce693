#include "solver/geometry_normals.hpp"

#include <cmath>

#include "model/material.hpp"

namespace mmpm {

namespace {
double dot(const Vec3& u, const Vec3& v) {
  return u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
}
// Normals closer than 30 degrees are one face (face_normal); a pair farther
// than 150 degrees apart faces each other (take_facing_faces).
const double kCos30 = std::sqrt(3.0) / 2;
}  // namespace

std::vector<GeometryNormalField> geometry_normal_fields(const Scene& scene, const FieldPlan& plan) {
  std::vector<GeometryNormalField> out;
  const auto F = std::size_t(plan.fields);
  for (std::size_t f = 0; f < F; ++f) {
    bool read = false;
    for (std::size_t o = 0; o < F; ++o) {
      const int l = plan.pair[f * F + o];
      read |= o != f && l >= 0 && plan.laws[std::size_t(l)].normal == NormalMethod::geometry;
    }
    if (!read) continue;
    GeometryNormalField g{int(f),
                          plan.rigid[f] ? plan.rigid_material[f] : -1,
                          ShapeSurface(scene, materials_in_field(plan, int(f))),
                          {}};
    g.motion.resize(g.surface.bodies().size());
    out.push_back(std::move(g));
  }
  return out;
}

void move_rigid_shapes(std::vector<GeometryNormalField>& fields, const Scene& scene, double time) {
  for (GeometryNormalField& f : fields) {
    if (f.rigid_material < 0) continue;
    // The particles moved with the material; the shapes are where they started.
    const Vec3 u = rigid_displacement(scene.materials[std::size_t(f.rigid_material)], time);
    for (BodyMotion& m : f.motion) m.c = u, m.C0 = {0, 0, 0};
  }
}

std::vector<std::array<std::size_t, 2>> geometry_normal_pairs(
    const std::vector<GeometryNormalField>& fields, const FieldPlan& plan) {
  std::vector<std::array<std::size_t, 2>> out;
  const auto F = std::size_t(plan.fields);
  for (std::size_t a = 0; a < fields.size(); ++a)
    for (std::size_t b = a + 1; b < fields.size(); ++b) {
      const int l = plan.pair[std::size_t(fields[a].field) * F + std::size_t(fields[b].field)];
      if (l >= 0 && plan.laws[std::size_t(l)].normal == NormalMethod::geometry)
        out.push_back({a, b});
    }
  return out;
}

FaceNormal face_normal(const GeometryNormalField& f, const Vec3& x, double step, int dim) {
  FaceNormal out;
  out.n = f.surface.distance(x, &f.motion).gradient;
  if (out.n[0] == 0 && out.n[1] == 0 && out.n[2] == 0) return out;
  // Tangents of the face: the interface's fixed perpendicular of n
  // (kernels/mm_normals.hpp), and in 3D n × it.
  std::array<Vec3, 2> t{};
  int tangents = 1;
  if (dim == 2) {
    const VecD<2, double> t2 =
        tangent_or_perpendicular<2, double>({0, 0}, 0.0, {out.n[0], out.n[1]});
    t[0] = {t2[0], t2[1], 0};
  } else {
    t[0] = tangent_or_perpendicular<3, double>({0, 0, 0}, 0.0, out.n);
    t[1] = {out.n[1] * t[0][2] - out.n[2] * t[0][1], out.n[2] * t[0][0] - out.n[0] * t[0][2],
            out.n[0] * t[0][1] - out.n[1] * t[0][0]};
    tangents = 2;
  }
  out.flat = true;
  out.candidates[0] = out.n;
  out.count = 1;
  for (int k = 0; k < tangents; ++k)
    for (const double side : {-step, step}) {
      Vec3 probe = x;
      for (int d = 0; d < 3; ++d) probe[d] += side * t[std::size_t(k)][d];
      const Vec3 m = f.surface.distance(probe, &f.motion).gradient;
      if (dot(m, out.n) < kCos30) out.flat = false;
      if (m[0] != 0 || m[1] != 0 || m[2] != 0) out.candidates[std::size_t(out.count++)] = m;
    }
  return out;
}

void take_facing_faces(FaceNormal& a, FaceNormal& b) {
  if (dot(a.n, b.n) <= -kCos30) return;  // already facing
  double best = -kCos30;
  int ia = -1, ib = -1;
  for (int i = 0; i < a.count; ++i)
    for (int j = 0; j < b.count; ++j) {
      const double c = dot(a.candidates[std::size_t(i)], b.candidates[std::size_t(j)]);
      if (c < best) best = c, ia = i, ib = j;
    }
  if (ia < 0) return;  // no pair of faces faces the other: leave both
  a.n = a.candidates[std::size_t(ia)];
  b.n = b.candidates[std::size_t(ib)];
}

}  // namespace mmpm
