// Each material's displacement at the node itself, not at its particles'
// mass centroid (separation = "extrapolated"; docs/interface_validation.md,
// "The stiff-interface bias" and "Extrapolated separation").
//
// The paper's δ = x_b − x_a (P-11, P-13) takes x_j = mx_j / m_j, the
// S m-weighted mean displacement of material j's particles around the node.
// Those particles sit on their own side of the interface: with 2 particles
// per cell their centroid lies 3h/8 from it, so δ also holds the strain of
// two 3h/8 layers, and the interface acts stiffer than D (first order in h).
// Here each field's displacement is extrapolated from its centroid to the
// node with the S m-weighted least-squares gradient of its particles'
// displacements:
//
//   r_p = (x_p − x_i) / h          (cell units),   w_p = S_ip m_p
//   R   = Σ w r,   RR = Σ w r rᵀ,   UR = Σ w (u_p − ū) rᵀ,   ū = mx / m
//   C   = RR − R Rᵀ / m             (the centroid's second moment)
//   B   = UR C⁺                     (the gradient, per cell)
//   m u(x_i) = mx − B R             (exact for a displacement linear in x)
//
// The particles must spread in every direction: with the least eigenvalue
// of C / m below kSpreadNone (cell²) the field keeps the paper's centroid,
// above kSpreadFull it gets the full extrapolation, linearly between. With 2
// or more particles per cell the spread is ≥ 0.047 cell² (uGIMP, 2 per
// cell, the normal of an interface on a grid line); with 1 per cell the
// particles of one side form a single row whose spread is only their
// strain. Extrapolating along the other directions alone did harm there:
// the sphere in a cube at 1 particle per cell and D = 1e6 MPa/mm went from
// the centroid's slow creep to a blow-up. The same holds where a material
// reaches a node through one row of its particles whatever the seeding: an
// interface on a cell midplane (each node sees the far side's nearest row
// only, 0.75 cell away) keeps the centroid's bias.
//
// The moments are scattered like mx (kernels/p2g_multimaterial.hpp): only by
// the tiles that reach a multimaterial node, color by color, so the sums and
// their order do not depend on the thread count; and only by the particles
// whose stencil holds a multimaterial node, into those nodes alone (a tile
// is up to 64 cells wide, an interface's nodes 2-4). mx is corrected in
// place at the multimaterial nodes, each node on its own.
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "kernels/binning.hpp"
#include "kernels/p2g_multimaterial.hpp"
#include "kernels/position_sum.hpp"
#include "kernels/weights.hpp"

namespace mmpm {

inline constexpr double kSpreadNone = 0.005;  // cell²
inline constexpr double kSpreadFull = 0.01;   // cell²
// The farthest the node is extrapolated to from the centroid along each
// principal direction of the particles' spread, in standard deviations of
// it. A side of a plane interface seeded 2 per cell lies sqrt(3) from its
// centroid (linear, uGIMP; 1.57 bspline2, 1.51 bspline3), in every direction
// at an edge or corner of the interface too. Particles cut by a curved
// surface can leave a node far from a small spread; the extrapolated δ then
// weighs some particles by large negative factors, a spring that pushes
// some modes apart: without the cap the sphere in a cube at 100 µm and
// D = 1e5 MPa/mm never settled (K from energy 23 600 against 3 260; a cap
// on the total distance instead of each direction's, 3: 5 290). With it, it
// does (docs/interface_validation.md, "Extrapolated separation").
inline constexpr double kMaxExtrapolation = 1.75;

// Per field and node, like GridView's arrays ([f * nodes + i]).
template <int D, class Real>
struct SeparationMoments {
  static constexpr int kSym = D * (D + 1) / 2;  // xx, xy, (xz,) yy, (yz, zz)
  std::array<Real*, D> r{};
  std::array<Real*, kSym> rr{};
  std::array<Real*, D * D> ur{};  // row-major: [a * D + b] = Σ w (u_a − ū_a) r_b
  bool enabled() const { return r[0] != nullptr; }
};

namespace separation_detail {

template <int D>
constexpr int sym_index(int a, int b) {
  if (a > b) std::swap(a, b);
  // Upper triangle row by row: (0,0) (0,1) (0,2) (1,1) (1,2) (2,2).
  return a * D - a * (a - 1) / 2 + (b - a);
}

// Adds particles [b, e) into the moments. Returns the first particle whose
// stencil left the grid, or SIZE_MAX.
template <int D, class Shape, class Real>
std::size_t scatter_moments(const ParticleView<D, Real>& P, const GridView<D, Real>& G,
                            const SeparationMoments<D, Real>& M, const std::uint8_t* listed,
                            std::size_t b, std::size_t e) {
  const std::array<Real, 3> inv_h{Real(1) / G.h[0], Real(1) / G.h[1], Real(1) / G.h[2]};
  const std::size_t nx = std::size_t(G.nodes_per_dim[0]), ny = std::size_t(G.nodes_per_dim[1]);
  Stencil<D, Shape, Real> st{};
  for (std::size_t p = b; p < e; ++p) {
    if (!st.build(P, G, inv_h, p)) return p;
    // Most particles of a reaching tile reach no multimaterial node: skip them.
    bool reaches = false;
    for (int k = 0; k < st.count; ++k) reaches |= listed[st.base + st.node[k]] != 0;
    if (!reaches) continue;
    const std::size_t fo = std::size_t(P.field[p]) * G.nodes;
    const Real mp = P.m[p];
    Real xi[D], u[D];
    int corner[D];
    for (int d = 0; d < D; ++d) {
      xi[d] = (P.x[d][p] - G.origin[d]) * inv_h[d];
      u[d] = separation_coordinate(P, false, d, p);
    }
    corner[0] = int(st.base % nx);
    corner[1] = int((st.base / nx) % ny);
    if constexpr (D == 3) corner[2] = int(st.base / (nx * ny));
    constexpr int S = Shape::S;
    for (int k = 0; k < st.count; ++k) {
      const Real w = st.w[k] * mp;
      if (w == Real(0) || !listed[st.base + st.node[k]]) continue;  // only listed nodes are read
      const std::size_t i = fo + st.base + st.node[k];
      if (!(G.m[i] > Real(0))) continue;
      const int offset[3] = {k % S, (k / S) % S, k / (S * S)};
      Real r[D], du[D];
      for (int d = 0; d < D; ++d) {
        r[d] = xi[d] - Real(corner[d] + offset[d]);
        du[d] = u[d] - G.mx[d][i] / G.m[i];
      }
      for (int a = 0; a < D; ++a) {
        M.r[a][i] += w * r[a];
        for (int c = a; c < D; ++c) M.rr[std::size_t(sym_index<D>(a, c))][i] += w * r[a] * r[c];
        for (int c = 0; c < D; ++c) M.ur[std::size_t(a * D + c)][i] += w * du[a] * r[c];
      }
    }
  }
  return SIZE_MAX;
}

// Eigenvalues (into c's diagonal) and eigenvectors (columns of v) of the
// symmetric c by cyclic Jacobi rotations; D <= 3 converges in a few sweeps.
template <int D>
void symmetric_eigen(double (&c)[D][D], double (&v)[D][D]) {
  for (int a = 0; a < D; ++a)
    for (int b = 0; b < D; ++b) v[a][b] = a == b ? 1.0 : 0.0;
  for (int sweep = 0; sweep < 16; ++sweep) {
    double off = 0, diag = 0;
    for (int a = 0; a < D; ++a) {
      diag += c[a][a] * c[a][a];
      for (int b = a + 1; b < D; ++b) off += c[a][b] * c[a][b];
    }
    if (!(off > 1e-30 * diag)) return;
    for (int p = 0; p < D; ++p)
      for (int q = p + 1; q < D; ++q) {
        if (c[p][q] == 0.0) continue;
        const double theta = (c[q][q] - c[p][p]) / (2.0 * c[p][q]);
        const double t =
            (theta >= 0 ? 1.0 : -1.0) / (std::abs(theta) + std::sqrt(theta * theta + 1));
        const double co = 1.0 / std::sqrt(t * t + 1), si = t * co;
        for (int k = 0; k < D; ++k) {  // c <- c J (columns p, q)
          const double ckp = c[k][p], ckq = c[k][q];
          c[k][p] = co * ckp - si * ckq;
          c[k][q] = si * ckp + co * ckq;
        }
        for (int k = 0; k < D; ++k) {  // c <- Jᵀ c (rows p, q)
          const double cpk = c[p][k], cqk = c[q][k];
          c[p][k] = co * cpk - si * cqk;
          c[q][k] = si * cpk + co * cqk;
        }
        for (int k = 0; k < D; ++k) {
          const double vkp = v[k][p], vkq = v[k][q];
          v[k][p] = co * vkp - si * vkq;
          v[k][q] = si * vkp + co * vkq;
        }
      }
  }
}

// m u(x_i) of one field at one node from its moments (see the file's head).
template <int D, class Real>
void correct_node(const GridView<D, Real>& G, const SeparationMoments<D, Real>& M, std::size_t i) {
  const double m = double(G.m[i]);
  double rbar[D], c[D][D], v[D][D];
  for (int a = 0; a < D; ++a) rbar[a] = double(M.r[a][i]) / m;
  for (int a = 0; a < D; ++a)
    for (int b = 0; b < D; ++b)
      c[a][b] = double(M.rr[std::size_t(sym_index<D>(a, b))][i]) / m - rbar[a] * rbar[b];
  symmetric_eigen<D>(c, v);
  // y = C⁻¹ r̄, one eigen-direction at a time, each at most kMaxExtrapolation
  // standard deviations of the particles' spread in that direction; scaled by
  // how well the least spread direction is resolved (none below kSpreadNone).
  double keep = 1.0;
  for (int k = 0; k < D; ++k)
    keep =
        std::min(keep, std::clamp((c[k][k] - kSpreadNone) / (kSpreadFull - kSpreadNone), 0.0, 1.0));
  if (keep == 0.0) return;
  double y[D] = {};
  for (int k = 0; k < D; ++k) {
    const double l = c[k][k];
    double proj = 0;
    for (int a = 0; a < D; ++a) proj += v[a][k] * rbar[a];
    const double reach = kMaxExtrapolation * std::sqrt(l);
    proj = std::clamp(proj, -reach, reach);
    for (int a = 0; a < D; ++a) y[a] += keep / l * proj * v[a][k];
  }
  // m u(x_i) = mx − B R = mx − UR C⁺ r̄  (UR = Σ w (u − ū) rᵀ, B = (UR / m) C⁺, R = m r̄).
  for (int a = 0; a < D; ++a) {
    double shift = 0;
    for (int b = 0; b < D; ++b) shift += double(M.ur[std::size_t(a * D + b)][i]) * y[b];
    G.mx[a][i] = Real(double(G.mx[a][i]) - shift);
  }
}

}  // namespace separation_detail

// Scatters the moments from the tiles find_reach_tiles listed (after mx and m
// hold their sums at the multimaterial nodes) and moves each deformable
// field's mx at `nodes` from its centroid to the node. `rigid` flags fields
// left as they are (a rigid body's displacement is uniform). Returns the
// first particle whose stencil left the grid, or SIZE_MAX.
template <int D, class Shape, class Real>
std::size_t extrapolate_separation(const ParticleView<D, Real>& P, const GridView<D, Real>& G,
                                   const SeparationMoments<D, Real>& M,
                                   const TileSchedule& schedule, const ReachTiles& reach_tiles,
                                   const std::vector<std::uint32_t>& nodes,
                                   const unsigned char* rigid, Real mass_threshold,
                                   std::vector<std::uint8_t>& listed, bool parallel) {
  constexpr int kSym = SeparationMoments<D, Real>::kSym;
  // Flags of the listed nodes (all zero between calls; sized once), and their
  // moments zeroed: nothing reads the moments anywhere else.
  if (listed.size() != G.nodes) listed.assign(G.nodes, 0);
  for (const std::uint32_t n : nodes) listed[n] = 1;
  team_for(parallel, nodes.size(), [&](std::size_t k) {
    for (int f = 0; f < G.fields; ++f) {
      const std::size_t i = G.at(f, nodes[k]);
      for (int a = 0; a < D; ++a) M.r[a][i] = Real(0);
      for (int a = 0; a < kSym; ++a) M.rr[std::size_t(a)][i] = Real(0);
      for (int a = 0; a < D * D; ++a) M.ur[std::size_t(a)][i] = Real(0);
    }
  });
  std::atomic<std::size_t> first_bad{SIZE_MAX};
  for (const auto& list : reach_tiles.tiles) {
    team_for(parallel, list.size(), [&](std::size_t k) {
      const std::size_t b = schedule.begin[list[k]], e = schedule.begin[list[k] + 1];
      offer_min(first_bad,
                separation_detail::scatter_moments<D, Shape, Real>(P, G, M, listed.data(), b, e));
    });
  }
  for (const std::uint32_t n : nodes) listed[n] = 0;
  if (const std::size_t bad = first_bad.load(); bad != SIZE_MAX) return bad;
  team_for(parallel, nodes.size(), [&](std::size_t k) {
    for (int f = 0; f < G.fields; ++f) {
      if (rigid && rigid[f]) continue;
      const std::size_t i = G.at(f, nodes[k]);
      if (!(G.m[i] > mass_threshold)) continue;
      separation_detail::correct_node<D, Real>(G, M, i);
    }
  });
  return SIZE_MAX;
}

}  // namespace mmpm
