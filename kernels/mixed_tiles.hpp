// Where multimaterial nodes can be: the tiles whose neighbourhood holds
// particles of two or more fields. The multimaterial node search
// (kernels/multimaterial.hpp) scans only their nodes.
//
// Why: a node gets mass only from the particles of the cells around it, so a
// node whose neighbouring tiles hold one field's particles has one field's
// mass and cannot be a multimaterial node. In a scene with one interface
// line (the two-layer scene: ~250 multimaterial nodes of 65 025) the search
// read 2 x 65 025 masses per step, about half of the multimaterial stage;
// it now reads 2 x 12 240 (docs/multimaterial.md, "Only where two fields
// meet", has the numbers).
//
// A node i (per direction) receives from cells i - hi .. i + lo, hi, lo <= 2
// (kernels/tile_reach.hpp), and tiles are at least 4 cells wide, so those
// cells lie in tile(i) - 1 .. tile(i) + 1, where tile(i) = i >> shift,
// clamped to the last tile (the last node row of a grid whose cells fill its
// tiles exactly). The flags are valid while every particle stays in the tile
// of its key, which the solver ensures: a particle that changes tile makes
// the next step re-sort before its P2G (Stepper::step).
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "kernels/binning.hpp"
#include "kernels/tile_spans.hpp"

namespace mmpm {

template <int D>
struct MixedTiles {
  TileSpans<D> tiles;  // the mixed tiles' nodes

  // From the tile ranges of the sorted particles (TileSchedule::begin, by
  // slot) and their fields.
  void build(const TileLayout<D>& layout, const std::array<int, 3>& nodes,
             const std::vector<std::uint32_t>& begin, const std::uint8_t* field) {
    const std::size_t nt = layout.tile_count;
    // Per tile: kEmpty, kSeveral, or the one field its particles have.
    constexpr int kEmpty = -1, kSeveral = -2;
    std::vector<int> one(nt, kEmpty);
    for (std::size_t t = 0; t < nt; ++t) {
      const std::uint32_t s = layout.slot_of_tile(std::uint32_t(t));
      for (std::uint32_t p = begin[s]; p < begin[s + 1]; ++p) {
        const int f = field[p];
        if (one[t] == kEmpty) {
          one[t] = f;
        } else if (one[t] != f) {
          one[t] = kSeveral;
          break;
        }
      }
    }
    // mixed[t]: tiles t - 1 .. t + 1 (in every direction) hold particles of
    // two or more fields.
    std::vector<std::uint8_t> mixed(nt, 0);
    const auto& n = layout.tiles;
    for (int tz = 0; tz < n[2]; ++tz)
      for (int ty = 0; ty < n[1]; ++ty)
        for (int tx = 0; tx < n[0]; ++tx) {
          int seen = kEmpty;
          bool two = false;
          for (int z = std::max(0, tz - 1); z <= std::min(n[2] - 1, tz + 1) && !two; ++z)
            for (int y = std::max(0, ty - 1); y <= std::min(n[1] - 1, ty + 1) && !two; ++y)
              for (int x = std::max(0, tx - 1); x <= std::min(n[0] - 1, tx + 1) && !two; ++x) {
                const int f = one[layout.tile_index(x, y, z)];
                if (f == kEmpty) continue;
                two = f == kSeveral || (seen != kEmpty && seen != f);
                seen = f;
              }
          mixed[layout.tile_index(tx, ty, tz)] = two;
        }
    tiles.build(layout, nodes, mixed);
  }

  // body(first, count) for each maximal run of nodes in [first, first +
  // count) (flat node indices of one field, x fastest) whose tile is mixed.
  template <class Body>
  void for_each_mixed_run(std::size_t first, std::size_t count, Body&& body) const {
    tiles.for_each_run(first, count, body);
  }

  // Nodes of the mixed tiles (each node counted in the tile that holds it).
  std::size_t mixed_node_count() const { return tiles.node_count(); }
};

}  // namespace mmpm
