// Which tiles' particles reach a set of nodes, and the node box a tile's
// particles reach. Used to scatter the multimaterial fields (mx, Omega, g)
// only around multimaterial nodes (docs/performance.md, "Multimaterial
// fields where they are read").
//
// A particle of key cell c (its cell, or its nearest node when binned so:
// kernels/shape.hpp binned_by_nearest_node) has nonzero weights only on
// nodes c - lo .. c + hi, lo = Shape::window_lo, hi = Shape::W - 1 - lo
// (its stencil lies inside its window, kernels/window.hpp): linear 0/1,
// the others 1/2 (binned by the nearest node: weights on c - 1 .. c + 1,
// and the window's rows along x write zeros to c + 2). So node i receives
// from cells i - hi .. i + lo only, and a tile from cells [t0, t1) reaches
// nodes t0 - lo .. t1 - 1 + hi.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "kernels/binning.hpp"

namespace mmpm {

struct NodeReach {
  int lo = 1, hi = 2;  // a particle in cell c reaches nodes c - lo .. c + hi
  template <class Shape>
  static NodeReach of() {
    return {Shape::window_lo, Shape::W - 1 - Shape::window_lo};
  }
};

// flag[t] = 1 for every tile with a cell that reaches one of nodes[0, count)
// (node indices of one field, x fastest); flag has layout.tile_count entries
// and is not cleared here.
template <int D>
void mark_tiles_reaching(const TileLayout<D>& layout, const std::array<int, 3>& nodes_per_dim,
                         NodeReach reach, const std::uint32_t* nodes, std::size_t count,
                         std::vector<std::uint8_t>& flag) {
  for (std::size_t k = 0; k < count; ++k) {
    std::size_t rest = nodes[k];
    std::array<int, 3> tlo{0, 0, 0}, thi{0, 0, 0};
    for (int d = 0; d < D; ++d) {
      const auto n = std::size_t(nodes_per_dim[std::size_t(d)]);
      const int i = int(rest % n);
      rest /= n;
      const int last_cell = layout.cells[std::size_t(d)] - 1;
      tlo[std::size_t(d)] = std::clamp(i - reach.hi, 0, last_cell) >> layout.shift;
      thi[std::size_t(d)] = std::clamp(i + reach.lo, 0, last_cell) >> layout.shift;
    }
    for (int tz = tlo[2]; tz <= thi[2]; ++tz)
      for (int ty = tlo[1]; ty <= thi[1]; ++ty)
        for (int tx = tlo[0]; tx <= thi[0]; ++tx) flag[layout.tile_index(tx, ty, tz)] = 1;
  }
}

// The nodes tile t's particles can reach: per direction [lo, hi], clipped
// to the grid.
struct NodeBox {
  std::array<int, 3> lo{0, 0, 0}, hi{0, 0, 0};
};
template <int D>
NodeBox tile_node_box(const TileLayout<D>& layout, std::uint32_t tile,
                      const std::array<int, 3>& nodes_per_dim, NodeReach reach) {
  NodeBox b;
  std::uint32_t rest = tile;
  for (int d = 0; d < D; ++d) {
    const auto nt = std::uint32_t(layout.tiles[std::size_t(d)]);
    const int t = int(rest % nt);
    rest /= nt;
    const int c0 = t << layout.shift;
    const int c1 = std::min(c0 + layout.T, layout.cells[std::size_t(d)]) - 1;
    b.lo[std::size_t(d)] = std::max(0, c0 - reach.lo);
    b.hi[std::size_t(d)] = std::min(nodes_per_dim[std::size_t(d)] - 1, c1 + reach.hi);
  }
  return b;
}

// Zeroes a[field * nodes + node] for every field and every node of the box.
template <int D, class Real>
void zero_node_box(Real* a, std::size_t nodes, int fields, const std::array<int, 3>& nodes_per_dim,
                   const NodeBox& b) {
  const auto nx = std::size_t(nodes_per_dim[0]), ny = std::size_t(nodes_per_dim[1]);
  const std::size_t len = std::size_t(b.hi[0] - b.lo[0] + 1);
  for (int f = 0; f < fields; ++f)
    for (int z = b.lo[2]; z <= b.hi[2]; ++z)
      for (int y = b.lo[1]; y <= b.hi[1]; ++y) {
        Real* row = a + std::size_t(f) * nodes + std::size_t(b.lo[0]) +
                    nx * (std::size_t(y) + ny * std::size_t(z));
        std::fill(row, row + len, Real(0));
      }
}

}  // namespace mmpm
