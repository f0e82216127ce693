// Particle-to-grid transfer (ALGORITHM §1 and §2 step 2), one tile at a
// time. The caller runs tiles color by color; tiles of one color touch
// disjoint nodes, so threads add straight into the grid with no atomics.
#pragma once

#include <cstddef>
#include <cstdint>

#include "kernels/weights.hpp"

namespace mmpm {

// What a P2G pass scatters (bit mask).
enum P2GWhat : unsigned {
  kMassMomentum = 1u,  // m, p
  kForce = 2u,         // internal force -V sigma.G, traction force S fext
  kMultimaterial = 4u, // mx, Omega, g  (ALGORITHM §1, P-10/13, P-19, P-33)
  kMomentumOnly = 8u,  // p alone (MUSL's second transfer)
};

struct P2GOptions {
  bool position_separation = false;  // mx holds positions (else displacements)
  double inv_thickness = 1.0;        // 2D: Omega and g are areas (P-19, P-33)
};

// Scatters particles [begin, end). Returns the first particle whose stencil
// leaves the grid, or end.
template <int D, class Shape, class Real, unsigned What, bool MultiField, bool Traction>
std::size_t p2g_range(const ParticleView<D, Real>& P, const GridView<D, Real>& G,
                      const P2GOptions& opt, std::size_t begin, std::size_t end) {
  constexpr int NS = kStressComponents<D>;
  const std::array<Real, 3> inv_h{Real(1) / G.h[0], Real(1) / G.h[1], Real(1) / G.h[2]};
  const Real inv_t = Real(opt.inv_thickness);
  Stencil<D, Shape, Real> st;
  for (std::size_t p = begin; p < end; ++p) {
    if (!st.build(P, G, inv_h, p)) return p;
    const std::size_t fo = MultiField ? std::size_t(P.field[p]) * G.nodes : 0;
    const std::size_t b = st.base + fo;
    const Real mp = P.m[p];
    Real mv[D], vs[NS], fe[D], mw[D];
    for (int d = 0; d < D; ++d) mv[d] = mp * P.v[d][p];
    if constexpr ((What & kForce) != 0) {
      for (int c = 0; c < NS; ++c) vs[c] = P.V[p] * P.s[c][p];
      if constexpr (Traction)
        for (int d = 0; d < D; ++d) fe[d] = P.fext[d][p];
    }
    Real area = 0;
    if constexpr ((What & kMultimaterial) != 0) {
      area = P.V[p] * (D == 2 ? inv_t : Real(1));
      for (int d = 0; d < D; ++d)
        mw[d] = mp * (opt.position_separation ? P.x[d][p] : P.x[d][p] - P.x0[d][p]);
    }
    for (int k = 0; k < st.count; ++k) {
      const std::size_t i = b + st.node[k];
      const Real w = st.w[k];
      if constexpr ((What & kMassMomentum) != 0) {
        G.m[i] += w * mp;
        for (int d = 0; d < D; ++d) G.p[d][i] += w * mv[d];
      }
      if constexpr ((What & kMomentumOnly) != 0) {
        for (int d = 0; d < D; ++d) G.p[d][i] += w * mv[d];
      }
      if constexpr ((What & kForce) != 0) {
        const auto& gk = st.g[k];
        if constexpr (D == 2) {
          // f = -V sigma . G  (sigma: xx, yy, xy, zz)
          G.f[0][i] -= vs[0] * gk[0] + vs[2] * gk[1];
          G.f[1][i] -= vs[2] * gk[0] + vs[1] * gk[1];
        } else {
          // Voigt: xx, yy, zz, yz, xz, xy
          G.f[0][i] -= vs[0] * gk[0] + vs[5] * gk[1] + vs[4] * gk[2];
          G.f[1][i] -= vs[5] * gk[0] + vs[1] * gk[1] + vs[3] * gk[2];
          G.f[2][i] -= vs[4] * gk[0] + vs[3] * gk[1] + vs[2] * gk[2];
        }
        if constexpr (Traction)
          for (int d = 0; d < D; ++d) G.f[d][i] += w * fe[d];
      }
      if constexpr ((What & kMultimaterial) != 0) {
        G.vol[i] += w * area;
        for (int d = 0; d < D; ++d) {
          G.mx[d][i] += w * mw[d];
          G.g[d][i] += st.g[k][d] * area;
        }
      }
    }
  }
  return end;
}

}  // namespace mmpm
