// The 2D linear gather with K particles of one window in one 64-byte vector
// (K = 2 in double, 4 in float; kernels/packed_linear.hpp), for every G2P
// pass: USL's and USF's, MUSL's gradient pass, and MUSL's fused pass, whose
// momentum scatter m v then runs with the packed scatter's block
// (kernels/p2g_packed.hpp) on the gather's lanes. The solver uses it
// wherever it applies (packed_gather_pays).
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
// bits for L (tests/test_p2g.cpp PackedLinearGather). The particles'
// update from those values runs K at a time (update_group) for a whole
// group of deformable particles, else particle by particle
// (detail::update_particle, shared with the one-particle kernel); v and x
// are within 2 ulp of it (-ffp-contract may fuse per call site).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <utility>

#include "kernels/g2p_particle.hpp"
#include "kernels/grid_prefetch.hpp"
#include "kernels/grid_update.hpp"
#include "kernels/p2g_packed.hpp"
#include "kernels/packed_linear.hpp"
#include "kernels/weight_batch.hpp"
#include "kernels/window_block.hpp"

namespace mmpm {

// Whether g2p_range uses the packed gather: wherever it applies (2D
// linear, AVX-512), in double and float, for every pass. With the particle
// update particle by particle it paid in float only (double 9.47 -> 8.97
// ns/particle, medians equal); with update_group it pays in both
// (docs/performance.md "The packed gather", 2026-11-25: G2P kernel double
// 9.92 -> 7.65, float 5.85 -> 3.81 ns/particle on 1 thread).
template <int D, class Shape, class Real>
constexpr bool packed_gather_pays() {
  return packed_particles<D, Shape, Real>() > 1;
}

// m and m v of particles p .. p + count - 1 right after the update wrote
// v, lanes at and past count 0 (PackedSource::make's products). Built from
// one scalar load per lane: after a group updated particle by particle, a
// K-lane load of v would span K scalar stores, which the CPU cannot forward
// to it (it waits for them to reach the cache).
template <class Source, class Real>
[[gnu::always_inline]] inline Source updated_momenta(const ParticleView<2, Real>& P, std::size_t p,
                                                     int count) {
  using S = decltype(Source::m);
  auto lanes = [&]<std::size_t... I>(const Real* a, std::index_sequence<I...>)
      __attribute__((always_inline)) {
    return S{(int(I) < count ? a[p + I] : Real(0))...};
  };
  constexpr auto kLanes = std::make_index_sequence<sizeof(S) / sizeof(Real)>{};
  Source q;
  q.m = lanes(P.m, kLanes);
  for (int d = 0; d < 2; ++d) q.mv[d] = q.m * lanes(P.v[d], kLanes);
  return q;
}

// Particles p .. p + K - 1's update from the packed sums (lanes 4c .. 4c + 3
// of sums[d]: slot c's vn, dv, L_d,x, L_d,y), K lanes per operation: the
// formulas of detail::update_particle lane by lane, its finite test (first
// bad particle) and its external work, summed particle by particle in its
// order. For full groups of deformable particles without the fused stress
// update; the rest goes particle by particle. v, x and x_next are within
// 2 ulp of update_particle's (-ffp-contract fuses per call site), L is the
// gathered sum itself.
template <class Real, unsigned What, bool Traction, bool Gravity, int K, class VW>
[[gnu::always_inline]] inline void update_group(const ParticleView<2, Real>& P, const G2PParams& q,
                                                Real dt, Real flip, Real pic, std::size_t p,
                                                const VW (&sums)[2], G2PRangeResult& r) {
  using S = Lanes<Real, K>;
  static_assert((What & kStressUpdate) == 0);
  if constexpr ((What & kUpdateMotion) != 0) {
    S vn[2], vnew[2];
    for (int d = 0; d < 2; ++d) {
      vn[d] = lanes_pick<K>(sums[d], [](int c) { return 4 * c; });
      const S dv = lanes_pick<K>(sums[d], [](int c) { return 4 * c + 1; });
      vnew[d] = flip * (lanes_load<S>(P.v[d] + p) + dv) + pic * vn[d];
      lanes_store(P.v[d] + p, vnew[d]);
      // detail::move_particle, K lanes at once
      const S x = lanes_load<S>(P.x[d] + p);
      S moved;
      if (std::is_same_v<Real, float> && P.xlo[0]) {
        S lo = lanes_load<S>(P.xlo[d] + p);
        moved = compensated_add(x, lo, dt * vn[d]);
        lanes_store(P.xlo[d] + p, lo);
      } else {
        moved = x + dt * vn[d];
      }
      lanes_store(P.x_next[0] ? P.x_next[d] + p : P.x[d] + p, moved);
    }
    // Finite: v - v is 0 for finite v, NaN for inf and NaN.
    const S zero = (vnew[0] - vnew[0]) + (vnew[1] - vnew[1]);
    if (r.bad == SIZE_MAX)
      for (int c = 0; c < K; ++c)
        if (!(zero[c] == Real(0))) {
          r.bad = p + std::size_t(c);
          break;
        }
    if constexpr (Traction || Gravity)
      for (int c = 0; c < K; ++c) {
        const Real vn_c[2] = {vn[0][c], vn[1][c]};
        r.external_work +=
            detail::external_work<2, Real, Traction, Gravity>(P, q, p + std::size_t(c), vn_c);
      }
  }
  if constexpr ((What & kVelocityGradient) != 0)
    for (int d = 0; d < 2; ++d) {
      lanes_store(P.L[2 * d] + p, lanes_pick<K>(sums[d], [](int c) { return 4 * c + 2; }));
      lanes_store(P.L[2 * d + 1] + p, lanes_pick<K>(sums[d], [](int c) { return 4 * c + 3; }));
    }
  if constexpr ((What & kSeparationShift) != 0)  // detail::advance_shift, K lanes at once
    for (int d = 0; d < 2; ++d) {
      const S vn = lanes_pick<K>(sums[d], [](int c) { return 4 * c; });
      const S moved = lanes_load<S>(P.x_next[d] + p) - lanes_load<S>(P.x[d] + p);
      lanes_store(P.sep_shift[d] + p, lanes_load<S>(P.sep_shift[d] + p) + (dt * vn - moved));
    }
  if constexpr ((What & kCommitPosition) != 0)
    for (int d = 0; d < 2; ++d) lanes_store(P.x[d] + p, lanes_load<S>(P.x_next[d] + p));
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
  constexpr int K = packed_particles<2, LinearShape, Real>();
  static_assert(K > 1);
  constexpr bool kMotion = (What & kUpdateMotion) != 0;
  constexpr bool kGradient = (What & kVelocityGradient) != 0;
  constexpr bool kScatter = (What & kScatterMomentum) != 0;
  static_assert(!kScatter || kMotion, "the momentum scattered is the updated one");
  // MUSL's second transfer: m v of the updated particles, with the lanes of
  // the gather (p2g_range_packed's block and run handling).
  using Block = PackedLinearBlock<Real, kMomentumOnly, false, K>;
  using Source = typename Block::Source;
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
  auto ahead = gather_lines_ahead<What, Win>(q.prefetch_grid, off, G, V);
  const Real inv_hx = builder.inverse_spacing(0), inv_hy = builder.inverse_spacing(1);
  PackedBatch<Real, K, MultiField> batch;
  Block carried;  // current == SIZE_MAX: nothing carried (kScatter only)
  const ParticleLinesAhead* const columns_ahead = q.particles_ahead;
  for (std::size_t first = begin; first < end; first += kWeightBatch) {
    const std::size_t n = std::min(kWeightBatch, end - first);
    if (columns_ahead) columns_ahead->batch(first, n);
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
      ahead.window(b);
      Block block;  // as in p2g_range_packed
      if constexpr (kScatter) {
        if (carried.current == b)
          block = carried;
        else
          carried.flush(G, off);
        carried.current = SIZE_MAX;
        block.current = b;
      }
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
        bool whole = count == K && (What & kStressUpdate) == 0;
        // Groups with a rigid particle go particle by particle (its motion
        // is prescribed, its shift kept).
        if constexpr ((What & (kUpdateMotion | kSeparationShift)) != 0 && MultiField)
          if (whole && q.rigid)
            for (int c = 0; c < K; ++c)
              whole = whole && !q.rigid[P.field[first + k + std::size_t(c)]];
        if (whole) {
          if constexpr ((What & kStressUpdate) == 0)
            update_group<Real, What, Traction, Gravity, K>(P, q, dt, flip, pic, first + k, sums, r);
        } else
          for (int c = 0; c < count; ++c) {
            const std::size_t p = first + k + std::size_t(c);
            if (detail::rigid_motion<2, Real, What, MultiField>(P, q, dt, p)) continue;
            const Real vn[2] = {sums[0][4 * c], sums[1][4 * c]};
            const Real dv[2] = {sums[0][4 * c + 1], sums[1][4 * c + 1]};
            const Real L[4] = {sums[0][4 * c + 2], sums[0][4 * c + 3], sums[1][4 * c + 2],
                               sums[1][4 * c + 3]};
            detail::update_particle<2, Real, What, Traction, Gravity>(P, q, dt, flip, pic, p, vn,
                                                                      dv, L, r, stress);
          }
        if constexpr (kScatter)  // every particle of the group, rigid ones too (g2p.hpp)
          block.accumulate(w, updated_momenta<Source>(P, first + k, count));
      }
      if constexpr (kScatter) {
        if (j == n && first + n < end)
          carried = block;  // the run may go on in the next batch
        else
          block.flush(G, off);
      }
      i = j;
    }
  }
  if constexpr (kScatter) carried.flush(G, off);
  // As g2p_range_impl: did a particle leave its tile?
  constexpr bool kMoves = (What & (kCommitPosition | kUpdateMotion)) != 0;
  if (kMoves && ((What & kCommitPosition) != 0 || !P.x_next[0]))
    r.moved_tile = key_of.any_moved(P.key, begin, end);
  return r;
}

}  // namespace mmpm
