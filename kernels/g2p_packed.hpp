// The 2D linear gather with K particles of one window in one 64-byte vector
// (K = 2 in double, 4 in float; kernels/packed_linear.hpp), for the G2P
// passes that do not scatter momentum back (USL's G2P, MUSL's gradient
// pass, USF's). The solver uses it in float (packed_gather_pays).
//
// Why: the one-particle gather (kernels/g2p.hpp G2PGather) ran its 4-lane
// products and its shuffle tree of sums at half (double) or a quarter
// (float) of an AVX-512 register, after a per-particle shape-function loop
// for the window. Here the window lanes of K particles come straight from
// the distances locate_batch stores, the window's grid values are loaded
// once per run of particles in one cell, and the products and the sums run
// for K particles at once. Each value is computed with the one-particle
// gather's operations in its order (products A = Y v, B = GY v, Q = Y dv,
// then X A, X Q, GX A, X B, each summed (l0 + l1) + (l2 + l3)): the same
// bits for L (tests/test_p2g.cpp PackedLinearGather). The particle's update
// from those values is detail::update_particle, shared with the
// one-particle kernel; there -ffp-contract may fuse v and x differently
// per call site (within 2 ulp).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>

#include "kernels/g2p_particle.hpp"
#include "kernels/grid_update.hpp"
#include "kernels/packed_linear.hpp"
#include "kernels/weight_batch.hpp"
#include "kernels/window_block.hpp"

namespace mmpm {

// Whether g2p_range uses the packed gather: in float (4 particles per
// vector) only. Measured on the G2P kernel (2D linear, 250k particles, 5
// interleaved rounds, minimum ns/particle): float 8.22 -> 5.99 (1 thread),
// 4.46 -> 3.66 (2 threads); double 9.47 -> 8.97 and 4.60 -> 5.02, medians
// unchanged, and the 2D linear step's G2P stage 17.7 -> 17.8 (4 rounds).
// In double the one-particle gather already fills half a register and the
// particle's scalar update dominates (docs/performance.md "The packed
// gather").
template <int D, class Shape, class Real>
constexpr bool packed_gather_pays() {
  return packed_particles<D, Shape, Real>() >= 4;
}

// G2P of particles [begin, end) with the packed gather; the contract of
// g2p_range (kernels/g2p.hpp), without kScatterMomentum.
template <class Real, unsigned What, bool MultiField, bool Traction, bool Gravity, class KeyFn,
          class StressFn>
G2PRangeResult g2p_range_packed(const ParticleView<2, Real>& particles,
                                const GridView<2, Real>& grid,
                                const GridVelocity<2, Real>& velocities, const G2PParams& q,
                                const KeyFn& key_of, std::size_t begin, std::size_t end,
                                const StressFn& stress) {
  static_assert((What & kScatterMomentum) == 0, "the packed gather does not scatter");
  constexpr int K = packed_particles<2, LinearShape, Real>();
  static_assert(K > 1);
  constexpr bool kMotion = (What & kUpdateMotion) != 0;
  constexpr bool kGradient = (What & kVelocityGradient) != 0;
  using PL = PackedLinearLanes<Real, K>;
  using Win = typename PL::Win;
  using VW = typename PL::VW;
  // Local copies of the views, as g2p_range_impl.
  const ParticleView<2, Real> P = particles;
  const GridView<2, Real> G = grid;
  const GridVelocity<2, Real> V = velocities;
  G2PRangeResult r;
  const Real dt = Real(q.dt), flip = Real(q.flip), pic = Real(1) - Real(q.flip);
  const WindowBuilder<2, LinearShape, Real> builder(G);
  const auto off = Win::offsets(G);
  const Real inv_hx = builder.inverse_spacing(0), inv_hy = builder.inverse_spacing(1);
  PackedBatch<Real, K, MultiField> batch;
  for (std::size_t first = begin; first < end; first += kWeightBatch) {
    const std::size_t n = std::min(kWeightBatch, end - first);
    batch.locate(builder, P, first, n);
    for (std::size_t i = 0; i < n;) {
      if (!batch.inside[i]) {  // the stencil leaves the grid: the step fails on it
        if (r.bad == SIZE_MAX) r.bad = first + i;
        ++i;
        continue;
      }
      // A run: consecutive particles with this window and field.
      const std::size_t b = batch.window(P, G, i);
      const std::size_t j = batch.run_end(P, G, i, b, n);
      VW vel[2], dvel[2];
      for (int d = 0; d < 2; ++d) {
        vel[d] = PL::repeat(Win::template load<0>(V.vel[d] + b, off));
        if constexpr (kMotion) dvel[d] = PL::repeat(Win::template load<0>(V.dvel[d] + b, off));
      }
      for (std::size_t k = i; k < j; k += std::size_t(K)) {
        const PL w = PL::of(batch.dx(k), batch.dy(k), inv_hx, inv_hy);
        // Lanes 4c .. 4c + 3 of sums[d]: slot c's vn, dv, L_d,x, L_d,y
        // (G2PGather::gather's lanes_sum4, slot by slot).
        VW sums[2];
        for (int d = 0; d < 2; ++d) {
          VW A{}, B{}, Q{};
          A += w.Y * vel[d];
          if constexpr (kGradient) B += w.GY * vel[d];
          if constexpr (kMotion) Q += w.Y * dvel[d];
          sums[d] = PL::sum4(w.X * A, w.X * Q, w.GX * A, w.X * B);
        }
        const int count = int(std::min<std::size_t>(std::size_t(K), j - k));
        for (int c = 0; c < count; ++c) {
          const std::size_t p = first + k + std::size_t(c);
          if (detail::rigid_motion<2, Real, What, MultiField>(P, q, dt, p)) continue;
          const Real vn[2] = {sums[0][4 * c], sums[1][4 * c]};
          const Real dv[2] = {sums[0][4 * c + 1], sums[1][4 * c + 1]};
          const Real L[4] = {sums[0][4 * c + 2], sums[0][4 * c + 3], sums[1][4 * c + 2],
                             sums[1][4 * c + 3]};
          detail::update_particle<2, Real, What, Traction, Gravity>(P, q, dt, flip, pic, p, vn, dv,
                                                                    L, r, stress);
        }
      }
      i = j;
    }
  }
  // As g2p_range_impl: did a particle leave its tile?
  constexpr bool kMoves = (What & (kCommitPosition | kUpdateMotion)) != 0;
  if (kMoves && ((What & kCommitPosition) != 0 || !P.x_next[0]))
    r.moved_tile = key_of.any_moved(P.key, begin, end);
  return r;
}

}  // namespace mmpm
