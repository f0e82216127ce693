// Software prefetch of the grid lines a tile's coming cells will reach, in
// 2D ([simulation] prefetch_grid, default on).
//
// Why: inside a tile the particles go cell by cell, y fastest and x slowest
// (TileLayout::key, kernels/binning.hpp), so a 2D window reaches a new
// 64-byte line of each of its grid rows once every 64 / sizeof(Real) cell
// columns, row after row, one row pitch apart. Once the grid has left the
// caches (2D grids from ~500^2 nodes, beside a particle stream that flushes
// the L3) the hardware prefetchers do not follow these short strided pieces,
// and every first touch waited for memory: the 2D linear step at 10^6
// particles took 42 ns/particle-step on one thread against 32 at 3*10^5,
// and 26 against 25 with four times the particles per node
// (docs/performance.md "Grid lines a line ahead").
//
// While a window at column x runs, the line of each of its rows at column
// x + 64 / sizeof(Real) is requested: 8 or 16 cell columns (hundreds to
// thousands of particles) before a window reaches it, by which time it sits
// in the L1 or L2. Most requests find their line there already and cost one
// load slot. A prefetch is a hint: no value changes, and an address past
// the grid's last row (the line ahead of the last nodes) never faults.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "kernels/g2p_particle.hpp"
#include "kernels/grid_update.hpp"
#include "kernels/grid_view.hpp"
#include "kernels/window_block.hpp"

namespace mmpm {

// The solver requests only on grids of this size and more (nine arrays over
// all fields; Stepper::prefetch_grid): a core's L2 on the machines
// measured, which holds smaller grids.
inline constexpr std::size_t kPrefetchMinGridBytes = std::size_t(1) << 20;

// The grid arrays one pass reads (kReads) and adds to (kWrites), and the
// rows of its window. The counts are compile-time so that a request is one
// address load and one prefetch. With a run-time count the loop over the
// arrays took ~9 instructions per array and window; the 2D linear scatter
// on an L2-sized block went 4.18 -> 3.90 ns/particle without it
// (docs/performance.md "Requests unrolled").
template <class Win, int kReads = 0, int kWrites = 0>
class GridLinesAhead {
  using Real = typename Win::RealType;

 public:
  GridLinesAhead(bool on, const typename Win::Offsets& rows) : on_(on && Win::dim == 2) {
    for (std::size_t r = 0; r < kRows; ++r) row_bytes_[r] = rows[r] * sizeof(Real);
    if constexpr (kRows > 1) row_step_ = rows[1];
  }
  // An array the pass only reads (the velocities) or also writes (the sums):
  // kReads and kWrites of them, then seal(). Fewer or more than the counts
  // turn the requests off (they are hints; nothing is lost).
  void read(const Real* a) { add(a, read_, reads_); }
  void write(const Real* a) { add(a, write_, writes_); }
  void seal() {
    on_ = on_ && reads_ == kReads && writes_ == kWrites;
    // A null array (a pass without it) takes another's address: a request
    // for a line already asked for, rather than one near address 0. All
    // null: nothing to request.
    std::uintptr_t any = 0;
    for (const std::uintptr_t a : read_) any = any ? any : a;
    for (const std::uintptr_t a : write_) any = any ? any : a;
    if (any == 0 && kReads + kWrites > 0) on_ = false;
    for (std::uintptr_t& a : read_) a = a ? a : any;
    for (std::uintptr_t& a : write_) a = a ? a : any;
  }

  bool on() const { return on_; }

  // The lines one line ahead in x of the rows of the window at `base`
  // (field offset included). Cells go y fastest, so a window one row above
  // the last one shares all its rows but the top one with it: only that
  // row is requested then, and nothing for the same window again.
  [[gnu::always_inline]] void window(std::size_t base) {
    if (!on_ || base == last_) return;
    const bool above = last_ != SIZE_MAX && base == last_ + row_step_;
    last_ = base;
    const std::uintptr_t ahead = base * sizeof(Real) + kLineBytes;
    request_row(ahead + row_bytes_[kRows - 1]);
    if (!above)
      for (std::size_t r = 0; r + 1 < kRows; ++r) request_row(ahead + row_bytes_[r]);
  }

  // Every window of a built batch in order: base_of(i) is particle i's
  // window with its field offset, or SIZE_MAX (off the grid).
  template <class BaseOf>
  [[gnu::always_inline]] void batch(std::size_t n, const BaseOf& base_of) {
    if (!on_) return;
    for (std::size_t i = 0; i < n; ++i)
      if (const std::size_t b = base_of(i); b != SIZE_MAX) window(b);
  }

 private:
  static constexpr std::uintptr_t kLineBytes = 64;
  template <int N>
  using Addresses = std::array<std::uintptr_t, std::size_t(N)>;
  template <std::size_t N>
  void add(const Real* a, std::array<std::uintptr_t, N>& to, int& count) {
    if (count >= int(N)) {
      on_ = false;
      ++count;
      return;
    }
    to[std::size_t(count++)] = reinterpret_cast<std::uintptr_t>(a);  // 0 if null: seal()
  }
  // One row's line in every array: `at` is the byte offset from an array's start.
  [[gnu::always_inline]] void request_row(std::uintptr_t at) const {
    for (int k = 0; k < kReads; ++k)
      __builtin_prefetch(reinterpret_cast<const void*>(read_[std::size_t(k)] + at), 0, 3);
    for (int k = 0; k < kWrites; ++k)
      __builtin_prefetch(reinterpret_cast<const void*>(write_[std::size_t(k)] + at), 1, 3);
  }
  static constexpr std::size_t kRows = std::tuple_size_v<typename Win::Offsets>;
  bool on_;
  std::size_t row_step_ = 0;     // node offset of the window's second row
  std::size_t last_ = SIZE_MAX;  // the last window requested
  int reads_ = 0, writes_ = 0;
  Addresses<kReads> read_{};
  Addresses<kWrites> write_{};
  std::array<std::size_t, kRows> row_bytes_{};
};

// The arrays a scatter of `What` (kernels/window_block.hpp) adds to.
template <unsigned What, int D>
constexpr int scatter_array_count() {
  const int per_dim = int((What & (kMassMomentum | kMomentumOnly)) != 0) +
                      int((What & kForce) != 0) + int((What & kMultimaterial) != 0) +
                      int((What & kDomainGradient) != 0);
  return int((What & kMassMomentum) != 0) + int((What & kMultimaterial) != 0) + D * per_dim;
}
template <unsigned What, class Win, int D, class Real>
GridLinesAhead<Win, 0, scatter_array_count<What, D>()> scatter_lines_ahead(
    bool on, const typename Win::Offsets& rows, const GridView<D, Real>& G) {
  GridLinesAhead<Win, 0, scatter_array_count<What, D>()> ahead(on, rows);
  if constexpr ((What & kMassMomentum) != 0) ahead.write(G.m);
  if constexpr ((What & kMultimaterial) != 0) ahead.write(G.vol);
  for (int d = 0; d < D; ++d) {
    if constexpr ((What & (kMassMomentum | kMomentumOnly)) != 0) ahead.write(G.p[d]);
    if constexpr ((What & kForce) != 0) ahead.write(G.f[d]);
    if constexpr ((What & kMultimaterial) != 0) ahead.write(G.mx[d]);
    if constexpr ((What & kDomainGradient) != 0) ahead.write(G.g[d]);
  }
  ahead.seal();
  return ahead;
}

// The arrays a gather of `What` (kernels/g2p_particle.hpp) reads, and the
// momenta MUSL's velocity pass adds to.
template <unsigned What, int D>
constexpr int gather_read_count() {
  return D * (1 + int((What & kUpdateMotion) != 0));
}
template <unsigned What, int D>
constexpr int gather_write_count() {
  return D * int((What & kScatterMomentum) != 0);
}
template <unsigned What, class Win, int D, class Real>
GridLinesAhead<Win, gather_read_count<What, D>(), gather_write_count<What, D>()> gather_lines_ahead(
    bool on, const typename Win::Offsets& rows, const GridView<D, Real>& G,
    const GridVelocity<D, Real>& V) {
  GridLinesAhead<Win, gather_read_count<What, D>(), gather_write_count<What, D>()> ahead(on, rows);
  for (int d = 0; d < D; ++d) {
    ahead.read(V.vel[d]);
    if constexpr ((What & kUpdateMotion) != 0) ahead.read(V.dvel[d]);
    if constexpr ((What & kScatterMomentum) != 0) ahead.write(G.p[d]);
  }
  ahead.seal();
  return ahead;
}

}  // namespace mmpm
