// Which grid nodes each thread works on in the node loops (zeroing, the
// momentum update, velocities, the multimaterial passes).
//
// Why: the two cores of this machine do not share a cache level that is
// quick to reach; a cache line one core wrote costs the other ~200 ns to
// read (one line ping-ponged between the two CPUs: ~400 ns per round trip,
// docs/performance.md "Threads keep their nodes"). The colored
// P2G writes the nodes around each thread's tiles, and the G2P reads them
// back from the same tiles (kernels/binning.hpp TileSchedule), so a node
// loop that splits the nodes any other way hands about half of every grid
// array from one core to the other, twice per stage. With two fields the
// old split of the flat (field, node) range gave thread 0 all of field 0
// and thread 1 all of field 1: every line P2G wrote then crossed.
//
// The ownership is a cut of the node index range inside the bands of the
// tiles where each thread's particles begin (each color's tiles are split
// among the threads in tile order, x fastest like the nodes), so thread i
// owns, in every field, the nodes of the rows its tiles cover, up to the
// bands the threads share, where the cut balances the node counts. Which
// thread runs a node never changes what the node computes, and the
// reductions below keep their fixed chunks, so results do not depend on
// the split or the thread count.
#pragma once

#include <omp.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "kernels/active_nodes.hpp"
#include "kernels/binning.hpp"
#include "kernels/reduce.hpp"

namespace mmpm {

// Thread cuts of node_ownership fall on multiples of this many nodes.
inline constexpr std::size_t kNodeCutAlign = 16;

struct NodeOwnership {
  // threads + 1 ascending node indices, split[0] = 0, split[threads] = nodes;
  // empty: an even split.
  std::vector<std::size_t> split;
  // With runs: the loops below visit only the nodes each field's particles
  // can reach (kernels/active_nodes.hpp); the nodes outside hold zeros.
  // Null: every node.
  const FieldNodeRuns* active = nullptr;

  // Nodes [first, last) of thread i of `threads`. A team of another size
  // than the split was made for (a loop below its parallel threshold runs
  // on one thread) gets an even split.
  std::pair<std::size_t, std::size_t> range(std::size_t nodes, std::size_t team,
                                            std::size_t i) const {
    if (split.size() != team + 1 || split.back() != nodes) return thread_block(nodes, team, i);
    return {split[i], split[i + 1]};
  }
  // The chunks of `chunk` nodes whose first node thread i owns (for the
  // reductions, whose chunks are fixed).
  std::pair<std::size_t, std::size_t> chunks(std::size_t nodes, std::size_t chunk, std::size_t team,
                                             std::size_t i) const {
    const auto [b, e] = range(nodes, team, i);
    return {(b + chunk - 1) / chunk, (e + chunk - 1) / chunk};
  }
  // The calling thread's nodes inside a parallel region.
  std::pair<std::size_t, std::size_t> mine(std::size_t nodes) const {
    return range(nodes, std::size_t(team_size()), std::size_t(team_rank()));
  }
};

// The split for `threads` threads from the tile schedule of the sorted
// particles. In every color, thread i's tiles begin in some tile
// (TileSchedule::share, the colored passes' split, which the other
// particle loops follow too). The threads' P2G writes meet inside those
// tiles' bands: each one's tile row (2D) or tile layer (3D), all nodes
// whose highest coordinate lies in the tile's range. Below the lowest band
// one thread wrote the nodes, above the highest the other; inside them
// they share rows. So a cut inside the bands crosses at most those bands'
// written nodes to the other core. The cut is the one nearest the even
// split nodes i / threads. Why not the tile's lowest node (the cut before):
// with 8-cell tiles in 3D that left thread 0 ~30 % of the nodes of a block
// filling its grid, and every node loop waited on the other thread
// (docs/performance.md "A cut balanced inside the band"). With `active`
// (kernels/active_nodes.hpp) the loops visit only its runs, and the even
// split counts only those nodes: around a body in a large grid, half the grid's nodes may
// sit above it, all in one thread's share.
template <int D>
NodeOwnership node_ownership(const TileLayout<D>& layout, const std::array<int, 3>& nodes_per_dim,
                             const TileSchedule& schedule, std::size_t threads,
                             const FieldNodeRuns* active = nullptr) {
  NodeOwnership own;
  own.active = active;
  std::size_t nodes = 1;
  for (int d = 0; d < D; ++d) nodes *= std::size_t(nodes_per_dim[std::size_t(d)]);
  if (threads < 2 || schedule.begin.empty() || schedule.begin.back() == 0) return own;
  const std::size_t top_nodes = std::size_t(nodes_per_dim[std::size_t(D - 1)]);
  const std::size_t slice = nodes / top_nodes;  // nodes per row (2D) or layer (3D)
  const std::size_t tiles_below_top =
      std::size_t(layout.tile_count) / std::size_t(layout.tiles[std::size_t(D - 1)]);
  own.split.assign(threads + 1, 0);
  for (std::size_t i = 1; i < threads; ++i) {
    std::size_t first = top_nodes, last = 0;  // band slices [first, last)
    for (std::size_t c = 0; c < schedule.tiles.size(); ++c) {
      const auto& list = schedule.tiles[c];
      if (list.empty()) continue;
      const std::size_t k = std::min(schedule.share(c, threads, i).first, list.size() - 1);
      const std::size_t tile = layout.tile_of_slot(list[k]);
      const std::size_t low = (tile / tiles_below_top) << layout.shift;  // band's lowest slice
      first = std::min(first, low);
      last = std::max(last, low + std::size_t(layout.T));
    }
    const std::size_t band_lo = std::min(first, top_nodes) * slice;
    const std::size_t band_hi = std::min(last, top_nodes) * slice;
    const std::size_t even =
        active ? active->node_quantile(nodes, i, threads) : nodes * i / threads;
    // The cut on a multiple of 16 nodes (a 64-byte line of floats, two of
    // doubles), a few nodes from the band's cut at most: a thread whose
    // range starts mid-line has every vector load of every node array
    // straddle two lines. The 3D grid bench's update on 2 threads: 1.19
    // ns/node with its cut at node 34 460, 0.79 with it at 34 464
    // (docs/performance.md "The grid stage on two threads").
    const std::size_t cut = std::clamp(even, band_lo, band_hi);
    own.split[i] = std::clamp((cut + kNodeCutAlign / 2) / kNodeCutAlign * kNodeCutAlign,
                              own.split[i - 1], nodes);
  }
  own.split[threads] = nodes;
  return own;
}

// body(f, first, last) on the calling thread's nodes [first, last) of each
// field f (indices within the field); call inside a parallel region.
template <class Body>
inline void for_own_field_nodes(const NodeOwnership& own, std::size_t nodes, int fields,
                                Body&& body) {
  const auto [b, e] = own.mine(nodes);
  if (b >= e) return;
  for (int f = 0; f < fields; ++f) {
    if (own.active)
      own.active->for_each(f, b, e,
                           [&](std::size_t first, std::size_t last) { body(f, first, last); });
    else
      body(f, b, e);
  }
}

// As for_own_field_nodes, with flat (field, node) indices: body(first, last).
template <class Body>
inline void for_own_nodes(const NodeOwnership& own, std::size_t nodes, int fields, Body&& body) {
  for_own_field_nodes(own, nodes, fields, [&](int f, std::size_t b, std::size_t e) {
    body(std::size_t(f) * nodes + b, std::size_t(f) * nodes + e);
  });
}

// for_own_nodes on the team: each thread its own nodes, in one parallel
// region (one thread below kParallelMinNodes nodes x fields).
template <class Body>
inline void team_own_nodes(const NodeOwnership& own, std::size_t nodes, int fields, Body&& body) {
  team_run(nodes * std::size_t(fields) >= kParallelMinNodes,
           [&] { for_own_nodes(own, nodes, fields, body); });
}

// A node-range hook that does nothing (the default `after` of the node passes).
struct NoNodeHook {
  void operator()(int, std::size_t, std::size_t) const {}
};

// Arrays of fields x nodes set to zero, each thread its own nodes, in one
// parallel region.
template <class Real, std::size_t N>
void zero_owned(const NodeOwnership& own, std::size_t nodes, int fields,
                const std::array<Real*, N>& arrays) {
  team_own_nodes(own, nodes, fields, [&](std::size_t b, std::size_t e) {
    for (Real* a : arrays)
      if (a) std::fill(a + b, a + e, Real(0));
  });
}

// Per field f, the sum over its nodes of body(f, first, last, acc) (K
// values), computed in fixed chunks of kNodeReduceChunk nodes and added in
// chunk order, so the totals do not depend on the thread count; each thread
// sums the chunks that start on its own nodes.
template <int K, class Body>
std::vector<std::array<double, K>> owned_field_sums(const NodeOwnership& own, std::size_t nodes,
                                                    int fields, Body&& body) {
  constexpr std::size_t chunk = kNodeReduceChunk;
  const std::size_t chunks = chunk_count(nodes, chunk);
  std::vector<std::array<double, K>> partial(chunks * std::size_t(fields));
  team_run(nodes * std::size_t(fields) >= kParallelMinNodes, [&] {
    const auto [c0, c1] =
        own.chunks(nodes, chunk, std::size_t(team_size()), std::size_t(team_rank()));
    for (int f = 0; f < fields; ++f)
      for (std::size_t c = c0; c < c1; ++c) {
        std::array<double, K> acc{};
        const std::size_t b = c * chunk, e = std::min(nodes, (c + 1) * chunk);
        // A chunk's runs in node order: the skipped nodes would have added
        // +0 (zero mass), so the chunk's sum keeps its bits.
        if (own.active)
          own.active->for_each(
              f, b, e, [&](std::size_t first, std::size_t last) { body(f, first, last, acc); });
        else
          body(f, b, e, acc);
        partial[std::size_t(f) * chunks + c] = acc;
      }
  });
  std::vector<std::array<double, K>> total(std::size_t(fields), std::array<double, K>{});
  for (int f = 0; f < fields; ++f)
    for (std::size_t c = 0; c < chunks; ++c)
      for (int k = 0; k < K; ++k)
        total[std::size_t(f)][k] += partial[std::size_t(f) * chunks + c][k];
  return total;
}

}  // namespace mmpm
