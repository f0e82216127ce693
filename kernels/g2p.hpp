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
#include "kernels/grid_prefetch.hpp"
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
// Pairs = false: never two particles per vector (the benchmark baseline).
template <int D, class Shape, class Real, bool Windowed, bool Pairs = true>
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
  //
  // Two particles at a time (kPairs: windows of one row of 4 nodes per
  // unit, AVX-512: the shapes binned by the nearest node, 2D and 3D in
  // double, 2D in float): the window's rows are held twice over, one copy
  // per half vector, so a pair of particles of one window runs every
  // product and sum in one vector (gather_pair; 512 bits in double, 256 in
  // float). The one-particle gather reads the lower half.
  static constexpr bool kPairs =
      Pairs && Windowed && Win::W == 4 && Win::L == 4 && kRegisterVectorBytes == 64;
  using V2 = Lanes<Real, 8>;
  using HeldVec = std::conditional_t<kPairs, V2, typename Win::V>;
  struct WindowValues {
    std::size_t base = SIZE_MAX;
    HeldVec vel[D][Win::units] = {}, dvel[D][Win::units] = {};
  };
  struct NoValues {};
  using Held = std::conditional_t<Windowed, WindowValues, NoValues>;

  // Unit u of one array, held as HeldVec.
  template <int u>
  [[gnu::always_inline]] HeldVec held_load(const Real* a) const {
    const auto v = Win::template load<u>(a, offsets);
    if constexpr (kPairs)
      return __builtin_shufflevector(v, v, 0, 1, 2, 3, 0, 1, 2, 3);
    else
      return v;
  }
  // The one-particle unit of a held vector.
  [[gnu::always_inline]] static typename Win::V held_row(const HeldVec& v) {
    if constexpr (kPairs)
      return __builtin_shufflevector(v, v, 0, 1, 2, 3);
    else
      return v;
  }
  // Loads the window at b unless it is the one held.
  template <bool Motion>
  [[gnu::always_inline]] void hold(const GridVelocity<D, Real>& V, std::size_t b,
                                   Held& held) const {
    if (b == held.base) return;
    held.base = b;
    static_for<Win::units>([&](auto uc) __attribute__((always_inline)) {
      constexpr int u = decltype(uc)::value;
      for (int d = 0; d < D; ++d) {
        held.vel[d][u] = held_load<u>(V.vel[d] + b);
        if constexpr (Motion) held.dvel[d][u] = held_load<u>(V.dvel[d] + b);
      }
    });
  }

  // vn, dv: velocity and its change over the step; L row-major dv_a/dx_b.
  // Velocity: vn without dv (the separation shift of the gradient pass;
  // the windowed sums form S v with the gradient's anyway).
  template <bool Motion, bool Gradient, bool Velocity = Motion>
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
          if constexpr (Motion || Velocity) vn[d] += s * vi;
          if constexpr (Motion) dv[d] += s * V.dvel[d][i];
          if constexpr (Gradient)
            for (int e = 0; e < D; ++e) L[d * D + e] += vi * w.g[k][e];
        }
      }
    } else {
      // Unit sums A = sum_u Y(u) v_u, B = sum_u GY(u) v_u, C = sum_u GZ(u) v_u,
      // then v_p = sum(X A), L_d,x = sum(GX A), L_d,y = sum(X B), L_d,z = sum(X C).
      using Vec = typename Win::V;
      constexpr int Ln = Win::L;
      hold<Motion>(V, b, held);
      Vec A[D] = {}, B[D] = {}, C[D] = {}, Q[D] = {};
      static_for<Win::units>([&](auto uc) __attribute__((always_inline)) {
        constexpr int u = decltype(uc)::value;
        const Vec Yu = w.template Y<u>(), GYu = w.template GY<u>(), GZu = w.template GZ<u>();
        for (int d = 0; d < D; ++d) {
          const Vec vu = held_row(held.vel[d][u]);
          A[d] += Yu * vu;
          if constexpr (Gradient) {
            B[d] += GYu * vu;
            if constexpr (D == 3) C[d] += GZu * vu;
          }
          if constexpr (Motion) Q[d] += Yu * held_row(held.dvel[d][u]);
        }
      });
      const Vec X = w.X(), GX = w.GX();
      if constexpr (D == 2 && (Ln == 8 || Ln == 16)) {
        // The eight dot products of both directions in one shuffle tree:
        // lanes_sum8 adds as the four-at-a-time branch below does, bit for
        // bit, in fewer, whole-register shuffles.
        const Vec parts[8] = {X * A[0], X * Q[0], GX * A[0], X * B[0],
                              X * A[1], X * Q[1], GX * A[1], X * B[1]};
        const Lanes<Real, 8> s = lanes_sum8<Real, Ln>(parts);
        for (int d = 0; d < D; ++d) {
          if constexpr (Motion || Velocity) vn[d] = s[4 * d];
          if constexpr (Motion) dv[d] = s[4 * d + 1];
          if constexpr (Gradient) L[d * D + 0] = s[4 * d + 2], L[d * D + 1] = s[4 * d + 3];
        }
        return;
      }
      for (int d = 0; d < D; ++d) {
        if constexpr (Ln >= 4) {
          // Four dot products at once (a shuffle tree, not four serial sums).
          const Lanes<Real, 4> s1 =
              lanes_sum4(lanes_fold4<Real, Ln>(X * A[d]), lanes_fold4<Real, Ln>(X * Q[d]),
                         lanes_fold4<Real, Ln>(GX * A[d]), lanes_fold4<Real, Ln>(X * B[d]));
          if constexpr (Motion || Velocity) vn[d] = s1[0];
          if constexpr (Motion) dv[d] = s1[1];
          if constexpr (Gradient) {
            L[d * D + 0] = s1[2];
            L[d * D + 1] = s1[3];
            if constexpr (D == 3) L[d * D + 2] = lanes_sum<Real, Ln>(X * C[d]);
          }
        } else {
          if constexpr (Motion || Velocity) vn[d] = lanes_sum<Real, Ln>(X * A[d]);
          if constexpr (Motion) dv[d] = lanes_sum<Real, Ln>(X * Q[d]);
          if constexpr (Gradient) {
            L[d * D + 0] = lanes_sum<Real, Ln>(GX * A[d]);
            L[d * D + 1] = lanes_sum<Real, Ln>(X * B[d]);
            if constexpr (D == 3) L[d * D + 2] = lanes_sum<Real, Ln>(X * C[d]);
          }
        }
      }
    }
  }

  // gather() for two particles a and b of one window (base b0, field offset
  // included), lanes 0-3 particle a's, 4-7 particle b's. Every lane runs
  // gather()'s operations in gather()'s order (the same products Y v,
  // GY v, GZ v, Y dv, unit by unit, then the same tree of sums), so each
  // particle gets gather()'s bits (tests/test_p2g.cpp
  // G2PPairGather.SameBitsAsOneParticle): which particles pair up may
  // depend on the thread's range without changing a result. Why: gather()
  // runs 4-lane vectors, half an AVX-512 register; pairs take 6-9 % off
  // the 3D G2P kernels on one thread (docs/performance.md "Two particles
  // per vector in the 3D gathers"), and 2D's since its windows have 3 rows
  // ("The same in 2D double").
  template <bool Motion, bool Gradient, bool Velocity = Motion>
  [[gnu::always_inline]] void gather_pair(const Weights& wa, const Weights& wb,
                                          const GridVelocity<D, Real>& V, std::size_t b0,
                                          Held& held, Real (*vn)[D], Real (*dv)[D],
                                          Real (*L)[D * D]) const requires(kPairs) {
    constexpr int W = Win::W, WY = Win::WY;
    hold<Motion>(V, b0, held);
    // Lane k of the pair: lane j of a's weights for k < 4, of b's for k >= 4.
    auto pair_lane =
        []<class VA>(const VA& a, const VA& b, auto jc) __attribute__((always_inline)) {
      constexpr int j = decltype(jc)::value, n = int(sizeof(VA) / sizeof(Real));
      return V2(__builtin_shufflevector(a, b, j, j, j, j, n + j, n + j, n + j, n + j));
    };
    // 2D has no z factor: Window::Y is the y weight alone (wz, dwz unused).
    V2 wy[WY], dwy[WY], wz[WY], dwz[WY];
    static_for<WY>([&](auto jc) __attribute__((always_inline)) {
      constexpr int j = decltype(jc)::value;
      wy[j] = pair_lane(wa.wa, wb.wa, std::integral_constant<int, W + j>{});
      if constexpr (D == 3)
        wz[j] = pair_lane(wa.wa, wb.wa, std::integral_constant<int, 2 * W + j>{});
      if constexpr (Gradient) {
        dwy[j] = pair_lane(wa.dwa, wb.dwa, std::integral_constant<int, W + j>{});
        if constexpr (D == 3)
          dwz[j] = pair_lane(wa.dwa, wb.dwa, std::integral_constant<int, 2 * W + j>{});
      }
    });
    V2 A[D] = {}, B[D] = {}, C[D] = {}, Q[D] = {};
    static_for<Win::units>([&](auto uc) __attribute__((always_inline)) {
      constexpr int u = decltype(uc)::value, jy = u % WY, jz = u / WY;  // one row per unit
      // Window::Y / GY / GZ: the y factor times the z factor, lane by lane.
      V2 Yu = wy[jy];
      if constexpr (D == 3) Yu = Yu * wz[jz];
      for (int d = 0; d < D; ++d) {
        const V2 vu = held.vel[d][u];
        A[d] += Yu * vu;
        if constexpr (Gradient) {
          if constexpr (D == 3) {
            const V2 GYu = dwy[jy] * wz[jz], GZu = wy[jy] * dwz[jz];
            B[d] += GYu * vu;
            C[d] += GZu * vu;
          } else {
            B[d] += dwy[jy] * vu;
          }
        }
        if constexpr (Motion) Q[d] += Yu * held.dvel[d][u];
      }
    });
    // Lanes 0-3 of a's x weights, then b's (n: lanes of a weight vector).
    constexpr int n = int(sizeof(wa.wa) / sizeof(Real));
    const V2 X = __builtin_shufflevector(wa.wa, wb.wa, 0, 1, 2, 3, n, n + 1, n + 2, n + 3);
    const V2 GX = __builtin_shufflevector(wa.dwa, wb.dwa, 0, 1, 2, 3, n, n + 1, n + 2, n + 3);
    for (int d = 0; d < D; ++d) {
      // lanes_sum4 on each half: {sum XA, sum XQ, sum GX A, sum XB} per particle.
      const V2 a = X * A[d], q = X * Q[d], c = GX * A[d], e = X * B[d];
      const V2 aq = __builtin_shufflevector(a, q, 0, 8, 2, 10, 4, 12, 6, 14) +
                    __builtin_shufflevector(a, q, 1, 9, 3, 11, 5, 13, 7, 15);
      const V2 ce = __builtin_shufflevector(c, e, 0, 8, 2, 10, 4, 12, 6, 14) +
                    __builtin_shufflevector(c, e, 1, 9, 3, 11, 5, 13, 7, 15);
      const V2 s1 = __builtin_shufflevector(aq, ce, 0, 1, 8, 9, 4, 5, 12, 13) +
                    __builtin_shufflevector(aq, ce, 2, 3, 10, 11, 6, 7, 14, 15);
      for (int k = 0; k < 2; ++k) {
        if constexpr (Motion || Velocity) vn[k][d] = s1[4 * k];
        if constexpr (Motion) dv[k][d] = s1[4 * k + 1];
        if constexpr (Gradient) {
          L[k][d * D + 0] = s1[4 * k + 2];
          L[k][d * D + 1] = s1[4 * k + 3];
        }
      }
    }
    if constexpr (Gradient && D == 3) {
      // L_d,z = lanes_sum(X C[d]) per particle: a serial sum from 0 (gather()'s
      // order), for the 3 directions and 2 particles at once. Transposed by
      // shuffles, lane 2d + k of the l-th vector added is lane l of particle
      // k's X C[d], so each sum gets its lanes in lanes_sum's order (24 lane
      // extracts and scalar adds were the alternative).
      const V2 xc0 = X * C[0], xc1 = X * C[1], xc2 = X * C[2];
      V2 sum = V2{};
      static_for<4>([&](auto lc) __attribute__((always_inline)) {
        constexpr int l = decltype(lc)::value;
        const V2 t01 = __builtin_shufflevector(xc0, xc1, l, 4 + l, 8 + l, 12 + l, l, l, l, l);
        sum += __builtin_shufflevector(t01, xc2, 0, 1, 2, 3, 8 + l, 12 + l, 0, 0);
      });
      for (int d = 0; d < D; ++d)
        for (int k = 0; k < 2; ++k) L[k][d * D + 2] = sum[2 * d + k];
    }
  }
};

// Where MUSL's fused pass scatters the momenta: the solver's choice
// (automatic, below), in the block beside the gathers, or after each batch.
enum class MomentumScatterAt { automatic, inline_block, after_batch };

// PairGathers = false keeps the one-particle gather where pairs would run
// (G2PGather::kPairs), the baseline bench/bench_g2p.cpp measures them against.
template <int D, class Shape, class Real, unsigned What, bool MultiField, bool Traction,
          bool Gravity, bool Windowed, bool PairGathers = true,
          MomentumScatterAt ScatterAt = MomentumScatterAt::automatic, class KeyFn,
          class StressFn = NoStressUpdate>
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
  using Gather = G2PGather<D, Shape, Real, Windowed, PairGathers>;
  Gather st(G);
  typename Gather::Held held;
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
  using Weights = typename Gather::Weights;
  // The windowed passes request the grid lines a line ahead; the pointwise
  // kernel (grids too small for a window) does not.
  auto ahead =
      gather_lines_ahead<What, Window<D, Shape, Real>>(Windowed && q.prefetch_grid, off, G, V);
  // When the momentum block and the gather's sums (2D vectors) do not fit in
  // the registers together (3D cubic B-splines in double: 8 units x 3 + 6),
  // the momenta of a batch are scattered after its gathers, by
  // GroupedScatter (kernels/window_block.hpp), from the same windows: the
  // same sums in the same order. A particle off the grid ends the batch's
  // scatter there (the step fails on it anyway). Counted in the block's own
  // units (ScatterUnits: 3D uGIMP and quadratic B-splines in double, 5 x 3 +
  // 6, stay inline: the 3D uGIMP step's G2P stage -5 to -10 % against
  // deferred, docs/performance.md "MUSL's momenta scattered beside the
  // gathers again").
  using Scatter = ScatterUnits<D, Shape, Real>;
  constexpr bool kDefer =
      kScatter && Windowed &&
      (ScatterAt == MomentumScatterAt::automatic
           ? D * Scatter::units + 2 * D > block_register_budget<typename Scatter::V>()
           : ScatterAt == MomentumScatterAt::after_batch);
  constexpr int kDeferUG = block_group_units<D, Shape, Real, kMomentumOnly, false>();
  struct NoDeferred {
    explicit NoDeferred(const GridView<D, Real>&) {}
  };
  std::conditional_t<kDefer, GroupedScatter<D, Shape, Real, kMomentumOnly, false, kDeferUG>,
                     NoDeferred>
      deferred(G);
  auto scatter_momentum = [&](const Weights& w, std::size_t p, std::size_t fo)
      __attribute__((always_inline)) {
    if constexpr (kDefer) return;  // after the batch
    // m and m v of particle p (the momentum pass has no force terms).
    const ScatterSource<D, Real> s =
        scatter_source<D, Real, kMomentumOnly, false>(P, P2GOptions{}, Real(1), p);
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
  // With kPairs the batch's gathers run right after its windows are built,
  // two particles of one window at a time (G2PGather::gather_pair), into
  // these arrays; the particles' updates then read them. The gathers read
  // only the grid, so running them first changes nothing. Entries a pass
  // does not gather stay 0, as gather()'s zeroed locals.
  constexpr bool kPairs = Gather::kPairs;
  constexpr bool kMotion = (What & kUpdateMotion) != 0, kGradient = (What & kVelocityGradient) != 0;
  constexpr bool kVelocity = kMotion || (What & kSeparationShift) != 0;
  static_assert((What & kSeparationShift) == 0 || (What & kCommitPosition) != 0,
                "the shift reads x_next before the commit");
  struct Gathered {
    Real vn[kWeightBatch][D] = {}, dv[kWeightBatch][D] = {}, L[kWeightBatch][D * D] = {};
    std::size_t first = 0;
  };
  struct NoGathered {};
  std::conditional_t<kPairs, Gathered, NoGathered> gathered;
  auto build = [&](std::size_t first, std::size_t n, Weights * w, bool* ok)
      __attribute__((always_inline)) {
    if (q.particles_ahead) q.particles_ahead->batch(first, n);
    st.build_batch(P, first, n, w, ok);
    if constexpr (Windowed)
      ahead.batch(n, [&](std::size_t i) {
        return ok[i] ? w[i].base + field_offset<MultiField>(P, G, first + i) : SIZE_MAX;
      });
    if constexpr (kPairs) {
      gathered.first = first;
      for (std::size_t i = 0; i < n;) {
        if (!ok[i]) {
          ++i;
          continue;
        }
        const std::size_t b = w[i].base + field_offset<MultiField>(P, G, first + i);
        if (i + 1 < n && ok[i + 1] &&
            w[i + 1].base + field_offset<MultiField>(P, G, first + i + 1) == b) {
          st.template gather_pair<kMotion, kGradient, kVelocity>(
              w[i], w[i + 1], V, b, held, gathered.vn + i, gathered.dv + i, gathered.L + i);
          i += 2;
        } else {
          st.template gather<kMotion, kGradient, kVelocity>(
              w[i], V, b - w[i].base, held, gathered.vn[i], gathered.dv[i], gathered.L[i]);
          i += 1;
        }
      }
    }
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
    if constexpr (kPairs) {
      (void)fo;  // read above only by the momentum scatter
      const std::size_t i = p - gathered.first;
      detail::update_particle<D, Real, What, Traction, Gravity>(
          P, q, dt, flip, pic, p, gathered.vn[i], gathered.dv[i], gathered.L[i], r, stress);
    } else {
      Real vn[D] = {}, dv[D] = {}, L[D * D] = {};
      st.template gather<kMotion, kGradient, kVelocity>(w, V, fo, held, vn, dv, L);
      detail::update_particle<D, Real, What, Traction, Gravity>(P, q, dt, flip, pic, p, vn, dv, L,
                                                                r, stress);
    }
    if constexpr (kScatter) scatter_momentum(w, p, fo);
    return true;
  };
  // The deferred scatter's sources, field by field, filled batch by batch.
  struct NoSources {};
  std::conditional_t<kDefer, ScatterSourceBatch<D, Real>, NoSources> sources;
  auto after_batch = [&](std::size_t first, std::size_t n, const Weights* w, const bool* ok) {
    if constexpr (kDefer) {
      std::size_t base[kWeightBatch];
      std::size_t count = 0;
      for (; count < n && ok[count]; ++count)
        base[count] = w[count].base + field_offset<MultiField>(P, G, first + count);
      sources.template fill<kMomentumOnly, false>(P, P2GOptions{}, Real(1), first, count);
      deferred.add(w, base, sources, count, count == n && first + n < end);
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
