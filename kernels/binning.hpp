// Binning for the colored scatter (ARCHITECTURE "Parallel scatter without
// races"). Cells are grouped into square tiles of T cells per direction;
// a particle's key is its tile index times T^D plus its cell inside the
// tile, so a stable counting sort by key groups particles tile by tile (and
// cell by cell inside a tile, for locality and for the windowed scatter). Tiles whose indices have
// the same parity in every direction share a color; two tiles of one color are at least T cells
// apart, and a particle in cell c touches nodes c-1 .. c+2 at most (every shape function here), so
// T >= 3 keeps same-colored tiles on disjoint nodes.
#pragma once

#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <utility>
#include <vector>

#include "kernels/reduce.hpp"

namespace mmpm {

template <int D>
struct TileLayout {
  int T = 8;      // tile edge in cells: a power of two (shifts, not divisions)
  int shift = 3;  // log2(T)
  std::array<int, 3> cells{1, 1, 1};
  std::array<int, 3> tiles{1, 1, 1};
  std::uint32_t keys_per_tile = 1;  // T^D
  int key_shift = 3 * D;            // log2(keys_per_tile)
  std::uint32_t tile_count = 1;
  // The order tiles are stored in (docs/performance.md "Particles stored
  // color by color"). A key holds the tile's slot, not its index: with
  // color_major, the slots run through color 0's tiles (in tile order), then
  // color 1's, ..., so each colored pass reads its particles front to back;
  // without, slot = tile index (x fastest). Tile indices (x fastest, like
  // the nodes) stay what every geometric question is asked in.
  bool color_major = true;
  // Per direction, how many tiles have an even (half[0]) and an odd
  // (half[1]) index: a color's tiles form a half[p_x] x half[p_y] (x
  // half[p_z]) lattice.
  std::array<std::array<std::uint32_t, 2>, 3> half{};
  // First slot of each color (color c = sum of p_d << d, p_d the parity of
  // the tile's index along d); color_begin[1 << D] = tile_count.
  std::array<std::uint32_t, 9> color_begin{};

  // tile_edge is rounded up to a power of two, at least 4.
  void setup(int tile_edge, const std::array<int, 3>& grid_cells, bool by_color = true) {
    shift = 2;
    while ((1 << shift) < tile_edge) ++shift;
    T = 1 << shift;
    key_shift = D * shift;
    cells = grid_cells;
    keys_per_tile = 1u << key_shift;
    tile_count = 1;
    color_major = by_color;
    for (int d = 0; d < D; ++d) {
      tiles[d] = (cells[d] + T - 1) >> shift;
      tile_count *= std::uint32_t(tiles[d]);
      half[d] = {std::uint32_t(tiles[d] + 1) / 2, std::uint32_t(tiles[d]) / 2};
    }
    for (int d = D; d < 3; ++d) half[d] = {1, 0};
    color_begin.fill(tile_count);
    std::uint32_t next = 0;
    for (int c = 0; c < (1 << D); ++c) {
      color_begin[c] = next;
      std::uint32_t count = 1;
      for (int d = 0; d < D; ++d) count *= half[d][(c >> d) & 1];
      next += count;
    }
  }
  std::uint32_t key_count() const { return tile_count * keys_per_tile; }

  // The slot of the tile at tile coordinates t.
  std::uint32_t slot(const std::uint32_t (&t)[3]) const {
    return color_major ? color_major_slot(t, half, tiles)
                       : tile_index(int(t[0]), int(t[1]), int(t[2]));
  }
  // The color-major slot from the layout's numbers passed by value, so that
  // PositionTile::any_moved can call it on locals inside its vector loop.
  // Selects only: the rank inside the color's lattice, h_x + half_x (h_y +
  // half_y h_z) (h = t >> 1), plus the slots of the colors before it, which
  // order colors by p_z, then p_y, then p_x: sum over k of p_k half_k[0]
  // prod_{d<k} tiles_d prod_{d>k} half_d[p_d].
  static std::uint32_t color_major_slot(const std::uint32_t (&t)[3],
                                        const std::array<std::array<std::uint32_t, 2>, 3>& half,
                                        const std::array<int, 3>& tiles) {
    std::uint32_t rank = 0, stride = 1, before = 0, below = 1;
    std::uint32_t above[3] = {1, 1, 1};  // prod_{d>k} half_d[p_d]
    // Selects, not half[d][t[d] & 1]: indexed by a lane's value, GCC made
    // that a vector gather in any_moved's loop, ~10 % of the 2D linear
    // gradient pass's samples (docs/performance.md "The tile-change test
    // without gathers").
    for (int d = D - 1; d > 0; --d) above[d - 1] = above[d] * (t[d] & 1 ? half[d][1] : half[d][0]);
    for (int d = 0; d < D; ++d) {
      const std::uint32_t p = t[d] & 1;
      rank += (t[d] >> 1) * stride;
      stride *= p ? half[d][1] : half[d][0];
      before += p * half[d][0] * below * above[d];
      below *= std::uint32_t(tiles[d]);
    }
    return before + rank;
  }
  std::uint32_t slot_of_tile(std::uint32_t tile) const {
    std::uint32_t t[3] = {0, 0, 0};
    for (int d = 0; d < D; ++d) {
      t[d] = tile % std::uint32_t(tiles[d]);
      tile /= std::uint32_t(tiles[d]);
    }
    return slot(t);
  }
  int color_of_slot(std::uint32_t s) const {
    if (!color_major) return color(s);
    int c = 0;
    while (c + 1 < (1 << D) && s >= color_begin[c + 1]) ++c;
    return c;
  }
  std::uint32_t tile_of_slot(std::uint32_t s) const {
    if (!color_major) return s;
    const int c = color_of_slot(s);
    std::uint32_t rank = s - color_begin[c], tile = 0, stride = 1;
    for (int d = 0; d < D; ++d) {
      const std::uint32_t p = std::uint32_t(c >> d) & 1, n = half[d][p];
      const std::uint32_t h = d + 1 < D ? rank % n : rank;
      rank = d + 1 < D ? rank / n : 0;
      tile += (2 * h + p) * stride;
      stride *= std::uint32_t(tiles[d]);
    }
    return tile;
  }

  // Key of a cell given by its integer indices (clamped into the grid so that
  // a particle exactly on the upper boundary still gets a valid key).
  // Inside a tile, cells go y fastest, then z, x slowest: consecutive cells
  // differ by one in y, so the windowed scatter's consecutive blocks
  // (kernels/window.hpp) meet on whole rows along x at the same addresses,
  // and each row load is served by the previous block's row store. In x
  // order they would overlap by all but one node, a partial overlap the
  // CPU cannot forward (the load waits for the store to reach the cache).
  std::uint32_t key(const std::array<int, 3>& c_in) const {
    std::uint32_t t[3] = {0, 0, 0}, local = 0;
    for (int d = 0; d < D; ++d) {
      const int c = c_in[d] < 0 ? 0 : (c_in[d] >= cells[d] ? cells[d] - 1 : c_in[d]);
      t[d] = std::uint32_t(c >> shift);
      const int slot_bits = d == 0 ? D - 1 : d - 1;  // x -> highest bits
      local |= std::uint32_t(c & (T - 1)) << (slot_bits * shift);
    }
    return (slot(t) << key_shift) | local;
  }
  std::uint32_t slot_of_key(std::uint32_t k) const { return k >> key_shift; }
  std::uint32_t tile_of_key(std::uint32_t k) const { return tile_of_slot(slot_of_key(k)); }
  // Index of the tile at tile coordinates (tx, ty, tz), x fastest.
  std::size_t tile_index(int tx, int ty, int tz) const {
    return std::size_t(tx) +
           std::size_t(tiles[0]) * (std::size_t(ty) + std::size_t(tiles[1]) * std::size_t(tz));
  }
  int color(std::uint32_t tile) const {
    int col = 0;
    for (int d = 0; d < D; ++d) {
      col |= int(tile % std::uint32_t(tiles[d]) & 1u) << d;
      tile /= std::uint32_t(tiles[d]);
    }
    return col;
  }
};

// Where the particles of each tile are, and which tiles each thread takes in
// a colored pass (colors in turn, the tiles of one color in parallel).
// Tiles are named by their slots (TileLayout): the particles of slot s are
// [begin[s], begin[s + 1]).
//
// Thread i of T takes the tiles holding the i-th T-quantile of the color's
// particles, in slot order, rather than tiles handed out dynamically, and
// every particle loop of the Stepper gives each thread the same particles
// (thread_ranges), so a particle's cache lines stay in one core's caches
// from pass to pass. A dynamic tile schedule moved them between the cores
// in every pass: the 2D linear step on 2 threads took 29 ns/particle with
// it and 20 with this split (docs/performance.md, "Threads keep their
// particles"). Which thread runs a tile does not change what the tile
// computes, so the split leaves the results bitwise unchanged.
struct TileSchedule {
  std::vector<std::uint32_t> begin;                  // first particle per slot, size tiles + 1
  std::array<std::vector<std::uint32_t>, 8> tiles;   // non-empty slots per color, in order
  std::array<std::vector<std::uint32_t>, 8> prefix;  // per color: particles in tiles [0, k)
  bool color_major = true;                           // the layout's storage order

  // From the sorted keys of n particles.
  template <int D>
  void build(const TileLayout<D>& layout, const std::uint32_t* key, std::size_t n) {
    const std::uint32_t nt = layout.tile_count;
    color_major = layout.color_major;
    begin.assign(std::size_t(nt) + 1, 0);
    for (std::size_t p = 0; p < n; ++p) ++begin[layout.slot_of_key(key[p]) + 1];
    for (std::uint32_t t = 0; t < nt; ++t) begin[t + 1] += begin[t];
    for (auto& c : tiles) c.clear();
    for (std::uint32_t t = 0; t < nt; ++t)
      if (begin[t + 1] > begin[t]) tiles[std::size_t(layout.color_of_slot(t))].push_back(t);
    for (std::size_t c = 0; c < tiles.size(); ++c) {
      prefix[c].assign(tiles[c].size() + 1, 0);
      for (std::size_t k = 0; k < tiles[c].size(); ++k)
        prefix[c][k + 1] = prefix[c][k] + (begin[tiles[c][k] + 1] - begin[tiles[c][k]]);
    }
  }

  // The positions [first, last) in tiles[color] that thread i of `threads`
  // takes; the shares of all threads partition the color's tiles.
  std::pair<std::size_t, std::size_t> share(std::size_t color, std::size_t threads,
                                            std::size_t i) const {
    const auto& pre = prefix[color];
    const std::size_t count = pre.size() - 1, total = pre.back();
    const auto boundary = [&](std::size_t j) -> std::size_t {
      if (j == 0) return 0;
      if (j >= threads) return count;
      return std::size_t(std::lower_bound(pre.begin(), pre.end(), total * j / threads) -
                         pre.begin());
    };
    return {boundary(i), boundary(i + 1)};
  }

  // The particles thread i of `threads` takes in the loops that are not
  // colored, as up to 8 ranges [first, last): stored color by color, its
  // tiles of each color are one range (the colored passes' share); stored
  // in tile order, its shares of the colors interleave, and the i-th
  // contiguous block of the n particles is what they cover, to a tile.
  struct Ranges {
    std::array<std::pair<std::size_t, std::size_t>, 8> range{};
    std::size_t count = 0;
  };
  Ranges thread_ranges(std::size_t threads, std::size_t i) const {
    Ranges r;
    const std::size_t n = begin.empty() ? 0 : begin.back();
    if (!color_major || threads < 2) {
      r.range[0] = thread_block(n, threads, i);
      r.count = r.range[0].second > r.range[0].first ? 1 : 0;
      return r;
    }
    for (std::size_t c = 0; c < tiles.size(); ++c) {
      const auto [first, last] = share(c, threads, i);
      if (first >= last) continue;
      const std::size_t b = begin[tiles[c][first]], e = begin[tiles[c][last - 1] + 1];
      if (r.count && r.range[r.count - 1].second == b)
        r.range[r.count - 1].second = e;  // adjoins the previous color's range
      else
        r.range[r.count++] = {b, e};
    }
    return r;
  }
};

// Cell index of a coordinate (cell units): floor, as an int.
template <class Real>
inline int cell_of(Real x, Real origin, Real inv_h) {
  return int(std::floor((x - origin) * inv_h));
}

// G2P's test for particles that moved into another tile than their key's
// (kernels/g2p.hpp KeyFn). inv_h is stored, not h, so the test multiplies
// instead of dividing per particle and direction, as the sort's key does.
template <int D, class Real>
struct PositionTile {
  TileLayout<D> tiles;
  std::array<Real, 3> origin{}, inv_h{};
  std::array<const Real*, D> x{};
  // From the grid's origin and cell size h, and the particles' x arrays.
  template <class Positions>
  static PositionTile of(const TileLayout<D>& layout, const std::array<Real, 3>& grid_origin,
                         const std::array<Real, 3>& h, const Positions& positions) {
    PositionTile k{layout, grid_origin, {Real(1) / h[0], Real(1) / h[1], Real(1) / h[2]}, {}};
    for (int d = 0; d < D; ++d) k.x[std::size_t(d)] = positions[d];
    return k;
  }
  // Whether any particle of [begin, end) is outside the tile of its key: the
  // test of slot(tile(p)) != slot_of_key(key[p]) for a whole range, as one loop the
  // compiler vectorises. Asked per particle inside G2P, this test was a fifth
  // of the instructions of the gradient pass (docs/performance.md). The
  // members are copied to locals first: read through `this` inside the loop,
  // GCC 12 did not vectorise it (scalar code, ~2 ns/particle, a fifth of the
  // 2D linear G2P kernel; docs/performance.md "The tile-change test ran
  // scalar").
  bool any_moved(const std::uint32_t* __restrict key, std::size_t begin, std::size_t end) const {
    return tiles.color_major ? moved_tiles<true>(key, begin, end)
                             : moved_tiles<false>(key, begin, end);
  }

 private:
  template <bool ColorMajor>
  bool moved_tiles(const std::uint32_t* __restrict key, std::size_t begin, std::size_t end) const {
    const Real* __restrict pos[D];
    Real x0[D], scale[D];
    int last_cell[D];
    std::uint32_t stride[D];
    std::uint32_t tiles_below = 1;
    for (int d = 0; d < D; ++d) {
      const auto k = std::size_t(d);
      pos[d] = x[k], x0[d] = origin[k], scale[d] = inv_h[k];
      last_cell[d] = tiles.cells[k] - 1;
      stride[d] = tiles_below;
      tiles_below *= std::uint32_t(tiles.tiles[k]);
    }
    const auto half = tiles.half;
    const auto counts = tiles.tiles;
    const int shift = tiles.shift;
    const int key_shift = tiles.key_shift;
    unsigned moved = 0;
#pragma omp simd reduction(| : moved)
    for (std::size_t p = begin; p < end; ++p) {
      std::uint32_t t[3] = {0, 0, 0}, slot = 0;
      for (int d = 0; d < D; ++d) {
        const int c = std::clamp(int(std::floor((pos[d][p] - x0[d]) * scale[d])), 0, last_cell[d]);
        t[d] = std::uint32_t(c >> shift);
        if constexpr (!ColorMajor) slot += t[d] * stride[d];
      }
      if constexpr (ColorMajor) slot = TileLayout<D>::color_major_slot(t, half, counts);
      moved |= unsigned(slot != (key[p] >> key_shift));
    }
    return moved != 0;
  }
};

// Stable counting sort: fills perm so that perm[new] = old, and offsets
// (size key_count + 1) with the first sorted position of every key. With
// `tie` (the particles' seed ids), the particles of one key (one cell) are
// put in tie order instead of their old order: the order a cell's
// particles add into the grid then depends on which particles the cell
// holds, not on the order the last sort left them in, so the results do
// not depend on the storage order (particle_order "color" or "tile"). A
// cell holds a handful of particles, mostly still in order: an insertion
// sort per cell.
inline void counting_sort(const std::uint32_t* key, std::size_t n, std::uint32_t key_count,
                          std::vector<std::uint32_t>& offsets, std::vector<std::uint32_t>& perm,
                          const std::uint32_t* tie = nullptr) {
  offsets.assign(std::size_t(key_count) + 1, 0);
  for (std::size_t p = 0; p < n; ++p) ++offsets[key[p] + 1];
  for (std::size_t k = 0; k < key_count; ++k) offsets[k + 1] += offsets[k];
  perm.resize(n);
  std::vector<std::uint32_t> next(offsets.begin(), offsets.end() - 1);
  for (std::size_t p = 0; p < n; ++p) perm[next[key[p]]++] = std::uint32_t(p);
  if (!tie) return;
  // The tie values in sorted position first (one gather), so the sort reads
  // them in order instead of at random old positions: from a shuffled start
  // those random reads took longer than the rest of the sort.
  std::vector<std::uint32_t> t(n);
  for (std::size_t i = 0; i < n; ++i) t[i] = tie[perm[i]];
  for (std::size_t k = 0; k < key_count; ++k)
    for (std::uint32_t i = offsets[k] + 1; i < offsets[k + 1]; ++i) {
      const std::uint32_t q = perm[i], tq = t[i];
      std::uint32_t j = i;
      for (; j > offsets[k] && t[j - 1] > tq; --j) perm[j] = perm[j - 1], t[j] = t[j - 1];
      perm[j] = q, t[j] = tq;
    }
}

// a[i] <- a[perm[i]] for one array, through `scratch` (n entries). Each
// thread gathers its particles into scratch and, after all have gathered,
// copies the same particles back: they then end in the cache of the thread
// whose particle loops use them (`sorted`: the schedule of the new order,
// TileSchedule::thread_ranges; without it, the static block;
// kernels/node_ownership.hpp explains why that matters on this machine).
// A serial copy-back left half of every column in the other core's cache
// and made the 2-thread sort slower than the 1-thread one.
template <class T>
inline void permute_in_place(T* __restrict a, T* __restrict scratch,
                             const std::uint32_t* __restrict perm, std::size_t n,
                             const TileSchedule* sorted = nullptr) {
  team_run(n >= kParallelMin, [&] {
    const auto threads = std::size_t(team_size()), me = std::size_t(team_rank());
    TileSchedule::Ranges mine;
    if (sorted) {
      mine = sorted->thread_ranges(threads, me);
    } else {
      mine.range[0] = thread_block(n, threads, me);
      mine.count = 1;
    }
    for (std::size_t r = 0; r < mine.count; ++r)
      for (std::size_t i = mine.range[r].first; i < mine.range[r].second; ++i)
        scratch[i] = a[perm[i]];
    team_barrier();
    for (std::size_t r = 0; r < mine.count; ++r) {
      const auto [b, e] = mine.range[r];
      if (e > b) std::memcpy(a + b, scratch + b, (e - b) * sizeof(T));
    }
  });
}

}  // namespace mmpm
