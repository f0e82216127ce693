// Per-particle weights on a fixed window of Shape::W nodes per direction
// (ALGORITHM §1: S_ip, G_ip as tensor products of 1D weights).
//
// Why a window and not the particle's own stencil: every particle of one
// key cell gets the same window (nodes key - window_lo .. + W - 1), so
//  - P2G adds a whole cell's particles into a small local block and writes
//    the block to the grid once per cell (kernels/window_block.hpp): the
//    grid sees one read-modify-write per node and cell instead of one per
//    node and particle, and consecutive particles no longer wait on each
//    other's stores to the same node (the latency chain that bounded the
//    pointwise scatter, docs/performance.md);
//  - the window is a fixed number of fixed-length vectors ("units"), so the
//    transfers are vector multiply-adds where a 3-node stencil starting
//    anywhere did not vectorise. A unit is RU consecutive rows of W nodes
//    along x, as many as fill one vector register (kRegisterVectorBytes:
//    64 bytes with AVX-512, 32 with AVX2): with AVX-512, 2D uGIMP in
//    double = 2 units of 2 rows x 4 nodes, 2D linear = the whole window (4
//    lanes), 3D linear = 8 lanes; with AVX2, one row of 4 doubles per unit.
//    A unit wider than the registers has no machine mode in GCC, which then
//    moves it through the stack (docs/performance.md "Targets without
//    AVX-512").
// Window nodes outside the particle's reach get weight 0 (Shape::lanes()
// evaluates every window node). Near the grid's edge the window is shifted
// inward, so it never leaves the grid; a particle whose own stencil leaves
// the grid is rejected as before.
//
// The key cell is the particle's cell, or in double, for the shapes whose
// stencil is the 3 nodes around the nearest node (uGIMP, quadratic
// B-spline), that node k: the cell of x + h/2 (kernels/shape.hpp
// binned_by_nearest_node, key_origin). The window then has WY = 3 rows per
// y and z direction instead of 4 (3D: 36 window nodes, not 64; 2D: 12, not
// 16); x keeps W = 4 lanes, one 256-bit vector per row, the fourth lane's
// weight 0. The gathers keep those one-row units (9 in 3D, 3 in 2D); the
// scatters, which add lane by lane, take 2 rows per unit, the last unit
// padded (WindowUnits, ScatterUnits).
//
// Per unit u the kernels use lane vectors X (x weights), GX (x derivatives)
// and Y(u), GY(u), GZ(u) such that, lane by lane,
//   S = X Y,   dS/dx = GX Y,   dS/dy = X GY,   dS/dz = X GZ.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <type_traits>
#include <utility>

#include "kernels/grid_view.hpp"
#include "kernels/lanes.hpp"
#include "kernels/particle_view.hpp"
#include "kernels/shape.hpp"
#include "kernels/weight_batch.hpp"

namespace mmpm {

template <class F, int... u>
[[gnu::always_inline]] inline void static_for_each(F& f, std::integer_sequence<int, u...>) {
  (f(std::integral_constant<int, u>{}), ...);
}

// f(integral_constant<int, u>) for u = 0 .. N - 1, unrolled. A function,
// not a lambda over the index pack: GCC left such a lambda out of line in
// the 3D gather (its attributes cannot be forced), and the gather's sums
// then lived in memory, each unit's multiply-add waiting for the last
// one's store (docs/performance.md "Unit loops kept inline"). The bodies
// passed in are marked always_inline for the same reason.
template <int N, class F>
[[gnu::always_inline]] inline void static_for(F&& f) {
  static_for_each(f, std::make_integer_sequence<int, N>{});
}

// Rows per unit: the most that fill at most `cap` (one register's worth) and
// divide the rows evenly, as a power of two (vector lanes are).
constexpr int window_rows_per_unit(int rows, int cap) {
  int ru = 1;
  while (2 * ru <= cap && 2 * ru <= rows && rows % (2 * ru) == 0) ru *= 2;
  return ru;
}

template <class Win, int RowsPerUnit>
struct WindowUnits;

template <int D, class Shape, class Real>
struct Window {
  static constexpr int dim = D;
  using RealType = Real;
  static constexpr int W = Shape::W;  // nodes per row (x)
  // Rows per y and z direction (header comment).
  static constexpr int WY = binned_by_nearest_node<D, Shape, Real> ? 3 : W;
  static constexpr int N = D == 2 ? W * WY : W * WY * WY;  // window nodes
  static constexpr int R = N / W;                          // rows of W nodes along x
  static constexpr int RU =
      window_rows_per_unit(R, int(kRegisterVectorBytes) / int(W * sizeof(Real)));  // rows per unit
  static constexpr int L = W * RU;                                                 // lanes per unit
  static constexpr int units = R / RU;
  // All directions' 1D weights in one vector (lane d * W + k: direction d,
  // node k), so the shape function runs once per particle, not once per
  // direction. 3D pads to 4 directions (vector widths are powers of two).
  static constexpr int DP = D == 2 ? 2 : 4;
  using V = Lanes<Real, L>;        // one unit
  using Row = Lanes<Real, W>;      // one row
  using VA = Lanes<Real, W * DP>;  // every direction's 1D weights
  using Offsets = std::array<std::size_t, R>;

  // Filled by WindowBuilder::build. No default initialisers: the transfers
  // keep a batch of windows on the stack (kernels/weight_batch.hpp), and
  // zeroing it on every call was measurable.
  std::size_t base;  // node index of the window's lowest corner (field 0)
  VA wa;             // 1D weights, lane d * W + k
  VA dwa;            // 1D derivatives, already divided by h

  // Nodes of the window along direction d.
  static constexpr int extent(int d) { return d == 0 ? W : WY; }

  // Every grid direction must hold a whole window; else the caller uses the
  // pointwise kernels.
  static bool fits(const GridView<D, Real>& G) {
    for (int d = 0; d < D; ++d)
      if (G.nodes_per_dim[d] < extent(d)) return false;
    return true;
  }

  // Offsets from base of the rows (row r: y index r % WY, z index r / WY).
  static Offsets offsets(const GridView<D, Real>& G) {
    Offsets off{};
    const std::size_t nx = std::size_t(G.nodes_per_dim[0]);
    const std::size_t nxy = nx * std::size_t(G.nodes_per_dim[1]);
    for (std::size_t r = 0; r < off.size(); ++r)
      off[r] = nx * (r % std::size_t(WY)) + nxy * (r / std::size_t(WY));
    return off;
  }

  // Grid values of unit u and their sum with v written back; the lane
  // vectors of the header comment (WindowUnits below, RU rows per unit).
  template <int u>
  static V load(const Real* a, const Offsets& off) {
    return WindowUnits<Window, RU>::template load<u>(a, off);
  }
  template <int u>
  static void add(Real* a, const Offsets& off, const V& v) {
    WindowUnits<Window, RU>::template add<u>(a, off, v);
  }
  V X() const { return WindowUnits<Window, RU>::X(*this); }
  V GX() const { return WindowUnits<Window, RU>::GX(*this); }
  template <int u>
  V Y() const {
    return WindowUnits<Window, RU>::template Y<u>(*this);
  }
  template <int u>
  V GY() const {
    return WindowUnits<Window, RU>::template GY<u>(*this);
  }
  template <int u>
  V GZ() const {
    return WindowUnits<Window, RU>::template GZ<u>(*this);
  }
};

// A window's nodes as vector units of RU rows of W nodes (lane k of unit u:
// x node k % W, row u * RU + k / W). Window uses the most rows per unit that
// divide its rows evenly, because the gathers sum across a unit's lanes.
// The scatters only add lane by lane, so they may pad (ScatterUnits below):
// rows past the window's last (R) are loaded as zeros, get the last row's
// weights (finite, never used) and are never stored. Every real lane gets
// the same operations either way, so the grid gets the same bits.
template <class Win, int RowsPerUnit>
struct WindowUnits {
  using Real = typename Win::RealType;
  static constexpr int D = Win::dim, W = Win::W, WY = Win::WY, R = Win::R;
  static constexpr int RU = RowsPerUnit;
  static constexpr int L = W * RU;                 // lanes per unit
  static constexpr int units = (R + RU - 1) / RU;  // the last one padded when RU does not divide R
  using V = Lanes<Real, L>;
  using Row = Lanes<Real, W>;
  using VA = typename Win::VA;
  using Offsets = typename Win::Offsets;

  // Grid values of unit u (rows are unaligned: windows start at any node),
  // rows joined with shuffles, not through memory.
  template <int u>
  static V load(const Real* a, const Offsets& off) {
    return join<u * RU, RU>(a, off);
  }
  template <int u>
  static void add(Real* a, const Offsets& off, const V& v) {
    const V sum = load<u>(a, off) + v;
    static_for<RU>([&](auto k) __attribute__((always_inline)) {
      constexpr int row = u * RU + decltype(k)::value;
      if constexpr (row < R)
        lanes_store(a + off[std::size_t(row)],
                    row_of<decltype(k)::value>(sum, std::make_index_sequence<W>{}));
    });
  }

  static V X(const Win& w) {
    return pick(w.wa, [](int k) { return k % W; });
  }
  static V GX(const Win& w) {
    return pick(w.dwa, [](int k) { return k % W; });
  }
  template <int u>
  static V Y(const Win& w) {
    return yz<u>(w.wa, w.wa);
  }
  template <int u>
  static V GY(const Win& w) {
    return yz<u>(w.dwa, w.wa);
  }
  template <int u>
  static V GZ(const Win& w) {
    if constexpr (D == 2)
      return V{};
    else
      return yz<u>(w.wa, w.dwa);
  }

 private:
  // Window row of lane k of unit u (padding rows take the last row's).
  static constexpr int row(int u, int k) { return std::min(u * RU + k / W, R - 1); }
  // Lanes of a picked by a constexpr index function of the unit lane.
  template <class F>
  static V pick(const VA& a, F f) {
    return lanes_pick<L>(a, f);
  }
  // Product of the y factor (from ya) and the z factor (from za) of unit u.
  template <int u>
  static V yz(const VA& ya, const VA& za) {
    constexpr auto jy = [](int k) { return W + row(u, k) % WY; };
    if constexpr (D == 2) {
      return pick(ya, jy);
    } else {
      constexpr auto lz = [](int k) { return 2 * W + row(u, k) / WY; };
      return pick(ya, jy) * pick(za, lz);
    }
  }
  // Rows first .. first + count - 1 joined into one vector (zeros past R).
  template <int first, int count>
  static Lanes<Real, W * count> join(const Real* a, const Offsets& off) {
    if constexpr (count == 1) {
      if constexpr (first < R)
        return lanes_load<Row>(a + off[std::size_t(first)]);
      else
        return Row{};
    } else {
      const auto lo = join<first, count / 2>(a, off);
      const auto hi = join<first + count / 2, count / 2>(a, off);
      return concat(lo, hi, std::make_index_sequence<W * count>{});
    }
  }
  template <class H, std::size_t... I>
  static Lanes<Real, W * 2 * (sizeof(H) / sizeof(Real) / W)> concat(const H& lo, const H& hi,
                                                                    std::index_sequence<I...>) {
    return __builtin_shufflevector(lo, hi, int(I)...);
  }
  template <int k, std::size_t... I>
  static Row row_of(const V& v, std::index_sequence<I...>) {
    return __builtin_shufflevector(v, v, int(k * W + I)...);
  }
};

// Rows per unit of the scatters: the most that fill at most `cap` (one
// register's worth), as a power of two, whether or not they divide the rows,
// up to the first power of two that covers them. 3D uGIMP and quadratic
// B-splines in double (9 rows of 4 nodes), with AVX-512: 5 units of 2 rows,
// one register each, where Window has 9 of one row, half a register
// (docs/performance.md "Two rows per unit in the 3D scatter"); with AVX2
// both are one row. 2D float binned by the nearest node (3 rows of 4
// floats): one unit of 4 rows, the last one padding, as the 4-row window
// had ("The same in 2D float").
constexpr int scatter_rows_per_unit(int rows, int cap) {
  int ru = 1;
  while (2 * ru <= cap && ru < rows) ru *= 2;
  return ru;
}
template <int D, class Shape, class Real>
using ScatterUnits =
    WindowUnits<Window<D, Shape, Real>,
                scatter_rows_per_unit(Window<D, Shape, Real>::R,
                                      int(kRegisterVectorBytes) / int(Shape::W * sizeof(Real)))>;
// Window's own units (one row per unit in the case above): the scatters'
// baseline in the benchmarks and tests.
template <int D, class Shape, class Real>
using RowUnits = WindowUnits<Window<D, Shape, Real>, Window<D, Shape, Real>::RU>;

// Builds particles' windows on one grid (the grid's constants are kept here,
// once, not in every Window of a batch, kernels/weight_batch.hpp).
template <int D, class Shape, class Real>
class WindowBuilder {
 public:
  using Win = Window<D, Shape, Real>;
  static constexpr int W = Win::W, DP = Win::DP;
  using VA = typename Win::VA;
  // The shape function runs on parts of VA of at most one register.
  // Why: GCC lowers the compares and selects of a vector wider than the
  // machine's (3D W = 4 in double: 16 lanes, two registers) lane by lane,
  // each lane through the stack; the uGIMP clamps then cost more than the
  // rest of the transfer (3D uGIMP double P2G 115 ns/particle vs 33 in
  // float, whose VA is one register).
  static constexpr int kParts = sizeof(VA) > kRegisterVectorBytes
                                    ? int(sizeof(VA) / kRegisterVectorBytes)
                                    : 1;
  static constexpr int PL = W * DP / kParts;  // lanes per part
  using Part = Lanes<Real, PL>;
  // Two particles' shape functions in one register where one particle's
  // lanes fill half of it (2D float uGIMP and B-splines: 8 of 16 lanes; 3D
  // linear float): the shape function's ~16 vector operations (uGIMP)
  // then serve two windows (docs/performance.md "Two windows' shape
  // functions per register"). Lane by lane the same operations, so the
  // same bits.
  static constexpr bool kPairShape = kParts == 1 && 2 * sizeof(VA) <= kRegisterVectorBytes;
  using Pair = std::conditional_t<kPairShape, Lanes<Real, 2 * PL>, Part>;

  // Lowest xi the stencil allows, and the margin it needs above: linear
  // [0, n - 1), uGIMP and quadratic [1/2, n - 3/2) (stencil base
  // floor(xi - 1/2)), cubic [1, n - 2). Shapes binned by the nearest node
  // measure xi from their key origin, half a cell lower (xi + 1/2 in
  // [1, n - 1)).
  static constexpr Real kLoXi = Shape::W == 2 ? Real(0) : (Shape::S == 3 ? Real(0.5) : Real(1));
  static constexpr Real kHiMargin = Shape::W == 2 ? Real(1) : (Shape::S == 3 ? Real(1.5) : Real(2));
  static constexpr Real kShift = binned_by_nearest_node<D, Shape, Real> ? Real(0.5) : Real(0);

  explicit WindowBuilder(const GridView<D, Real>& G) {
    for (int d = 0; d < D; ++d) {
      inv_h[d] = Real(1) / G.h[std::size_t(d)];
      origin[d] = key_origin<D, Shape>(G.origin[std::size_t(d)], G.h[std::size_t(d)]);
      n[d] = G.nodes_per_dim[std::size_t(d)];
      top[d] = n[d] - Win::extent(d);
    }
    // Each part built in a local and stored whole: lane-by-lane stores into
    // the members drew a false -Wmaybe-uninitialized from GCC 12 in some
    // inlining contexts.
    for (int h = 0; h < kParts; ++h) {
      Part scale{}, offset{}, direction{};
      for (int j = 0; j < PL; ++j) {
        const int k = h * PL + j, d = k / W;  // lane k: direction d, node k % W
        scale[j] = d < D ? inv_h[d] : Real(1);
        offset[j] = Real(-(k % W)) - kShift;  // lane j's node, in the key frame
        direction[j] = Real(d);
      }
      inv_h_lanes[h] = scale;
      offsets_lanes[h] = offset;
      direction_lanes[h] = direction;
    }
    if constexpr (kPairShape) {
      Pair scale{}, offset{};
      for (int j = 0; j < 2 * PL; ++j) {
        scale[j] = inv_h_lanes[0][j % PL];
        offset[j] = offsets_lanes[0][j % PL];
      }
      inv_h_pair = scale;
      offsets_pair = offset;
    }
  }

  // The windows of particles first .. first + n - 1 (n <= kWeightBatch)
  // into w, and ok[i] = build(P, first + i, w[i]), bitwise build()'s
  // windows. The scalar part of build() (bounds test, window base, clamp,
  // conversions: ~20 instructions per direction) runs for the whole batch in
  // one loop the compiler vectorises across particles; then each window's
  // shape function, which is vector code within one particle already. 2D
  // linear P2G 10.3 -> 6.2 ns/particle (docs/performance.md "Windows a batch
  // at a time, across particles").
  [[gnu::always_inline]] void build_batch(const ParticleView<D, Real>& P, std::size_t first,
                                          std::size_t count, Win* w, bool* ok) const {
    Real r[D][kWeightBatch];
    std::uint64_t window_base[kWeightBatch];
    int inside[kWeightBatch];
    locate_batch(P, first, count, r, window_base, inside);
    if constexpr (uses_half_width<Shape>) {
      // Half-widths: a column's, or the one all particles share
      // (P.lp_all). Without a column, one loop in which they are the same
      // for every particle, so the compiler builds their lanes, and 1 /
      // (2l), once per batch instead of per particle (2D uGIMP double: one
      // vector division and three shuffles per particle less;
      // docs/performance.md "One half-width for all particles"). One loop
      // with a test per particle was not split by GCC, and kept them.
      bool shared = true;
      for (int d = 0; d < D; ++d) shared = shared && !P.lp[std::size_t(d)];
      if (shared) {
        const std::array<Real, D> all = P.lp_all;
        shape_each(r, window_base, inside, count, w, ok,
                   [all](int d, std::size_t) { return all[std::size_t(d)]; });
      } else {
        shape_each(r, window_base, inside, count, w, ok,
                   [&P, first](int d, std::size_t i) { return half_width(P, d, first + i); });
      }
    } else {
      // The other shapes ignore l. (Reading P.lp_all here too, the 3D
      // cubic B-spline gathers of tests/test_p2g.cpp crashed GCC 12's SLP
      // vectoriser.)
      shape_each(r, window_base, inside, count, w, ok, [](int, std::size_t) { return Real(0.25); });
    }
  }

  // The shape function of each window of a batch whose distances and bases
  // locate_batch found; half_width(d, i): particle first + i's in direction d.
  template <class HalfWidth>
  [[gnu::always_inline]] void shape_each(const Real (&r)[D][kWeightBatch],
                                         const std::uint64_t (&window_base)[kWeightBatch],
                                         const int (&inside)[kWeightBatch], std::size_t count,
                                         Win* w, bool* ok, HalfWidth half_width_of) const {
    std::size_t i = 0;
    if constexpr (kPairShape) {
      // Windows of particles off the grid are built too (their distances
      // are finite) and never read.
      for (; i + 1 < count; i += 2) {
        ok[i] = inside[i] != 0;
        ok[i + 1] = inside[i + 1] != 0;
        Real ri[2][DP], li[2][DP];
        for (int h = 0; h < 2; ++h)
          for (int d = 0; d < D; ++d) {
            ri[h][d] = r[d][i + std::size_t(h)];
            li[h][d] = half_width_of(d, i + std::size_t(h));
          }
        shape_pair(ri, li, w[i], w[i + 1]);
        w[i].base = window_base[i];
        w[i + 1].base = window_base[i + 1];
      }
    }
    for (; i < count; ++i) {
      ok[i] = inside[i] != 0;
      if (!ok[i]) continue;
      Real ri[DP], li[DP];
      for (int d = 0; d < D; ++d) {
        ri[d] = r[d][i];
        li[d] = half_width_of(d, i);
      }
      shape(ri, li, w[i]);
      w[i].base = window_base[i];
    }
  }

  // The scalar part of build() for particles first .. first + count - 1
  // (count <= kWeightBatch), in one loop the compiler vectorises across
  // particles: distances r[d][i] from the window base (cell units; a finite
  // 0 - base off the grid), the base's node index and inside[i] (1 when the
  // stencil stays on the grid).
  // Arrays longer than the batch (N) leave their tail as it was.
  template <std::size_t N>
  [[gnu::always_inline]] void locate_batch(const ParticleView<D, Real>& P, std::size_t first,
                                           std::size_t count, Real (&r)[D][N],
                                           std::uint64_t (&window_base)[N],
                                           int (&inside)[N]) const {
    static_assert(N >= kWeightBatch);
    const Real* __restrict x[D];
    for (int d = 0; d < D; ++d) x[d] = P.x[d] + first;
#pragma GCC ivdep
    for (std::size_t i = 0; i < count; ++i) {
      std::uint64_t b = 0, stride = 1;
      int in_all = 1;
#pragma GCC unroll 3
      for (int d = 0; d < D; ++d) {
        const Real xi = (x[d][i] - origin[d]) * inv_h[d];
        // build()'s test; outside, xi is replaced by 0 before the int
        // conversion (never used: ok is false).
        const int in = int(xi >= kLoXi + kShift) & int(xi < Real(n[d]) - kHiMargin + kShift);
        in_all &= in;
        const Real xc = masked(xi, in);
        const int wb = std::clamp(int(xc) - Shape::window_lo, 0, top[d]);
        r[d][i] = xc - Real(wb);
        b += std::uint64_t(wb) * stride;
        stride *= std::uint64_t(n[d]);
      }
      window_base[i] = b;
      inside[i] = in_all;
    }
  }

  // 1 / h per direction (the derivatives' factor).
  Real inverse_spacing(int d) const {
    return inv_h[d];
  }

  // x when keep is 1, +0 when it is 0, by a bit mask. A select on a float
  // compare is control flow to GCC's vectoriser under -ftrapping-math (the
  // loop above then stays scalar); integer masking is not.
  [[gnu::always_inline]] static Real masked(Real x, int keep) {
    using Bits = std::conditional_t<sizeof(Real) == 8, std::uint64_t, std::uint32_t>;
    return __builtin_bit_cast(Real, __builtin_bit_cast(Bits, x) & (Bits(0) - Bits(keep)));
  }

  // The window of particle p into w; false when the particle's stencil
  // leaves the grid. The transfers use build_batch; this one-particle form
  // is the reference it is tested against (tests/test_window_batch.cpp).
  [[gnu::always_inline]] bool build(const ParticleView<D, Real>& P, std::size_t p, Win& w) const {
    Real r[DP], l[DP];
    std::size_t stride = 1;
    std::size_t base = 0;
    for (int d = 0; d < D; ++d) {
      const Real xi = (P.x[d][p] - origin[d]) * inv_h[d];
      // Compared in Real before any int conversion (a wild position must not overflow).
      if (!(xi >= kLoXi + kShift && xi < Real(n[d]) - kHiMargin + kShift)) return false;
      // Window base: key cell - window_lo, moved inward at the grid's edges.
      const int wb = std::clamp(int(xi) - Shape::window_lo, 0, top[d]);
      r[d] = xi - Real(wb);
      l[d] = uses_half_width<Shape> ? half_width(P, d, p) : Real(0.25);
      base += std::size_t(wb) * stride;
      stride *= std::size_t(n[d]);
    }
    shape(r, l, w);
    w.base = base;
    return true;
  }

  // The shape function of a window from its distances r (cell units, from
  // the window base) and half-widths l per direction.
  [[gnu::always_inline]] void shape(Real (&r)[DP], Real (&l)[DP], Win& w) const {
    if constexpr (DP > D)
      r[DP - 1] = Real(0.5), l[DP - 1] = Real(0.25);  // padding: any harmless distance
    if constexpr (kParts == 1) {
      // One register: lanes set one by one, then spread by one shuffle.
      VA rv{}, lv{};
      for (int d = 0; d < DP; ++d) rv[d] = r[d], lv[d] = l[d];
      constexpr auto seq = std::make_index_sequence<W * DP>{};
      Shape::lanes(spread(rv, seq) + offsets_lanes[0], spread(lv, seq), w.wa, w.dwa);
      w.dwa *= inv_h_lanes[0];
    } else {
      // Two registers: filling the wide vector lane by lane went through the
      // stack, and its load then waited on the scalar stores (a failed
      // store-to-load forward), so each part is set by broadcasts and
      // selects on constant masks. (A runtime loop over the parts, or
      // joining them with a shuffle, made GCC 12.2's SLP vectoriser crash on
      // tests/test_p2g.cpp, and the join measured slower.)
      static_for<kParts>([&](auto hc) __attribute__((always_inline)) {
        constexpr int h = decltype(hc)::value;
        Part pw, pdw;
        Shape::lanes(per_direction(r, h) + offsets_lanes[h], per_direction(l, h), pw, pdw);
        pdw *= inv_h_lanes[h];
        std::memcpy(reinterpret_cast<char*>(&w.wa) + h * sizeof(Part), &pw, sizeof(Part));
        std::memcpy(reinterpret_cast<char*>(&w.dwa) + h * sizeof(Part), &pdw, sizeof(Part));
      });
    }
  }

  // shape() of two windows at once (kPairShape): lanes 0 .. PL - 1 are
  // w0's, PL .. 2 PL - 1 w1's.
  [[gnu::always_inline]] void shape_pair(Real (&r)[2][DP], Real (&l)[2][DP], Win& w0,
                                         Win& w1) const {
    Pair rv{}, lv{};
    for (int h = 0; h < 2; ++h) {
      if constexpr (DP > D) r[h][DP - 1] = Real(0.5), l[h][DP - 1] = Real(0.25);
      for (int d = 0; d < DP; ++d) rv[h * DP + d] = r[h][d], lv[h * DP + d] = l[h][d];
    }
    constexpr auto seq = std::make_index_sequence<2 * PL>{};
    Pair pw, pdw;
    Shape::lanes(spread_pair(rv, seq) + offsets_pair, spread_pair(lv, seq), pw, pdw);
    pdw *= inv_h_pair;
    constexpr auto lo = std::make_index_sequence<PL>{};
    w0.wa = half_of<0>(pw, lo);
    w1.wa = half_of<PL>(pw, lo);
    w0.dwa = half_of<0>(pdw, lo);
    w1.dwa = half_of<PL>(pdw, lo);
  }

 private:
  // Lane d * W + k = lane d of t.
  template <std::size_t... I>
  static VA spread(const VA& t, std::index_sequence<I...>) {
    return __builtin_shufflevector(t, t, int(I / W)...);
  }
  // Lane k = lane d of particle h's DP lanes in t (k: particle h = k / PL,
  // direction d = k % PL / W).
  template <std::size_t... I>
  static Pair spread_pair(const Pair& t, std::index_sequence<I...>) {
    return __builtin_shufflevector(t, t, int(I / PL * DP + I % PL / W)...);
  }
  // Lanes first .. first + PL - 1 of v.
  template <int first, std::size_t... I>
  static VA half_of(const Pair& v, std::index_sequence<I...>) {
    return __builtin_shufflevector(v, v, int(first + I)...);
  }
  // Lane k of part h = v[direction of lane h * PL + k].
  [[gnu::always_inline]] Part per_direction(const Real (&v)[DP], int h) const {
    Part out = Part{} + v[DP - 1];
    for (int d = DP - 2; d >= 0; --d) out = direction_lanes[h] == Real(d) ? Part{} + v[d] : out;
    return out;
  }
  Real inv_h[D]{}, origin[D]{};  // origin: the key origin (kernels/binning.hpp)
  int n[D]{}, top[D]{};          // top: the highest window base
  Part inv_h_lanes[kParts]{}, offsets_lanes[kParts]{}, direction_lanes[kParts]{};
  Pair inv_h_pair{}, offsets_pair{};  // inv_h_lanes[0], offsets_lanes[0] twice (kPairShape)
};

}  // namespace mmpm
