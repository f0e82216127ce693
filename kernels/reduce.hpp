// Deterministic parallel sums: the index range is cut into fixed chunks
// (independent of the thread count), each chunk is summed in order, then the
// chunk sums are added serially. 1 and 2 threads give bitwise-equal results.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <utility>
#include <vector>

#include "kernels/team.hpp"

namespace mmpm {

inline constexpr std::size_t kReduceChunk = 4096;
// Loops shorter than this run on one thread: waking a team costs more than
// the work (about a microsecond per region, kernels/team.hpp).
inline constexpr std::size_t kParallelMin = 8192;
// Node loops (nodes x fields) shorter than this run on one thread. Lower
// than kParallelMin: each thread updates the nodes it owns, whose lines its
// own scatter left in its cache, while one thread alone must fetch the
// other core's half first (docs/performance.md "Node loops of small grids,
// and particle passes by their work").
inline constexpr std::size_t kParallelMinNodes = 4096;
// The fixed chunks of the node sums (owned_field_sums, kernels/node_ownership.hpp):
// smaller than kReduceChunk, so that a grid of a few thousand nodes has a
// chunk for each thread (one chunk of 4096 put a damped small grid's whole
// update on one thread).
inline constexpr std::size_t kNodeReduceChunk = 1024;

inline std::size_t chunk_count(std::size_t n, std::size_t chunk = kReduceChunk) {
  return (n + chunk - 1) / chunk;
}

// body(begin, end, acc) adds K values into acc for indices [begin, end).
template <int K, class Body>
std::array<double, K> deterministic_sum(std::size_t n, Body&& body) {
  const std::size_t chunks = chunk_count(n);
  std::vector<std::array<double, K>> partial(chunks);
  team_for(n >= kParallelMin, chunks, [&](std::size_t c) {
    std::array<double, K> acc{};
    body(c * kReduceChunk, std::min(n, (c + 1) * kReduceChunk), acc);
    partial[c] = acc;
  });
  std::array<double, K> total{};
  for (const auto& a : partial)
    for (int k = 0; k < K; ++k) total[k] += a[k];
  return total;
}

}  // namespace mmpm
