// Where each velocity field can have mass: the nodes of the tiles next to a
// tile holding particles of that field (kernels/tile_spans.hpp), as sorted
// runs of node indices per field. The node passes of a step (zeroing, the
// momentum update, the velocities, the supports, the grid kinetic energy)
// visit only these runs (kernels/node_ownership.hpp).
//
// Why: every field spans the whole grid, but a body fills only part of it.
// In the two-layer scene each of the two fields has particles on one half,
// so half of every node pass read and wrote nodes of zero mass; in a scene
// with room around its bodies most of the grid is empty
// (docs/performance.md "Node passes over the nodes a field can reach").
//
// A node outside its field's runs gets no particle's mass, so those passes
// would leave it at zero: skipping it keeps every result bitwise the same,
// provided it holds zeros. The runs are valid while every particle stays in
// the tile of its key, as for the mixed tiles (kernels/mixed_tiles.hpp); the
// Stepper rebuilds them with the tile ranges and zeroes the nodes that leave
// a field's runs (for_each_dropped).
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "kernels/binning.hpp"
#include "kernels/tile_spans.hpp"

namespace mmpm {

struct FieldNodeRuns {
  using Run = std::array<std::uint32_t, 2>;  // [first, last) within one field
  std::vector<std::vector<Run>> field;       // per field: ascending, disjoint, not adjacent

  // body(first, last) for each part of field f's runs inside [b, e), in
  // ascending order.
  template <class Body>
  void for_each(int f, std::size_t b, std::size_t e, Body&& body) const {
    const std::vector<Run>& runs = field[std::size_t(f)];
    auto it = std::upper_bound(runs.begin(), runs.end(), b,
                               [](std::size_t v, const Run& r) { return v < r[1]; });
    for (; it != runs.end() && (*it)[0] < e; ++it) {
      const std::size_t first = std::max<std::size_t>(b, (*it)[0]);
      const std::size_t last = std::min<std::size_t>(e, (*it)[1]);
      if (first < last) body(first, last);
    }
  }

  // The node index x at which the runs of all fields below x hold i /
  // parts of their nodes (the smallest such x; `nodes` when there are none).
  std::size_t node_quantile(std::size_t nodes, std::size_t i, std::size_t parts) const {
    const std::size_t target = node_count() * i / parts;
    auto below = [&](std::size_t x) {
      std::size_t c = 0;
      for (const auto& runs : field)
        for (const Run& r : runs) c += r[0] < x ? std::min<std::size_t>(r[1], x) - r[0] : 0;
      return c;
    };
    std::size_t lo = 0, hi = nodes;  // below(hi) >= target
    while (lo < hi) {
      const std::size_t mid = lo + (hi - lo) / 2;
      if (below(mid) >= target)
        hi = mid;
      else
        lo = mid + 1;
    }
    return lo;
  }

  // Nodes in the runs of every field.
  std::size_t node_count() const {
    std::size_t c = 0;
    for (const auto& runs : field)
      for (const Run& r : runs) c += r[1] - r[0];
    return c;
  }
};

// Every node of every field: the runs before the first build, so that the
// first build's for_each_dropped covers the whole grid.
inline FieldNodeRuns all_node_runs(std::size_t nodes, int fields) {
  FieldNodeRuns all;
  all.field.assign(std::size_t(fields), {});
  if (nodes > 0)
    for (auto& runs : all.field) runs.push_back({0, std::uint32_t(nodes)});
  return all;
}

// Gaps between runs shorter than this are visited rather than skipped. Why:
// each run a pass starts costs about a microsecond per step (every grid
// array's stream restarts from a cache miss), while a skipped node saves
// about 6 ns over the step's node passes. Skipping the empty part of every
// row in the two-layer scene (runs of ~145 nodes, gaps of ~110) made its
// grid stage 1.43x slower, not faster (docs/performance.md "Node passes
// over the nodes a field can reach").
inline constexpr std::size_t kMinSkippedNodes = 1024;

// The runs from the tile ranges of the sorted particles (TileSchedule::begin,
// by slot) and their fields; gaps shorter than min_gap are joined.
template <int D>
FieldNodeRuns active_node_runs(const TileLayout<D>& layout, const std::array<int, 3>& nodes,
                               const std::vector<std::uint32_t>& begin, const std::uint8_t* field,
                               int fields, std::size_t min_gap = kMinSkippedNodes) {
  const std::size_t nt = layout.tile_count;
  std::vector<std::vector<std::uint8_t>> occupied(std::size_t(fields),
                                                  std::vector<std::uint8_t>(nt, 0));
  for (std::size_t t = 0; t < nt; ++t) {
    const std::uint32_t s = layout.slot_of_tile(std::uint32_t(t));
    if (fields == 1) {
      occupied[0][t] = begin[s + 1] > begin[s];
      continue;
    }
    for (std::uint32_t p = begin[s]; p < begin[s + 1]; ++p) occupied[field[p]][t] = 1;
  }
  std::size_t count = 1;
  for (int d = 0; d < D; ++d) count *= std::size_t(nodes[std::size_t(d)]);
  FieldNodeRuns out;
  out.field.resize(std::size_t(fields));
  TileSpans<D> spans;
  for (int f = 0; f < fields; ++f) {
    spans.build(layout, nodes, tiles_next_to(layout, occupied[std::size_t(f)]));
    auto& runs = out.field[std::size_t(f)];
    spans.for_each_run(0, count, [&](std::size_t first, std::size_t k) {
      if (!runs.empty() && first - runs.back()[1] < min_gap)
        runs.back()[1] = std::uint32_t(first + k);  // a gap too short to pay for its skip
      else
        runs.push_back({std::uint32_t(first), std::uint32_t(first + k)});
    });
  }
  return out;
}

// body(f, first, last) for each part of field f's runs in `before` that is
// not in `after` (the nodes a rebuild takes out of the runs).
template <class Body>
void for_each_dropped(const FieldNodeRuns& before, const FieldNodeRuns& after, Body&& body) {
  for (std::size_t f = 0; f < before.field.size(); ++f) {
    const std::vector<FieldNodeRuns::Run> none;
    const auto& keep = f < after.field.size() ? after.field[f] : none;
    std::size_t k = 0;
    for (const FieldNodeRuns::Run& r : before.field[f]) {
      std::size_t at = r[0];
      while (k < keep.size() && keep[k][1] <= at) ++k;
      for (std::size_t j = k; j < keep.size() && keep[j][0] < r[1]; ++j) {
        if (keep[j][0] > at) body(int(f), at, std::size_t(keep[j][0]));
        at = std::max<std::size_t>(at, keep[j][1]);
      }
      if (at < r[1]) body(int(f), at, std::size_t(r[1]));
    }
  }
}

}  // namespace mmpm
