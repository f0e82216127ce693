// The multimaterial fields' P2G (mx, Omega and, for the mvg/avg/rigid
// normals, g: ALGORITHM §1, P-10/13, P-19, P-33) where they are read.
//
// Pass A and B read these fields only at multimaterial nodes
// (kernels/multimaterial.hpp gather_node), and in the paper's scenes those
// are a thin layer along the interfaces (the two-layer bench scene: 251 of
// 130 000 nodes). Scattered with the mass, momentum and force, they cost
// every particle three to five more block arrays (docs/performance.md,
// "Multimaterial fields where they are read"). Here, once the node list is
// known, only the particles of tiles that reach a multimaterial node
// scatter them (kernels/tile_reach.hpp), into node boxes zeroed first.
// Other tiles' particles have exactly zero weight at those nodes, and the
// tiles that reach a node add into it in the same order as a scatter of all
// tiles, so the values at multimaterial nodes are the same sums in the same
// order (tests/test_p2g.cpp checks them bitwise).
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "kernels/binning.hpp"
#include "kernels/p2g.hpp"
#include "kernels/tile_reach.hpp"

namespace mmpm {

// Scratch of the pass, kept between steps (no allocation once warm).
struct ReachTiles {
  std::vector<std::uint8_t> flag;                   // per tile index: reaches a listed node
  std::array<std::vector<std::uint32_t>, 8> tiles;  // their slots, per color, in order
};

// Flags the tiles of `schedule` that reach one of `nodes` (one field's node
// indices) and lists them per color; returns how many particles they hold.
template <int D, class Shape, class Real>
std::size_t find_reach_tiles(const GridView<D, Real>& G, const TileLayout<D>& layout,
                             const TileSchedule& schedule, const std::vector<std::uint32_t>& nodes,
                             ReachTiles& reach_tiles) {
  reach_tiles.flag.assign(layout.tile_count, 0);
  mark_tiles_reaching(layout, G.nodes_per_dim, NodeReach::of<Shape>(), nodes.data(), nodes.size(),
                      reach_tiles.flag);
  std::size_t particles = 0;
  for (std::size_t c = 0; c < reach_tiles.tiles.size(); ++c) {
    reach_tiles.tiles[c].clear();
    for (const std::uint32_t t : schedule.tiles[c])  // slots
      if (reach_tiles.flag[layout.tile_of_slot(t)]) {
        reach_tiles.tiles[c].push_back(t);
        particles += schedule.begin[t + 1] - schedule.begin[t];
      }
  }
  return particles;
}

// Scatters mx, vol (and g when with_gradient) from the particles of the
// tiles find_reach_tiles listed, into their node boxes zeroed first. Tiles
// of one color run in parallel when `parallel`. Returns the first particle
// whose stencil left the grid, or SIZE_MAX.
template <int D, class Shape, class Real>
std::size_t p2g_multimaterial_fields(const ParticleView<D, Real>& P, const GridView<D, Real>& G,
                                     const P2GOptions& opt, const TileLayout<D>& layout,
                                     const TileSchedule& schedule, const ReachTiles& reach_tiles,
                                     bool with_gradient, bool parallel) {
  const NodeReach reach = NodeReach::of<Shape>();
  // Zero the boxes the scatter adds into: all colors first (boxes of tiles
  // of different colors overlap); tiles of one color have disjoint boxes.
  for (const auto& list : reach_tiles.tiles) {
    team_for(parallel, list.size(), [&](std::size_t k) {
      const NodeBox box =
          tile_node_box(layout, layout.tile_of_slot(list[k]), G.nodes_per_dim, reach);
      zero_node_box<D>(G.vol, G.nodes, G.fields, G.nodes_per_dim, box);
      for (int d = 0; d < D; ++d) {
        zero_node_box<D>(G.mx[d], G.nodes, G.fields, G.nodes_per_dim, box);
        if (with_gradient) zero_node_box<D>(G.g[d], G.nodes, G.fields, G.nodes_per_dim, box);
      }
    });
  }
  std::atomic<std::size_t> bad{SIZE_MAX};
  for (const auto& list : reach_tiles.tiles) {
    team_for(parallel, list.size(), [&](std::size_t k) {
      const std::size_t b = schedule.begin[list[k]], e = schedule.begin[list[k] + 1];
      const std::size_t r =
          with_gradient ? p2g_range<D, Shape, Real, kMultimaterial | kDomainGradient, true, false>(
                              P, G, opt, b, e)
                        : p2g_range<D, Shape, Real, kMultimaterial, true, false>(P, G, opt, b, e);
      if (r != e) offer_min(bad, r);
    });
  }
  return bad.load();
}

}  // namespace mmpm
