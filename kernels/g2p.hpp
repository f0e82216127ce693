// Grid-to-particle transfer (ALGORITHM §2 step 6): velocity (FLIP/PIC
// blend), position, and the velocity gradient the constitutive update uses.
// Every particle reads only its own material field.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "kernels/constitutive.hpp"
#include "kernels/g2p_packed.hpp"
#include "kernels/g2p_particle.hpp"
#include "kernels/grid_update.hpp"
#include "kernels/weight_batch.hpp"
#include "kernels/weights.hpp"
#include "kernels/window_block.hpp"

namespace mmpm {

// Gathers the grid velocity, velocity change and velocity gradient of one
// particle. Windowed: rows of W nodes along x, with the separable sums
//   v_p = sum_x wx * A,  L_d,x = sum_x gx * A,  L_d,y = sum_x wx * B, ...
// where A = sum over the rows of (wy wz) v_row, B = sum of (gy wz) v_row,
// C = sum of (wy gz) v_row: three vector multiply-adds per row and field
// instead of one scalar pass per node. Pointwise: node by node on the stencil.
template <int D, class Shape, class Real, bool Windowed>
struct G2PGather {
  using Win = Window<D, Shape, Real>;
  using St = Stencil<D, Shape, Real>;
  using Weights = std::conditional_t<Windowed, Win, St>;
  struct NoBuilder {
    explicit NoBuilder(const GridView<D, Real>&) {}
  };
  std::conditional_t<Windowed, WindowBuilder<D, Shape, Real>, NoBuilder> builder;
  const GridView<D, Real>& grid_;
  std::array<Real, 3> inv_h_;
  typename Win::Offsets offsets{};

  explicit G2PGather(const GridView<D, Real>& grid)
      : builder(grid),
        grid_(grid),
        inv_h_{Real(1) / grid.h[0], Real(1) / grid.h[1], Real(1) / grid.h[2]} {
    if constexpr (Windowed) offsets = Win::offsets(grid);
  }

  // A batch of weights (kernels/weight_batch.hpp): windows through
  // WindowBuilder::build_batch, stencils one by one.
  [[gnu::always_inline]] void build_batch(const ParticleView<D, Real>& P, std::size_t first,
                                          std::size_t n, Weights* w, bool* ok) const {
    if constexpr (Windowed)
      builder.build_batch(P, first, n, w, ok);
    else
      for (std::size_t i = 0; i < n; ++i) ok[i] = w[i].build(P, grid_, inv_h_, first + i);
  }

  // The grid velocities (and changes) of one window, its rows joined into
  // units: loaded when a particle's window differs from the one held, and
  // reused by the rest of its run (the particles of one cell and field are
  // consecutive). Why: the loads and row joins of a window (3D uGIMP
  // double, MUSL's first pass: 6 arrays x 8 units, each two loads and a
  // shuffle) were repeated for every particle of the cell. Same values,
  // same sums: bitwise the per-particle loads (docs/performance.md "Unit
  // loops kept inline; a window's grid values held for its run").
  struct WindowValues {
    std::size_t base = SIZE_MAX;
    typename Win::V vel[D][Win::units] = {}, dvel[D][Win::units] = {};
  };
  struct NoValues {};
  using Held = std::conditional_t<Windowed, WindowValues, NoValues>;

  // vn, dv: velocity and its change over the step; L row-major dv_a/dx_b.
  template <bool Motion, bool Gradient>
  [[gnu::always_inline]] void gather(const Weights& w, const GridVelocity<D, Real>& V,
                                     std::size_t field_offset, Held& held, Real* vn, Real* dv,
                                     Real* L) const {
    const std::size_t b = w.base + field_offset;
    if constexpr (!Windowed) {
      for (int k = 0; k < St::count; ++k) {
        const std::size_t i = b + w.node[k];
        const Real s = w.w[k];
        for (int d = 0; d < D; ++d) {
          const Real vi = V.vel[d][i];
          if constexpr (Motion) {
            vn[d] += s * vi;
            dv[d] += s * V.dvel[d][i];
          }
          if constexpr (Gradient)
            for (int e = 0; e < D; ++e) L[d * D + e] += vi * w.g[k][e];
        }
      }
    } else {
      // Unit sums A = sum_u Y(u) v_u, B = sum_u GY(u) v_u, C = sum_u GZ(u) v_u,
      // then v_p = sum(X A), L_d,x = sum(GX A), L_d,y = sum(X B), L_d,z = sum(X C).
      using Vec = typename Win::V;
      constexpr int Ln = Win::L;
      const auto& off = offsets;
      if (b != held.base) {
        held.base = b;
        static_for<Win::units>([&](auto uc) __attribute__((always_inline)) {
          constexpr int u = decltype(uc)::value;
          for (int d = 0; d < D; ++d) {
            held.vel[d][u] = Win::template load<u>(V.vel[d] + b, off);
            if constexpr (Motion) held.dvel[d][u] = Win::template load<u>(V.dvel[d] + b, off);
          }
        });
      }
      Vec A[D] = {}, B[D] = {}, C[D] = {}, Q[D] = {};
      static_for<Win::units>([&](auto uc) __attribute__((always_inline)) {
        constexpr int u = decltype(uc)::value;
        const Vec Yu = w.template Y<u>(), GYu = w.template GY<u>(), GZu = w.template GZ<u>();
        for (int d = 0; d < D; ++d) {
          const Vec vu = held.vel[d][u];
          A[d] += Yu * vu;
          if constexpr (Gradient) {
            B[d] += GYu * vu;
            if constexpr (D == 3) C[d] += GZu * vu;
          }
          if constexpr (Motion) Q[d] += Yu * held.dvel[d][u];
        }
      });
      const Vec X = w.X(), GX = w.GX();
      for (int d = 0; d < D; ++d) {
        if constexpr (Ln >= 4) {
          // Four dot products at once (a shuffle tree, not four serial sums).
          const Lanes<Real, 4> s1 =
              lanes_sum4(lanes_fold4<Real, Ln>(X * A[d]), lanes_fold4<Real, Ln>(X * Q[d]),
                         lanes_fold4<Real, Ln>(GX * A[d]), lanes_fold4<Real, Ln>(X * B[d]));
          if constexpr (Motion) vn[d] = s1[0], dv[d] = s1[1];
          if constexpr (Gradient) {
            L[d * D + 0] = s1[2];
            L[d * D + 1] = s1[3];
            if constexpr (D == 3) L[d * D + 2] = lanes_sum<Real, Ln>(X * C[d]);
          }
        } else {
          if constexpr (Motion) {
            vn[d] = lanes_sum<Real, Ln>(X * A[d]);
            dv[d] = lanes_sum<Real, Ln>(X * Q[d]);
          }
          if constexpr (Gradient) {
            L[d * D + 0] = lanes_sum<Real, Ln>(GX * A[d]);
            L[d * D + 1] = lanes_sum<Real, Ln>(X * B[d]);
            if constexpr (D == 3) L[d * D + 2] = lanes_sum<Real, Ln>(X * C[d]);
          }
        }
      }
    }
  }
};

template <int D, class Shape, class Real, unsigned What, bool MultiField, bool Traction,
          bool Gravity, bool Windowed, class KeyFn, class StressFn = NoStressUpdate>
G2PRangeResult g2p_range_impl(const ParticleView<D, Real>& particles, const GridView<D, Real>& grid,
                              const GridVelocity<D, Real>& velocities, const G2PParams& q,
                              const KeyFn& key_of, std::size_t begin, std::size_t end,
                              const StressFn& stress = {}) {
  // Local copies of the views: the particle stores below cannot alias them,
  // so the array pointers stay in registers.
  const ParticleView<D, Real> P = particles;
  const GridView<D, Real> G = grid;
  const GridVelocity<D, Real> V = velocities;
  G2PRangeResult r;
  const Real dt = Real(q.dt), flip = Real(q.flip), pic = Real(1) - Real(q.flip);
  G2PGather<D, Shape, Real, Windowed> st(G);
  typename G2PGather<D, Shape, Real, Windowed>::Held held;
  constexpr bool kScatter = (What & kScatterMomentum) != 0;
  static_assert((What & kStressUpdate) == 0 || (What & kVelocityGradient) != 0,
                "the stress update needs the velocity gradient");
  static_assert(!kScatter || (What & kUpdateMotion) != 0,
                "the momentum scattered is the updated one");
  // The second transfer's block (windowed), or node-by-node adds (pointwise).
  using Block = WindowBlock<D, Shape, Real, kMomentumOnly, false>;
  Block block;
  const auto off =
      Windowed ? Window<D, Shape, Real>::offsets(G) : typename Window<D, Shape, Real>::Offsets{};
  using Weights = typename G2PGather<D, Shape, Real, Windowed>::Weights;
  // When the momentum block and the gather's sums (2D vectors) do not fit in
  // the registers together (3D uGIMP and B-splines in double: 27 + 6), the
  // momenta of a batch are scattered after its gathers, by GroupedScatter
  // (kernels/window_block.hpp), from the same windows: the same sums in the
  // same order. A particle off the grid ends the batch's scatter there (the
  // step fails on it anyway).
  constexpr int kUnits = Window<D, Shape, Real>::units;
  constexpr bool kDefer =
      kScatter && Windowed && D * kUnits + 2 * D > block_register_budget<D, Shape, Real>();
  constexpr int kDeferUG = block_group_units<D, Shape, Real, kMomentumOnly, false>();
  struct NoDeferred {
    explicit NoDeferred(const GridView<D, Real>&) {}
  };
  std::conditional_t<kDefer, GroupedScatter<D, Shape, Real, kMomentumOnly, false, kDeferUG>,
                     NoDeferred>
      deferred(G);
  auto momentum_source = [&](std::size_t p) __attribute__((always_inline)) {
    return scatter_source<D, Real, kMomentumOnly, false>(P, P2GOptions{}, Real(1), p);
  };
  auto scatter_momentum = [&](const Weights& w, std::size_t p, std::size_t fo)
      __attribute__((always_inline)) {
    if constexpr (kDefer) return;  // after the batch
    const ScatterSource<D, Real> s = momentum_source(p);
    if constexpr (Windowed) {
      block.at(w.base + fo, G, off);
      block.accumulate(w, s);
    } else {
      for (int k = 0; k < w.count; ++k) {
        const std::size_t i = w.base + fo + w.node[k];
        for (int d = 0; d < D; ++d) G.p[d][i] += w.w[k] * s.mv[d];
      }
    }
  };
  auto build = [&](std::size_t first, std::size_t n, Weights * w, bool* ok)
      __attribute__((always_inline)) {
    st.build_batch(P, first, n, w, ok);
  };
  auto transfer = [&](std::size_t p, const Weights* weights) __attribute__((always_inline)) {
    if (!weights) {
      if (r.bad == SIZE_MAX) r.bad = p;
      return true;
    }
    const Weights& w = *weights;
    const std::size_t fo = field_offset<MultiField>(P, G, p);
    if (detail::rigid_motion<D, Real, What, MultiField>(P, q, dt, p)) {
      if constexpr (kScatter) scatter_momentum(w, p, fo);
      return true;
    }
    Real vn[D] = {}, dv[D] = {}, L[D * D] = {};
    st.template gather<(What & kUpdateMotion) != 0, (What & kVelocityGradient) != 0>(w, V, fo, held,
                                                                                     vn, dv, L);
    detail::update_particle<D, Real, What, Traction, Gravity>(P, q, dt, flip, pic, p, vn, dv, L, r,
                                                              stress);
    if constexpr (kScatter) scatter_momentum(w, p, fo);
    return true;
  };
  // The deferred scatter's sources, filled in place batch by batch (zeroed
  // once here, not once per batch).
  struct NoSources {};
  std::conditional_t<kDefer, std::array<ScatterSource<D, Real>, kWeightBatch>, NoSources> sources{};
  auto after_batch = [&](std::size_t first, std::size_t n, const Weights* w, const bool* ok) {
    if constexpr (kDefer) {
      std::size_t base[kWeightBatch];
      std::size_t count = 0;
      for (; count < n && ok[count]; ++count) {
        const std::size_t p = first + count;
        base[count] = w[count].base + field_offset<MultiField>(P, G, p);
        fill_scatter_source<D, Real, kMomentumOnly, false>(sources[count], P, P2GOptions{}, Real(1),
                                                          p);
      }
      const ScatterSource<D, Real>* s = sources.data();
      deferred.add(w, base, s, count, count == n && first + n < end);
    }
  };
  for_each_weighted<Weights>(begin, end, build, transfer, after_batch);
  if constexpr (kDefer)
    deferred.finish();
  else if constexpr (kScatter && Windowed)
    block.flush(G, off);
  // Positions moved in this pass (in place, or committed from x_next): did a
  // particle leave its tile? One vectorised test of the range, after the loop.
  constexpr bool kMoves = (What & (kCommitPosition | kUpdateMotion)) != 0;
  if (kMoves && ((What & kCommitPosition) != 0 || !P.x_next[0]))
    r.moved_tile = key_of.any_moved(P.key, begin, end);
  return r;
}

// The solver's G2P: packed for 2D linear (kernels/g2p_packed.hpp, the same
// gathered sums), else windowed, and
// pointwise (node by node) only for grids too small for a window. 2D
// linear was pointwise while its windows were built particle by particle
// (12.7 vs 13.6 ns/particle); with the windows built a batch at a time
// (WindowBuilder::build_batch) the window wins there too
// (docs/performance.md "Windows a batch at a time, across particles").
template <int D, class Shape, class Real, unsigned What, bool MultiField, bool Traction,
          bool Gravity, class KeyFn, class StressFn = NoStressUpdate>
G2PRangeResult g2p_range(const ParticleView<D, Real>& P, const GridView<D, Real>& G,
                         const GridVelocity<D, Real>& V, const G2PParams& q, const KeyFn& key_of,
                         std::size_t begin, std::size_t end, const StressFn& stress = {}) {
  if constexpr (packed_gather_pays<D, Shape, Real>())
    if (Window<D, Shape, Real>::fits(G))
      return g2p_range_packed<Real, What, MultiField, Traction, Gravity>(P, G, V, q, key_of, begin,
                                                                         end, stress);
  if (Window<D, Shape, Real>::fits(G))
    return g2p_range_impl<D, Shape, Real, What, MultiField, Traction, Gravity, true>(
        P, G, V, q, key_of, begin, end, stress);
  return g2p_range_impl<D, Shape, Real, What, MultiField, Traction, Gravity, false>(
      P, G, V, q, key_of, begin, end, stress);
}

// The reference gather, node by node (benchmark baseline).
template <int D, class Shape, class Real, unsigned What, bool MultiField, bool Traction,
          bool Gravity, class KeyFn>
G2PRangeResult g2p_range_pointwise(const ParticleView<D, Real>& P, const GridView<D, Real>& G,
                                   const GridVelocity<D, Real>& V, const G2PParams& q,
                                   const KeyFn& key_of, std::size_t begin, std::size_t end) {
  return g2p_range_impl<D, Shape, Real, What, MultiField, Traction, Gravity, false>(
      P, G, V, q, key_of, begin, end);
}

}  // namespace mmpm
