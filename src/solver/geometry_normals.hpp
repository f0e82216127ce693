// normal = "geometry" (docs/contact_validation.md §18): before pass A, the
// domain gradient of each field a geometry pair reads is turned, at each
// multimaterial node, to the outward normal of its bodies' shapes there,
// its length kept. A rigid material's shapes move with its displacement; a
// deformable body's with the rotation and translation that fit its
// particles best (BodyMoments). Pass A's normal (RMVG against a rigid
// partner, MVG between deformable ones, kernels/mm_normals.hpp) then reads
// the faces of the shapes, not the staircase of their particles, and
// whatever reads the gradient's length (the presence test, the closed
// area) is unchanged.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "kernels/grid_view.hpp"
#include "kernels/mm_normals.hpp"
#include "kernels/particle_view.hpp"
#include "model/shape_surface.hpp"
#include "solver/field_plan.hpp"

namespace mmpm {

struct GeometryNormalField {
  int field = 0;
  int rigid_material = -1;  // moves the shapes; -1: each body by its particles' fit
  ShapeSurface surface;
  std::vector<BodyMotion> motion;  // per surface.bodies()
};

// The fields some pair with normal = "geometry" reads.
std::vector<GeometryNormalField> geometry_normal_fields(const Scene& scene, const FieldPlan& plan);

// The shapes where the bodies are at `time`: a rigid field's by its
// material's displacement. Deformable fields: fit_body_motions.
void move_rigid_shapes(std::vector<GeometryNormalField>& fields, const Scene& scene, double time);

// Deformable fields: each body's best-fit motion from its particles
// (seeded at x0, now at x + xlo), summed in particle order on one thread,
// so that 1 and 2 threads give the same bits. body_of_id: scene body of
// each particle id.
template <int D, class Real>
void fit_body_motions(std::vector<GeometryNormalField>& fields, const ParticleView<D, Real>& P,
                      const std::uint32_t* id, std::size_t n, const std::vector<int>& body_of_id,
                      std::size_t scene_bodies) {
  // Each geometry field's entry, and each of its bodies' moments (-1: none).
  std::vector<int> field_slot(256, -1);
  std::vector<int> body_slot(scene_bodies, -1);
  std::vector<BodyMoments> moments;
  for (std::size_t k = 0; k < fields.size(); ++k) {
    if (fields[k].rigid_material >= 0) continue;
    field_slot[std::size_t(fields[k].field)] = int(k);
    for (std::size_t b : fields[k].surface.bodies())
      body_slot[b] = int(moments.size()), moments.emplace_back();
  }
  if (moments.empty()) return;
  for (std::size_t p = 0; p < n; ++p) {
    if (P.field != nullptr && field_slot[P.field[p]] < 0) continue;
    const int slot = body_slot[std::size_t(body_of_id[id[p]])];
    if (slot < 0) continue;
    Vec3 X{0, 0, 0}, x{0, 0, 0};
    for (int d = 0; d < D; ++d) {
      X[d] = double(P.x0[d][p]);
      x[d] = double(P.x[d][p]) + (P.xlo[d] != nullptr ? double(P.xlo[d][p]) : 0.0);
    }
    moments[std::size_t(slot)].add(double(P.m[p]), X, x);
  }
  for (GeometryNormalField& f : fields) {
    if (f.rigid_material >= 0) continue;
    const auto& bodies = f.surface.bodies();
    for (std::size_t k = 0; k < bodies.size(); ++k)
      f.motion[k] = moments[std::size_t(body_slot[bodies[k]])].motion(D);
  }
}

// The pairs of entries of geometry_normal_fields that a geometry pair joins.
std::vector<std::array<std::size_t, 2>> geometry_normal_pairs(
    const std::vector<GeometryNormalField>& fields, const FieldPlan& plan);

// A body's outward normal at x, and whether its face is flat there: the
// normals one step along the face on either side (both tangents in 3D)
// turn by less than 30°. The step is the reach of the node's shape
// functions (half their support), so an edge or a corner whose particles
// the node sees is not flat; a curve of radius above two steps is.
struct FaceNormal {
  Vec3 n{0, 0, 0};
  bool flat = false;
  // n and the normals at the probes one step along the face: the faces of
  // an edge or a corner the node sees (orient_gradients picks among them).
  std::array<Vec3, 5> candidates{};
  int count = 0;
};
FaceNormal face_normal(const GeometryNormalField& f, const Vec3& x, double step, int dimension);

// Two edges or corners meeting at a node (two boxes end to end, at the ends
// of their shared face): each body's normal at the node is the face its
// signed distance finds nearest, which a displacement of a fraction of a
// cell switches between the shared face and the side face. Bars joined end
// to end and held at one end (so each moves by another amount) read the
// side face at the interface's end nodes of one bar, and the interface
// energy 0.0110 against 0.0200 exact (found by an outside review,
// docs/contact_validation.md §18). Where the two normals are not opposed
// (closer than 150°), each body takes the face, among those its node sees,
// of the most opposed pair: the face they share.
void take_facing_faces(FaceNormal& a, FaceNormal& b);

// At each listed node, every geometry field's gradient turns to its
// bodies' normal, its length kept. Where the two bodies of a geometry
// pair meet and one's face is flat there while the other's is an edge or a
// corner, both take the flat face's normal: the contact of an edge against
// a face acts along the face's normal (a sliding block's leading corner
// would otherwise hold it back along its side face's normal). `reach`:
// half the shape functions' support.
template <int D, class Real>
void orient_gradients(GridView<D, Real>& grid, const std::vector<std::uint32_t>& nodes,
                      const std::vector<GeometryNormalField>& fields,
                      const std::vector<std::array<std::size_t, 2>>& pairs, double reach) {
  std::vector<FaceNormal> face(fields.size());
  std::vector<double> length(fields.size());
  for (const std::uint32_t node : nodes) {
    const std::array<Real, 3> xi = grid.position(node);
    Vec3 x{0, 0, 0};
    for (int d = 0; d < D; ++d) x[d] = double(xi[d]);
    for (std::size_t k = 0; k < fields.size(); ++k) {
      const std::size_t at = grid.at(fields[k].field, node);
      double g2 = 0;
      for (int d = 0; d < D; ++d) g2 += double(grid.g[d][at]) * double(grid.g[d][at]);
      length[k] = std::sqrt(g2);
      // No particle of the field reaches the node: nothing to turn.
      face[k] = g2 > 0 ? face_normal(fields[k], x, reach, D) : FaceNormal{};
    }
    for (const auto& [a, b] : pairs) {
      if (length[a] == 0 || length[b] == 0) continue;
      if (face[a].flat != face[b].flat) {
        FaceNormal& edge = face[a].flat ? face[b] : face[a];
        const FaceNormal& flat = face[a].flat ? face[a] : face[b];
        for (int d = 0; d < 3; ++d) edge.n[d] = -flat.n[d];
      } else if (!face[a].flat) {
        take_facing_faces(face[a], face[b]);
      }
    }
    for (std::size_t k = 0; k < fields.size(); ++k) {
      const Vec3& n = face[k].n;
      if (n[0] == 0 && n[1] == 0 && n[2] == 0) continue;
      const std::size_t at = grid.at(fields[k].field, node);
      const double scale = length[k] * double(kDomainGradientOutward);
      for (int d = 0; d < D; ++d) grid.g[d][at] = Real(scale * n[d]);
    }
  }
}

}  // namespace mmpm
