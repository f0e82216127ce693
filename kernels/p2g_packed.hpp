// The 2D linear scatter with K particles in one 64-byte vector (K = 2 in
// double, 4 in float).
//
// Why: a 2D linear window is 2 x 2 nodes (kernels/window.hpp), 4 lanes: half
// an AVX-512 register in double, a quarter in float. The one-particle block
// (kernels/window_block.hpp) therefore ran every multiply-add at a half or a
// quarter of the register, and each particle paid ~20 instructions for its
// window (the per-particle shape-function loop of build_batch) and ~18 for
// its factors (scalar loads, products, broadcasts): ~87 instructions per
// particle at an IPC of about 4.5, so the kernel was bound by the count of
// instructions, not by memory (docs/performance.md "Two or four
// particles per vector"). Here consecutive particles of one window share the vector:
//  - the factors of K particles come from one K-lane load per array, their
//    products are K-lane operations, and one shuffle spreads a factor over
//    its particle's 4 lanes;
//  - the window's lanes are computed straight from the distances that
//    locate_batch stored (hat 1 - |d| and its derivative's sign, the
//    LinearShape::lanes formulas, bitwise the same lanes);
//  - the block keeps one partial sum per particle slot and adds the slots
//    together when it goes to the grid.
// The sums per node are those of the one-particle block in another order
// (the slots' partial sums, then slot 0 + slot 1 (+ (2 + 3))): round-off
// level, and the same bits for any thread count since the slots depend only
// on the particle order within a tile (tests/test_p2g.cpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "kernels/grid_prefetch.hpp"
#include "kernels/packed_linear.hpp"
#include "kernels/window_block.hpp"

namespace mmpm {

// The factors (ScatterSource) of K consecutive particles, one lane each;
// lanes at and past `count` are 0, so they add nothing.
template <class Real, int K, unsigned What, bool Traction>
struct PackedSource {
  using S = Lanes<Real, K>;
  S m{}, mv[2]{}, vs[3]{}, fe[2]{}, area{}, mw[2]{};

  template <bool Full>
  [[gnu::always_inline]] static S lanes_of(const Real* a, std::size_t p, int count) {
    if constexpr (Full) {
      return lanes_load<S>(a + p);
    } else {
      S v{};
      for (int k = 0; k < count; ++k) v[k] = a[p + k];
      return v;
    }
  }

  // Particles p .. p + count - 1 (Full: count == K). The products are
  // scatter_source's, lane by lane (the same bits).
  template <bool Full>
  [[gnu::always_inline]] static PackedSource make(const ParticleView<2, Real>& P,
                                                  const P2GOptions& opt, Real inv_t, std::size_t p,
                                                  int count) {
    PackedSource q;
    q.m = lanes_of<Full>(P.m, p, count);
    for (int d = 0; d < 2; ++d) q.mv[d] = q.m * lanes_of<Full>(P.v[d], p, count);
    if constexpr ((What & kForce) != 0) {
      const S V = lanes_of<Full>(P.V, p, count);
      for (int c = 0; c < 3; ++c) q.vs[c] = V * lanes_of<Full>(P.s[c], p, count);
      if constexpr (Traction)
        for (int d = 0; d < 2; ++d) q.fe[d] = lanes_of<Full>(P.fext[d], p, count);
    }
    if constexpr ((What & kMultimaterial) != 0) {
      q.area = lanes_of<Full>(P.V, p, count) * inv_t;
      for (int d = 0; d < 2; ++d) {
        const S x = lanes_of<Full>(P.x[d], p, count);
        S u = opt.position_separation ? x : x - lanes_of<Full>(P.x0[d], p, count);
        if constexpr (std::is_same_v<Real, float>)  // separation_coordinate, K lanes
          if (!opt.position_separation && P.xlo[0]) u += lanes_of<Full>(P.xlo[d], p, count);
        if (!opt.position_separation && P.sep_shift[0])
          u += lanes_of<Full>(P.sep_shift[d], p, count);
        q.mw[d] = q.m * u;
      }
    }
    return q;
  }
};

// The place of a sum the block does not make.
struct NoSum {};

// Sums of one window's particles, K particle slots of 4 lanes per vector
// (lane k * 4 + l: slot k, window lane l = x node l % 2, row l / 2).
template <class Real, unsigned What, bool Traction, int K>
struct PackedLinearBlock {
  using Win = Window<2, LinearShape, Real>;
  static constexpr int L = Win::L;  // 4
  using V = typename Win::V;
  using VW = Lanes<Real, K * L>;
  using S = Lanes<Real, K>;
  using Source = PackedSource<Real, K, What, Traction>;
  using Base = WindowBlock<2, LinearShape, Real, What, Traction>;  // for the quantity flags
  static constexpr bool kMass = Base::kMass, kMom = Base::kMom, kFrc = Base::kFrc, kMM = Base::kMM,
                        kGrad = Base::kGrad;

  // Only the sums What asks for take storage: a block cut by the end of a
  // weight batch is copied into `carried` and back (p2g_range_packed), and
  // with all eleven sums (704 bytes) GCC copied and zeroed it through
  // memcpy / memset calls: 2D linear P2G 5.8 -> 5.0 ns/particle without
  // them (docs/performance.md "P2G's time without memory").
  template <bool Used>
  using SumIf = std::conditional_t<Used, VW, NoSum>;
  [[no_unique_address]] SumIf<kMass> am{};
  SumIf<kMom> ap[2]{};
  SumIf<kFrc> af[2]{};
  [[no_unique_address]] SumIf<kMM> avol{};
  SumIf<kMM> amx[2]{};
  SumIf<kGrad> ag[2]{};
  std::size_t current = SIZE_MAX;  // window base (with field offset); SIZE_MAX: none

  // Slots k0 .. k0 + count - 1 added pairwise (lane l: window lane l).
  template <int k0, int count>
  [[gnu::always_inline]] static V slot_sum(const VW& a) {
    if constexpr (count == 1)
      return lanes_pick<L>(a, [](int l) { return k0 * L + l; });
    else
      return slot_sum<k0, count / 2>(a) + slot_sum<k0 + count / 2, count / 2>(a);
  }

  [[gnu::always_inline]] void flush(const GridView<2, Real>& G, const typename Win::Offsets& off) {
    if (current == SIZE_MAX) return;
    const std::size_t b = current;
    auto add = [&](Real * a, const VW& v) __attribute__((always_inline)) {
      Win::template add<0>(a + b, off, slot_sum<0, K>(v));
    };
    if constexpr (kMass) add(G.m, am);
    for (int d = 0; d < 2; ++d) {
      if constexpr (kMom) add(G.p[d], ap[d]);
      if constexpr (kFrc) add(G.f[d], af[d]);
      if constexpr (kMM) add(G.mx[d], amx[d]);
      if constexpr (kGrad) add(G.g[d], ag[d]);
    }
    if constexpr (kMM) add(G.vol, avol);
  }

  // Adds K particles with distances rx, ry from the window base (cell
  // units) and factors q. The lanes are LinearShape::lanes of d = r - node
  // (weight 1 - |d|, derivative sign(-d) / h), as WindowBuilder::shape.
  [[gnu::always_inline]] void accumulate(const S& rx, const S& ry, Real inv_hx, Real inv_hy,
                                         const Source& q) {
    accumulate(PackedLinearLanes<Real, K>::of(rx, ry, inv_hx, inv_hy), q);
  }
  // The same with the lanes already made (the fused G2P's, kernels/g2p_packed.hpp).
  [[gnu::always_inline]] void accumulate(const PackedLinearLanes<Real, K>& w, const Source& q) {
    using PL = PackedLinearLanes<Real, K>;
    const VW s = w.X * w.Y, Gx = w.GX * w.Y, Gy = w.X * w.GY;
    if constexpr (kMass) am += s * PL::spread(q.m);
    if constexpr (kMom)
      for (int d = 0; d < 2; ++d) ap[d] += s * PL::spread(q.mv[d]);
    if constexpr (kFrc) {
      // f = -V sigma . G (+ S fext); sigma: xx, yy, xy (window_block.hpp)
      const VW v0 = PL::spread(q.vs[0]), v1 = PL::spread(q.vs[1]), v2 = PL::spread(q.vs[2]);
      af[0] -= v0 * Gx;  // term by term, as WindowBlock::accumulate
      af[0] -= v2 * Gy;
      af[1] -= v2 * Gx;
      af[1] -= v1 * Gy;
      if constexpr (Traction)
        for (int d = 0; d < 2; ++d) af[d] += s * PL::spread(q.fe[d]);
    }
    if constexpr (kMM) {
      const VW area = PL::spread(q.area);
      avol += s * area;
      for (int d = 0; d < 2; ++d) amx[d] += s * PL::spread(q.mw[d]);
      if constexpr (kGrad) {
        ag[0] += Gx * area;
        ag[1] += Gy * area;
      }
    }
  }
};

// The packed scatter of particles [begin, end) (p2g_range's contract: returns
// the first particle whose stencil leaves the grid, or end). Each run of
// particles with the same window (and field) is summed in a block local to
// the run, K particles at a time, the run's last group with empty slots
// (zero factors); a block that lives across the whole loop stayed in memory
// (GCC spilled its sums, and each group then waited on the last one's
// stores). A run cut by the end of a batch carries its block into the next.
template <class Real, unsigned What, bool MultiField, bool Traction>
std::size_t p2g_range_packed(const ParticleView<2, Real>& particles, const GridView<2, Real>& grid,
                             const P2GOptions& opt, std::size_t begin, std::size_t end) {
  constexpr int K = packed_particles<2, LinearShape, Real>();
  static_assert(K > 1);
  using Block = PackedLinearBlock<Real, What, Traction, K>;
  using Source = typename Block::Source;
  const ParticleView<2, Real> P = particles;  // local copies, as p2g_range_one_block
  const GridView<2, Real> G = grid;
  const WindowBuilder<2, LinearShape, Real> builder(G);
  const auto off = Block::Win::offsets(G);
  auto ahead = scatter_lines_ahead<What, typename Block::Win>(opt.prefetch_grid, off, G);
  const Real inv_t = Real(opt.inv_thickness);
  const Real inv_hx = builder.inverse_spacing(0), inv_hy = builder.inverse_spacing(1);
  PackedBatch<Real, K, MultiField> batch;
  Block carried;  // current == SIZE_MAX: nothing carried
  const ParticleLinesAhead* const columns_ahead = opt.particles_ahead;
  for (std::size_t first = begin; first < end; first += kWeightBatch) {
    const std::size_t n = std::min(kWeightBatch, end - first);
    if (columns_ahead) columns_ahead->batch(first, n);
    batch.locate(builder, P, first, n);
    for (std::size_t i = 0; i < n;) {
      if (!batch.inside[i]) {
        carried.flush(G, off);
        return first + i;
      }
      const std::size_t b = batch.window(P, G, i);
      const std::size_t j = batch.run_end(P, G, i, b, n);
      ahead.window(b);
      // (Written out here and in g2p_range_packed: as member functions
      // of the block these made GCC keep the block in memory, and the
      // packed fused G2P went 8.1 -> 10.1 ns/particle.)
      Block block;
      if (carried.current == b)
        block = carried;
      else
        carried.flush(G, off);
      carried.current = SIZE_MAX;
      block.current = b;
      std::size_t k = i;
      for (; k + std::size_t(K) <= j; k += std::size_t(K))
        block.accumulate(batch.dx(k), batch.dy(k), inv_hx, inv_hy,
                         Source::template make<true>(P, opt, inv_t, first + k, K));
      if (k < j)
        block.accumulate(batch.dx(k), batch.dy(k), inv_hx, inv_hy,
                         Source::template make<false>(P, opt, inv_t, first + k, int(j - k)));
      if (j == n && first + n < end)
        carried = block;  // the run may go on in the next batch
      else
        block.flush(G, off);
      i = j;
    }
  }
  carried.flush(G, off);
  return end;
}

}  // namespace mmpm
