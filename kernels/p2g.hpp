// Particle-to-grid transfer (ALGORITHM §1 and §2 step 2), one tile at a
// time. The caller runs tiles color by color; tiles of one color touch
// disjoint nodes, so threads add straight into the grid with no atomics.
#pragma once

#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "kernels/grid_prefetch.hpp"
#include "kernels/p2g_packed.hpp"
#include "kernels/weight_batch.hpp"
#include "kernels/weights.hpp"
#include "kernels/window_block.hpp"

namespace mmpm {

// The reference scatter: every particle adds into its stencil's nodes one
// by one. Kept as the baseline the benchmarks compare the windowed scatter
// with, and for grids too small to hold a window. Scatters particles
// [begin, end); returns the first particle whose stencil leaves the grid, or
// end.
template <int D, class Shape, class Real, unsigned What, bool MultiField, bool Traction>
std::size_t p2g_range_pointwise(const ParticleView<D, Real>& P, const GridView<D, Real>& G,
                                const P2GOptions& opt, std::size_t begin, std::size_t end) {
  constexpr int NS = kStressComponents<D>;
  const std::array<Real, 3> inv_h{Real(1) / G.h[0], Real(1) / G.h[1], Real(1) / G.h[2]};
  const Real inv_t = Real(opt.inv_thickness);
  Stencil<D, Shape, Real> st{};
  for (std::size_t p = begin; p < end; ++p) {
    if (!st.build(P, G, inv_h, p)) return p;
    const std::size_t fo = field_offset<MultiField>(P, G, p);
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
        mw[d] = mp * separation_coordinate(P, opt.position_separation, d, p);
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
        for (int d = 0; d < D; ++d) G.mx[d][i] += w * mw[d];
        if constexpr ((What & kDomainGradient) != 0)
          for (int d = 0; d < D; ++d) G.g[d][i] += st.g[k][d] * area;
      }
    }
  }
  return end;
}

// The windowed scatter for blocks that do not fit in the registers
// (GroupedScatter, kernels/window_block.hpp): each run of particles with the
// same window is scattered once per group of UG units, so each group's sums
// stay in registers. One block of all units spilled to the stack: every
// particle then loaded and stored every sum (3D uGIMP double P2G 80 -> 67-75
// ns/particle). Bitwise the one-block sums. The caller has checked
// Window::fits. Returns as p2g_range.
template <int D, class Shape, class Real, unsigned What, bool MultiField, bool Traction, int UG,
          class Units = ScatterUnits<D, Shape, Real>>
std::size_t p2g_range_grouped(const ParticleView<D, Real>& particles, const GridView<D, Real>& grid,
                              const P2GOptions& opt, std::size_t begin, std::size_t end) {
  const ParticleView<D, Real> P = particles;
  const GridView<D, Real> G = grid;
  using Win = Window<D, Shape, Real>;
  const Real inv_t = Real(opt.inv_thickness);
  const WindowBuilder<D, Shape, Real> builder(G);
  GroupedScatter<D, Shape, Real, What, Traction, UG, Units> scatter(G);
  auto ahead = scatter_lines_ahead<What, Win>(opt.prefetch_grid, Win::offsets(G), G);
  Win w[kWeightBatch];
  ScatterSourceBatch<D, Real> q;
  std::size_t base[kWeightBatch];
  for (std::size_t first = begin; first < end; first += kWeightBatch) {
    const std::size_t n = std::min(kWeightBatch, end - first);
    bool inside[kWeightBatch];
    if (opt.particles_ahead) opt.particles_ahead->batch(first, n);
    builder.build_batch(P, first, n, w, inside);
    std::size_t ok = 0;
    while (ok < n && inside[ok]) ++ok;
    for (std::size_t i = 0; i < ok; ++i)
      base[i] = w[i].base + field_offset<MultiField>(P, G, first + i);
    ahead.batch(ok, [&](std::size_t i) { return base[i]; });
    q.template fill<What, Traction>(P, opt, inv_t, first, ok);
    scatter.add(w, base, q, ok, ok == n && first + n < end);
    if (ok < n) return first + ok;  // nothing carried: `more` was false
  }
  scatter.finish();
  return end;
}

// The windowed scatter with one block for the whole window (its sums fit in
// the registers). The caller has checked Window::fits. Returns as p2g_range.
template <int D, class Shape, class Real, unsigned What, bool MultiField, bool Traction,
          class Units = ScatterUnits<D, Shape, Real>>
std::size_t p2g_range_one_block(const ParticleView<D, Real>& particles,
                                const GridView<D, Real>& grid, const P2GOptions& opt,
                                std::size_t begin, std::size_t end) {
  // Local copies of the views: the grid stores below cannot alias them, so
  // the array pointers stay in registers.
  const ParticleView<D, Real> P = particles;
  const GridView<D, Real> G = grid;
  using Win = Window<D, Shape, Real>;
  using Block = WindowBlock<D, Shape, Real, What, Traction, Units::units, Units>;
  const Real inv_t = Real(opt.inv_thickness);
  const auto off = Win::offsets(G);
  Block block;
  const WindowBuilder<D, Shape, Real> builder(G);
  auto ahead = scatter_lines_ahead<What, Win>(opt.prefetch_grid, off, G);
  // In float, the batch's factors m, m v, V sigma, ... are computed in a
  // loop across its particles (vectorised) and the scatter reads them from
  // memory: per particle they cost a few scalar multiplies and a
  // register-to-vector broadcast each, on the vector ports that bound this
  // kernel, where a broadcast from memory is a load. Measured: float P2G
  // 3-11 % faster, double 0-3 % slower (docs/performance.md "Scatter
  // sources a batch at a time in the one-block scatter"). The same
  // products, so the same bits.
  constexpr bool kBatchSources = std::is_same_v<Real, float>;
  ScatterSourceBatch<D, Real> sources;
  std::size_t batch_first = begin;
  auto build = [&](std::size_t first, std::size_t n, Win * w, bool* ok)
      __attribute__((always_inline)) {
    if (opt.particles_ahead) opt.particles_ahead->batch(first, n);
    builder.build_batch(P, first, n, w, ok);
    ahead.batch(n, [&](std::size_t i) {
      return ok[i] ? w[i].base + field_offset<MultiField>(P, G, first + i) : SIZE_MAX;
    });
    if constexpr (kBatchSources) {
      sources.template fill<What, Traction>(P, opt, inv_t, first, n);
      batch_first = first;
    }
  };
  auto scatter = [&](std::size_t p, const Win* win) __attribute__((always_inline)) {
    if (!win) return false;
    block.at(win->base + field_offset<MultiField>(P, G, p), G, off);
    if constexpr (kBatchSources)
      block.accumulate(*win, sources.template at<What, Traction>(p - batch_first));
    else
      block.accumulate(*win, scatter_source<D, Real, What, Traction>(P, opt, inv_t, p));
    return true;
  };
  const std::size_t stop = for_each_weighted<Win>(begin, end, build, scatter);
  block.flush(G, off);
  return stop;
}

// The solver's scatter (kernels/window.hpp explains the window): particles
// of one window (consecutive in the binning order: same cell and field) add
// into a local block, which goes to the grid when the window changes. Same
// sums as p2g_range_pointwise, in a different order (round-off level).
// 2D linear with AVX-512 packs 2 or 4 particles per vector
// (kernels/p2g_packed.hpp). Units: the block's vector layout
// (kernels/window.hpp; RowUnits is the benchmarks' baseline). Scatters
// particles [begin, end); returns the first particle whose stencil leaves
// the grid, or end.
template <int D, class Shape, class Real, unsigned What, bool MultiField, bool Traction,
          class Units = ScatterUnits<D, Shape, Real>>
std::size_t p2g_range(const ParticleView<D, Real>& P, const GridView<D, Real>& G,
                      const P2GOptions& opt, std::size_t begin, std::size_t end) {
  using Win = Window<D, Shape, Real>;
  if (!Win::fits(G))
    return p2g_range_pointwise<D, Shape, Real, What, MultiField, Traction>(P, G, opt, begin, end);
  constexpr int UG = block_group_units<D, Shape, Real, What, Traction, Units>();
  if constexpr (packed_particles<D, Shape, Real>() > 1)
    return p2g_range_packed<Real, What, MultiField, Traction>(P, G, opt, begin, end);
  else if constexpr (UG < Units::units)
    return p2g_range_grouped<D, Shape, Real, What, MultiField, Traction, UG, Units>(P, G, opt,
                                                                                    begin, end);
  else
    return p2g_range_one_block<D, Shape, Real, What, MultiField, Traction, Units>(P, G, opt, begin,
                                                                                  end);
}

}  // namespace mmpm
