// Per-particle weights on a fixed window of Shape::W nodes per direction
// (ALGORITHM §1: S_ip, G_ip as tensor products of 1D weights).
//
// Why a window and not the particle's own stencil: every particle of one
// cell gets the same window (nodes cell - window_lo .. + W - 1), so
//  - P2G adds a whole cell's particles into a small local block and writes
//    the block to the grid once per cell (kernels/window_block.hpp): the
//    grid sees one read-modify-write per node and cell instead of one per
//    node and particle, and consecutive particles no longer wait on each
//    other's stores to the same node (the latency chain that bounded the
//    pointwise scatter, docs/performance.md);
//  - the window is a fixed number of fixed-length vectors ("units"), so the
//    transfers are vector multiply-adds where a 3-node stencil starting
//    anywhere did not vectorise:
//      W = 4 (uGIMP, B-splines): a unit is one row of 4 nodes along x
//        (4 doubles = 256 bits), W^(D-1) units;
//      W = 2 (linear): the whole window is one unit (2D: 4 lanes, 3D: 8).
// Window nodes outside the particle's reach get weight 0 (Shape::lanes()
// evaluates every window node). Near the grid's edge the window is shifted
// inward, so it never leaves the grid; a particle whose own stencil leaves
// the grid is rejected as before.
//
// Per unit u the kernels use lane vectors X (x weights), GX (x derivatives)
// and Y(u), GY(u), GZ(u) such that, lane by lane,
//   S = X Y,   dS/dx = GX Y,   dS/dy = X GY,   dS/dz = X GZ.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <utility>

#include "kernels/grid_view.hpp"
#include "kernels/lanes.hpp"
#include "kernels/particle_view.hpp"

namespace mmpm {

template <int D, class Shape, class Real>
struct Window {
  static constexpr int W = Shape::W;
  static constexpr int N = D == 2 ? W * W : W * W * W;  // window nodes
  static constexpr bool flat = W == 2;                  // one unit holds the whole window
  static constexpr int L = flat ? N : W;                // lanes per unit
  static constexpr int units = N / L;
  // All directions' 1D weights in one vector (lane d * W + k: direction d,
  // node k), so the shape function runs once per particle, not once per
  // direction. 3D pads to 4 directions (vector widths are powers of two).
  static constexpr int DP = D == 2 ? 2 : 4;
  using V = Lanes<Real, L>;        // one unit
  using VA = Lanes<Real, W * DP>;  // every direction's 1D weights
  using Offsets = std::array<std::size_t, flat ? N / 2 : units>;

  std::size_t base = 0;  // node index of the window's lowest corner (field 0)
  VA wa{};               // 1D weights, lane d * W + k
  VA dwa{};              // 1D derivatives, already divided by h

  // Every grid direction must hold a whole window (W nodes); else the caller
  // uses the pointwise kernels.
  static bool fits(const GridView<D, Real>& G) {
    for (int d = 0; d < D; ++d)
      if (G.nodes_per_dim[d] < W) return false;
    return true;
  }

  // Offsets from base of the contiguous runs of nodes along x: per unit
  // (rows, y index u % W, z index u / W), or per node pair (flat: pair q at
  // y index q % 2, z index q / 2).
  static Offsets offsets(const GridView<D, Real>& G) {
    Offsets off{};
    const std::size_t nx = std::size_t(G.nodes_per_dim[0]);
    const std::size_t nxy = nx * std::size_t(G.nodes_per_dim[1]);
    for (std::size_t q = 0; q < off.size(); ++q)
      off[q] = nx * (q % std::size_t(W)) + nxy * (q / std::size_t(W));
    return off;
  }

  // Grid values of unit u (unaligned: windows start at any node).
  static V load(const Real* a, const Offsets& off, int u) {
    if constexpr (!flat) {
      return lanes_load<V>(a + off[std::size_t(u)]);
    } else {
      V v{};
      for (int q = 0; q < N / 2; ++q) {
        const Lanes<Real, 2> t = lanes_load<Lanes<Real, 2>>(a + off[std::size_t(q)]);
        v[2 * q] = t[0];
        v[2 * q + 1] = t[1];
      }
      return v;
    }
  }
  static void add(Real* a, const Offsets& off, int u, const V& v) {
    if constexpr (!flat) {
      Real* row = a + off[std::size_t(u)];
      lanes_store(row, lanes_load<V>(row) + v);
    } else {
      for (int q = 0; q < N / 2; ++q) {
        Real* pair = a + off[std::size_t(q)];
        Lanes<Real, 2> t = lanes_load<Lanes<Real, 2>>(pair);
        t[0] += v[2 * q];
        t[1] += v[2 * q + 1];
        lanes_store(pair, t);
      }
    }
  }

  // The lane vectors of the header comment.
  V X() const { return x_lanes(wa); }
  V GX() const { return x_lanes(dwa); }
  V Y(int u) const { return yz(wa, wa, u); }
  V GY(int u) const { return yz(dwa, wa, u); }
  V GZ(int u) const {
    if constexpr (D == 2)
      return V{};
    else
      return yz(wa, dwa, u);
  }

  explicit Window(const GridView<D, Real>& G) {
    VA ih{};
    for (int d = 0; d < DP; ++d) {
      ih[d] = d < D ? Real(1) / G.h[std::size_t(d)] : Real(1);
      if (d < D)
        inv_h[d] = ih[d], origin[d] = G.origin[std::size_t(d)],
        n[d] = G.nodes_per_dim[std::size_t(d)];
    }
    inv_h_lanes = spread(ih, std::make_index_sequence<W * DP>{});
    for (int k = 0; k < W * DP; ++k) offsets_lanes[k] = Real(-(k % W));
  }

  // Returns false when the particle's stencil leaves the grid.
  [[gnu::always_inline]] bool build(const ParticleView<D, Real>& P, std::size_t p) {
    // Lowest xi the stencil allows, and the margin it needs above: linear
    // [0, n - 1), uGIMP and quadratic [1/2, n - 3/2) (stencil base
    // floor(xi - 1/2)), cubic [1, n - 2).
    constexpr Real lo_xi = Shape::W == 2 ? Real(0) : (Shape::S == 3 ? Real(0.5) : Real(1));
    constexpr Real hi_margin = Shape::W == 2 ? Real(1) : (Shape::S == 3 ? Real(1.5) : Real(2));
    VA r{}, l{};
    std::size_t stride = 1;
    base = 0;
    for (int d = 0; d < D; ++d) {
      const Real xi = (P.x[d][p] - origin[d]) * inv_h[d];
      // Compared in Real before any int conversion (a wild position must not overflow).
      if (!(xi >= lo_xi && xi < Real(n[d]) - hi_margin)) return false;
      // Window base: cell - window_lo, moved inward at the grid's edges.
      const int wb = std::clamp(int(xi) - Shape::window_lo, 0, n[d] - W);
      r[d] = xi - Real(wb);
      l[d] = Shape::S == 3 && P.lp[d] ? P.lp[d][p] : Real(0.25);
      base += std::size_t(wb) * stride;
      stride *= std::size_t(n[d]);
    }
    if constexpr (DP > D)
      r[DP - 1] = Real(0.5), l[DP - 1] = Real(0.25);  // padding: any harmless distance
    constexpr auto seq = std::make_index_sequence<W * DP>{};
    Shape::lanes(spread(r, seq) + offsets_lanes, spread(l, seq), wa, dwa);
    dwa *= inv_h_lanes;
    return true;
  }

 private:
  Real inv_h[D]{}, origin[D]{};
  int n[D]{};
  VA inv_h_lanes{}, offsets_lanes{};

  // Lane d * W + k = lane d of t.
  template <std::size_t... I>
  static VA spread(const VA& t, std::index_sequence<I...>) {
    return __builtin_shufflevector(t, t, int(I / W)...);
  }
  // Lane j of the unit: x node (j % W) for rows; (j % 2) for the flat window.
  template <std::size_t... I>
  static V x_lanes_of(const VA& a, std::index_sequence<I...>) {
    return __builtin_shufflevector(a, a, int(I % W)...);
  }
  static V x_lanes(const VA& a) { return x_lanes_of(a, std::make_index_sequence<L>{}); }
  // Flat window, lane i + 2 j + 4 l: y lane W + j, z lane 2W + l.
  template <std::size_t... I>
  static V y_lanes_of(const VA& a, std::index_sequence<I...>) {
    return __builtin_shufflevector(a, a, int(W + (I / 2) % 2)...);
  }
  template <std::size_t... I>
  static V z_lanes_of(const VA& a, std::index_sequence<I...>) {
    return __builtin_shufflevector(a, a, int(2 * W + (I / 4) % 2)...);
  }
  // Product of the y factor (from ya) and the z factor (from za) of unit u.
  static V yz(const VA& ya, const VA& za, int u) {
    if constexpr (flat) {
      constexpr auto seq = std::make_index_sequence<L>{};
      if constexpr (D == 2)
        return y_lanes_of(ya, seq);
      else
        return y_lanes_of(ya, seq) * z_lanes_of(za, seq);
    } else {
      const int j = u % W, l = u / W;
      const Real y = ya[W + j];
      return V{} + (D == 3 ? y * za[2 * W + l] : y);
    }
  }
};

}  // namespace mmpm
