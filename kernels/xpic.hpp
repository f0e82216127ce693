// XPIC(m) particle velocities (Hammerquist & Nairn 2017; docs/validation.md
// §3.12). FLIP keeps in the particle velocities a part the grid cannot see
// (the null space of the particle-to-grid map); on long runs of bodies that
// move across cells while they vibrate it grows (Brackbill's ringing: two
// disks with linear shapes gained 19 % of their energy after their
// collision by t = 3.5 at h = 1/160, 130 % by t = 6; uGIMP 1.7 % and
// 8.8 %). PIC removes it with everything the lumped projection smooths. XPIC(m) replaces the
// particle velocities, before the FLIP increment, by S v*, with v* the first m terms of the series
// for the projection onto the grid's velocity fields with the consistent mass matrix M_c = S^T M_p
// S:
//   M_c^-1 S^T M_p v_p = sum_{k=0}^{m-1} (I - A)^k v,   A = M_L^-1 S^T M_p S,
// v = M_L^-1 S^T M_p v_p the grid velocity of the step's P2G (M_L the lumped
// masses). m = 1 is PIC; each further term costs one interpolation to the
// particles and one mass-weighted scatter back (A). The last interpolation,
// S v*, rides on the step's FLIP G2P: its increment v_L - v takes v* more
// and the particles start from 0. Momentum is kept:
// sum_i m_i (A u)_i = sum_i m_i u_i, so every term after the first carries
// no momentum.
#pragma once

#include <array>
#include <cstddef>

#include "kernels/grid_view.hpp"
#include "kernels/particle_view.hpp"
#include "kernels/weights.hpp"

namespace mmpm {

// out_p = sum_i S_ip u_i over the nodes of particle p's field, for the
// particles [begin, end). Returns the first particle whose stencil leaves
// the grid (its out_p untouched), or end.
template <int D, class Shape, class Real>
std::size_t interpolate_to_particles(const ParticleView<D, Real>& P, const GridView<D, Real>& G,
                                     const std::array<const Real*, D>& u,
                                     const std::array<Real*, D>& out, std::size_t begin,
                                     std::size_t end) {
  const std::array<Real, 3> inv_h{Real(1) / G.h[0], Real(1) / G.h[1], Real(1) / G.h[2]};
  Stencil<D, Shape, Real> st{};
  for (std::size_t p = begin; p < end; ++p) {
    if (!st.build(P, G, inv_h, p)) return p;
    const std::size_t b = st.base + (P.field ? std::size_t(P.field[p]) * G.nodes : 0);
    Real s[D] = {};
    for (int k = 0; k < st.count; ++k)
      for (int d = 0; d < D; ++d) s[d] += st.w[k] * u[d][b + st.node[k]];
    for (int d = 0; d < D; ++d) out[d][p] = s[d];
  }
  return end;
}

// One more term of the series at nodes [begin, end): with q = S^T M_p S term
// (the scatter of the interpolated term), term <- term - q / m where the
// node holds mass above the threshold (A term = q / m), and sum += term.
template <int D, class Real>
void add_xpic_term(const Real* m, const std::array<const Real*, D>& q,
                   const std::array<Real*, D>& term, const std::array<Real*, D>& sum,
                   Real mass_threshold, std::size_t begin, std::size_t end) {
  for (std::size_t i = begin; i < end; ++i) {
    const bool heavy = m[i] > mass_threshold;
    for (int d = 0; d < D; ++d) {
      term[d][i] -= heavy ? q[d][i] / m[i] : Real(0);
      sum[d][i] += term[d][i];
    }
  }
}

}  // namespace mmpm
