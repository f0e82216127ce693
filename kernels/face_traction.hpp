// Traction loads applied at the loaded face (ALGORITHM §2 step 2, the
// external force; docs/validation.md §3.6).
//
// A traction acts on the body's boundary: its nodal force is the surface
// integral f_i = ∫_Γ N_i t dΓ, with N_i evaluated on Γ. Spreading a face
// particle's share F_p with its own weights S_ip (the particle's volume
// average) treats it as a body force on the outer particle layer: the layer
// beyond the load's point of action then carries part of the load (a bar in
// tension read 0.32 and 1.18 times the applied stress in its last two rows,
// 2 ppc uGIMP). Here F_p acts at the particle's face point x_p + o_p, through
// the grid's basis functions (grid_basis_at); o_p (set at seeding,
// src/model/bodies.cpp) runs along the face's outward normal to the edge of
// the particle's domain (on a rotated body's staircase, to the declared face
// within that domain). Sum_i w_i = 1 and Sum_i w_i x_i = the face point: the
// load's resultant and its moment are those of F_p at the face.
//
// The face point is clamped to where the particle's own stencil holds every
// node the basis reaches there, so the load only reaches nodes the particle's
// mass reaches (uGIMP and the B-splines, as seeded at any particles per cell,
// never need it; for linear shapes a face point beyond the particle's cell moves to
// the cell's edge).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "kernels/grid_update.hpp"
#include "kernels/grid_view.hpp"
#include "kernels/particle_view.hpp"
#include "kernels/shape.hpp"

namespace mmpm {

// The grid's basis functions N_base+k (k < S) along one axis at r = the face
// point's coordinate minus the stencil's base, in cells. r is first clamped
// to where the particle's stencil holds every node the basis reaches (the
// outer node's weight is 0 at the bound). Linear and uGIMP: the hats (uGIMP's
// particle weights average them over the particle's domain, so its grid
// basis is the hat). B-splines: the splines themselves, at the point, which
// is what the particles' internal forces integrate against; hats there left
// sigma_xx = 2.43 and -0.11 in a free bar's last two rows (bspline2).
template <class Shape>
void grid_basis_at(double r, double (&w)[Shape::S]) {
  if constexpr (std::is_same_v<Shape, BSpline2Shape>) {
    r = std::clamp(r, 0.5, 1.5);  // the nodes' distances r, r - 1, r - 2
    const double a = 1.5 - r, b = r - 1.0, c = r - 0.5;
    w[0] = 0.5 * a * a;
    w[1] = 0.75 - b * b;
    w[2] = 0.5 * c * c;
  } else if constexpr (std::is_same_v<Shape, BSpline3Shape>) {
    double dw[4];
    BSpline3Shape::weights(std::clamp(r, 1.0, 2.0), w, dw);
  } else {
    r = std::clamp(r, 0.0, double(Shape::S - 1));
    for (int k = 0; k < Shape::S; ++k) w[k] = std::max(0.0, 1.0 - std::abs(r - k));
  }
}

template <int D, class Shape, class Real>
struct FaceStencil {
  static constexpr int S = Shape::S;
  static constexpr int count = D == 2 ? S * S : S * S * S;
  std::size_t base = 0;                   // the particle's stencil corner, with its field's offset
  std::array<double, count> w{};          // basis weights of the face point, x fastest
  std::array<std::size_t, count> node{};  // offsets relative to base

  // False when the particle's stencil leaves the grid.
  bool build(const ParticleView<D, Real>& P, const GridView<D, Real>& G,
             const std::array<const Real*, D>& offset, std::size_t p) {
    double basis[D][S];
    int b[D];
    for (int d = 0; d < D; ++d) {
      // The particle's stencil, as the transfers find it (kernels/weights.hpp).
      const Real xi = (P.x[d][p] - G.origin[d]) * (Real(1) / G.h[d]);
      const Real l = uses_half_width<Shape> ? half_width(P, d, p) : Real(0);
      Real w1[S], d1[S];
      b[d] = Shape::eval(xi, l, w1, d1);
      if (b[d] < 0 || b[d] + S > G.nodes_per_dim[d]) return false;
      double face =
          (double(P.x[d][p]) + double(offset[d][p]) - double(G.origin[d])) / double(G.h[d]);
      grid_basis_at<Shape>(face - double(b[d]), basis[d]);
    }
    const std::size_t nx = std::size_t(G.nodes_per_dim[0]);
    const std::size_t field = P.field ? std::size_t(P.field[p]) * G.nodes : 0;
    if constexpr (D == 2) {
      base = field + std::size_t(b[0]) + nx * std::size_t(b[1]);
      int k = 0;
      for (int j = 0; j < S; ++j)
        for (int i = 0; i < S; ++i, ++k) {
          w[k] = basis[0][i] * basis[1][j];
          node[k] = std::size_t(i) + nx * std::size_t(j);
        }
    } else {
      const std::size_t nxy = nx * std::size_t(G.nodes_per_dim[1]);
      base = field + std::size_t(b[0]) + nx * std::size_t(b[1]) + nxy * std::size_t(b[2]);
      int k = 0;
      for (int l = 0; l < S; ++l)
        for (int j = 0; j < S; ++j)
          for (int i = 0; i < S; ++i, ++k) {
            w[k] = basis[0][i] * basis[1][j] * basis[2][l];
            node[k] = std::size_t(i) + nx * std::size_t(j) + nxy * std::size_t(l);
          }
    }
    return true;
  }
};

// Adds F_p (P.fext) of the listed particles at their face points to G.f, in
// list order (one thread: the sums do not depend on the thread count).
// Returns the index in the list of the first particle whose stencil leaves
// the grid, or count.
template <int D, class Shape, class Real>
std::size_t scatter_face_tractions(const ParticleView<D, Real>& P, const GridView<D, Real>& G,
                                   const std::array<const Real*, D>& offset,
                                   const std::uint32_t* list, std::size_t count) {
  FaceStencil<D, Shape, Real> st;
  for (std::size_t k = 0; k < count; ++k) {
    const std::size_t p = list[k];
    if (!st.build(P, G, offset, p)) return k;
    for (int i = 0; i < st.count; ++i) {
      if (st.w[i] == 0) continue;
      const std::size_t n = st.base + st.node[i];
      for (int d = 0; d < D; ++d) G.f[d][n] += Real(st.w[i] * double(P.fext[d][p]));
    }
  }
  return count;
}

// The power of the listed particles' face loads, Sum_p F_p . v(face point),
// v interpolated from GV.vel (the caller chooses which velocity that holds):
// the power of the nodal forces scatter_face_tractions added. With `load`
// (each particle's load index) and `factor` (per load), particle p's load
// counts factor[load[p]] times: the load of another instant of its ramp.
template <int D, class Shape, class Real>
double face_traction_power(const ParticleView<D, Real>& P, const GridView<D, Real>& G,
                           const GridVelocity<D, Real>& GV,
                           const std::array<const Real*, D>& offset, const std::uint32_t* list,
                           std::size_t count, const std::uint8_t* load = nullptr,
                           const double* factor = nullptr) {
  FaceStencil<D, Shape, Real> st;
  double power = 0;
  for (std::size_t k = 0; k < count; ++k) {
    const std::size_t p = list[k];
    if (!st.build(P, G, offset, p)) continue;  // the scatter has reported it
    const double f = load ? factor[load[p]] : 1.0;
    for (int d = 0; d < D; ++d) {
      double v = 0;
      for (int i = 0; i < st.count; ++i) v += st.w[i] * double(GV.vel[d][st.base + st.node[i]]);
      power += f * double(P.fext[d][p]) * v;
    }
  }
  return power;
}

}  // namespace mmpm
