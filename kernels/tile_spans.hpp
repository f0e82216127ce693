// A set of tiles as runs of grid nodes: each node belongs to the tile that
// holds it (node i along a direction: tile i >> shift, the last node row
// clamped to the last tile), and the nodes of the flagged tiles are listed
// as x intervals per tile row, joined into runs of consecutive flat node
// indices (x fastest) when the traversal asks for them.
//
// Used for the nodes next to two fields' particles (kernels/mixed_tiles.hpp)
// and for the nodes each field's particles can reach
// (kernels/active_nodes.hpp).
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "kernels/binning.hpp"

namespace mmpm {

template <int D>
struct TileSpans {
  TileLayout<D> layout;
  std::array<int, 3> nodes_per_dim{1, 1, 1};
  // Per tile row r = ty + tiles_y tz: the node intervals [x0, x1) along x
  // of its runs of flagged tiles, spans[span_begin[r] .. span_begin[r + 1]).
  std::vector<std::uint32_t> span_begin;
  std::vector<std::array<std::uint32_t, 2>> spans;

  // flag[t] != 0 for the tiles of the set (tile index order, layout.tile_index).
  void build(const TileLayout<D>& tiles, const std::array<int, 3>& nodes,
             const std::vector<std::uint8_t>& flag) {
    layout = tiles;
    nodes_per_dim = nodes;
    const auto& n = layout.tiles;
    span_begin.assign(std::size_t(n[1]) * std::size_t(n[2]) + 1, 0);
    spans.clear();
    const auto nx = std::uint32_t(nodes_per_dim[0]);
    for (int tz = 0; tz < n[2]; ++tz)
      for (int ty = 0; ty < n[1]; ++ty) {
        for (int tx = 0; tx < n[0]; ++tx) {
          if (!flag[layout.tile_index(tx, ty, tz)]) continue;
          const auto x0 = std::uint32_t(tx) << layout.shift;
          const std::uint32_t x1 = tx + 1 == n[0] ? nx : std::uint32_t(tx + 1) << layout.shift;
          const bool extends =
              spans.size() > span_begin[std::size_t(ty + n[1] * tz)] && spans.back()[1] == x0;
          if (extends)
            spans.back()[1] = x1;
          else
            spans.push_back({x0, x1});
        }
        span_begin[std::size_t(ty + n[1] * tz) + 1] = std::uint32_t(spans.size());
      }
  }

  // body(first, count) for each maximal run of nodes in [first, first +
  // count) (flat node indices of one field, x fastest) whose tile is in the set.
  template <class Body>
  void for_each_run(std::size_t first, std::size_t count, Body&& body) const {
    const auto nx = std::size_t(nodes_per_dim[0]), ny = std::size_t(nodes_per_dim[1]);
    const std::size_t end = first + count;
    std::size_t run = end, run_end = end;  // the open run [run, run_end), run == end: none
    std::size_t row = first / nx, y = row % ny, z = row / ny;
    for (std::size_t row_start = row * nx; row_start < end; row_start += nx) {
      const std::size_t r =
          std::size_t(tile_along(1, y)) +
          std::size_t(layout.tiles[1]) * std::size_t(D == 3 ? tile_along(2, z) : 0);
      for (std::uint32_t k = span_begin[r]; k < span_begin[r + 1]; ++k) {
        const std::size_t a = std::max(first, row_start + spans[k][0]);
        const std::size_t b = std::min(end, row_start + spans[k][1]);
        if (a >= b) continue;
        if (run != end && run_end == a) {
          run_end = b;  // continues the open run (across a row end too)
        } else {
          if (run != end) body(run, run_end - run);
          run = a, run_end = b;
        }
      }
      if (++y == ny) y = 0, ++z;
    }
    if (run != end) body(run, run_end - run);
  }

  // Nodes of the set's tiles (each node counted in the tile that holds it).
  std::size_t node_count() const {
    std::size_t nodes = 1;
    for (int d = 0; d < D; ++d) nodes *= std::size_t(nodes_per_dim[std::size_t(d)]);
    std::size_t c = 0;
    for_each_run(0, nodes, [&](std::size_t, std::size_t k) { c += k; });
    return c;
  }

 private:
  int tile_along(int d, std::size_t node) const {
    return std::min(int(node >> layout.shift), layout.tiles[std::size_t(d)] - 1);
  }
};

// flag[t] = 1 for every tile t with a tile of `occupied` among t - 1 .. t + 1
// in every direction (itself included). Why the neighbours: a particle in
// cell c reaches nodes c - 2 .. c + 2 at most, its window moved inward at a
// grid edge included (kernels/window.hpp), and tiles are at least 4 cells
// wide, so every node it reaches lies in tile(c) - 1 .. tile(c) + 1.
template <int D>
std::vector<std::uint8_t> tiles_next_to(const TileLayout<D>& layout,
                                        const std::vector<std::uint8_t>& occupied) {
  const auto& n = layout.tiles;
  std::vector<std::uint8_t> flag(std::size_t(layout.tile_count), 0);
  for (int tz = 0; tz < n[2]; ++tz)
    for (int ty = 0; ty < n[1]; ++ty)
      for (int tx = 0; tx < n[0]; ++tx) {
        if (!occupied[layout.tile_index(tx, ty, tz)]) continue;
        for (int z = std::max(0, tz - 1); z <= std::min(n[2] - 1, tz + 1); ++z)
          for (int y = std::max(0, ty - 1); y <= std::min(n[1] - 1, ty + 1); ++y)
            for (int x = std::max(0, tx - 1); x <= std::min(n[0] - 1, tx + 1); ++x)
              flag[layout.tile_index(x, y, z)] = 1;
      }
  return flag;
}

}  // namespace mmpm
