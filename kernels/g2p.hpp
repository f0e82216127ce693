// Grid-to-particle transfer (ALGORITHM §2 step 6): velocity (FLIP/PIC
// blend), position, and the velocity gradient the constitutive update uses.
// Every particle reads only its own material field.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "kernels/grid_update.hpp"
#include "kernels/weights.hpp"

namespace mmpm {

enum G2PWhat : unsigned {
  kUpdateMotion = 1u,    // v and x
  kVelocityGradient = 2u // L = sum v_i (x) G_ip
};

struct G2PParams {
  double dt = 0;
  double flip = 1;
  const unsigned char* rigid = nullptr;         // per field
  const double (*rigid_velocity)[3] = nullptr;  // per field, at t + dt
  double body_accel[3] = {0, 0, 0};             // for the external work of gravity
};

// Outcome of a G2P range: first bad particle (stencil off the grid or
// non-finite velocity), work of external forces, particles that changed tile.
struct G2PRangeResult {
  std::size_t bad = SIZE_MAX;
  double external_work = 0;
  bool moved_tile = false;
};

template <int D, class Shape, class Real, unsigned What, bool MultiField, bool Traction,
          bool Gravity, class KeyFn>
G2PRangeResult g2p_range(const ParticleView<D, Real>& P, const GridView<D, Real>& G,
                         const GridVelocity<D, Real>& V, const G2PParams& q,
                         const KeyFn& key_of, std::size_t begin, std::size_t end) {
  G2PRangeResult r;
  const std::array<Real, 3> inv_h{Real(1) / G.h[0], Real(1) / G.h[1], Real(1) / G.h[2]};
  const Real dt = Real(q.dt), flip = Real(q.flip), pic = Real(1) - Real(q.flip);
  Stencil<D, Shape, Real> st;
  for (std::size_t p = begin; p < end; ++p) {
    if (!st.build(P, G, inv_h, p)) {
      if (r.bad == SIZE_MAX) r.bad = p;
      continue;
    }
    const int field = MultiField ? int(P.field[p]) : 0;
    const std::size_t b = st.base + (MultiField ? std::size_t(field) * G.nodes : 0);
    if constexpr ((What & kUpdateMotion) != 0) {
      if (MultiField && q.rigid && q.rigid[field]) {  // prescribed motion (§7)
        for (int d = 0; d < D; ++d) {
          P.v[d][p] = Real(q.rigid_velocity[field][d]);
          if (P.x_next[0])
            P.x_next[d][p] = P.x[d][p] + dt * P.v[d][p];
          else
            P.x[d][p] += dt * P.v[d][p];
        }
        if (!P.x_next[0] && key_of.tile(p) != key_of.tile_of_key(P.key[p])) r.moved_tile = true;
        continue;
      }
    }
    Real vn[D] = {}, dv[D] = {}, L[D * D] = {};
    for (int k = 0; k < st.count; ++k) {
      const std::size_t i = b + st.node[k];
      const Real w = st.w[k];
      for (int d = 0; d < D; ++d) {
        const Real vi = V.vel[d][i];
        if constexpr ((What & kUpdateMotion) != 0) {
          vn[d] += w * vi;
          dv[d] += w * V.dvel[d][i];
        }
        if constexpr ((What & kVelocityGradient) != 0)
          for (int e = 0; e < D; ++e) L[d * D + e] += vi * st.g[k][e];
      }
    }
    if constexpr ((What & kUpdateMotion) != 0) {
      bool finite = true;
      double work = 0;
      for (int d = 0; d < D; ++d) {
        const Real vnew = flip * (P.v[d][p] + dv[d]) + pic * vn[d];
        P.v[d][p] = vnew;
        if (P.x_next[0])
          P.x_next[d][p] = P.x[d][p] + dt * vn[d];
        else
          P.x[d][p] += dt * vn[d];
        finite = finite && std::isfinite(vnew);
        // Work = force times the displacement of the material point, which
        // moves with the grid velocity (not with its FLIP velocity).
        const double vmove = double(vn[d]);
        if constexpr (Traction) work += double(P.fext[d][p]) * vmove;
        if constexpr (Gravity) work += double(P.m[p]) * q.body_accel[d] * vmove;
      }
      if constexpr (Traction || Gravity) r.external_work += work * q.dt;
      if (!finite && r.bad == SIZE_MAX) r.bad = p;
      if (!P.x_next[0] && key_of.tile(p) != key_of.tile_of_key(P.key[p])) r.moved_tile = true;
    }
    if constexpr ((What & kVelocityGradient) != 0)
      for (int c = 0; c < D * D; ++c) P.L[c][p] = L[c];
  }
  return r;
}

}  // namespace mmpm
