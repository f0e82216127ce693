// Software prefetch of the particle columns a pass streams, a fixed number
// of particles ahead ([simulation] prefetch_particles, default on; the
// solver requests in 2D only, Stepper::particles_ahead).
//
// Why: a transfer pass streams 8-16 particle columns (x, v, m, V, sigma,
// x_next, ...) beside the short grid row pieces of its windows. Once the
// columns leave the caches, the hardware prefetchers of the Intel host
// (Xeon, 2 MiB L2 per core) did not keep that many streams ahead: the 2D
// linear step read 40.2 ns/particle-step at 3*10^6 particles against 26.3
// at 3*10^5 on one thread. Requesting every column's lines kAhead particles
// ahead, one batch at a time, brought it to 33.5-35.3 (docs/performance.md
// "Particle columns requested ahead"). A request is a hint: no value
// changes, and a line past a column's end is never requested.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>

#include "kernels/particle_view.hpp"

namespace mmpm {

// The solver requests only when a pass's columns take this much and more
// (Stepper::particles_ahead): the 2D linear step at 10^4 particles (1.3 MiB
// of columns, in the L2) read 25.1 against 24.5 ns/particle-step with the
// requests, at 10^5 (12 MiB) the same, at 3*10^5 26.1 against 30.3.
inline constexpr std::size_t kPrefetchMinParticleBytes = std::size_t(4) << 20;

// What a pass does to the particles, for the columns it streams. Every
// transfer (scatter, motion, gradient, commit) also reads the position, its
// float low part, the uGIMP half-width and the field byte.
enum ParticleStreams : unsigned {
  kStreamScatter = 1u << 0,       // P2G of m, m v, V sigma: m, v, V, the force's sigma
  kStreamMotion = 1u << 1,        // G2P of the updated velocity: v; x_next (MUSL) or x
  kStreamMomentum = 1u << 2,      // MUSL's momenta scattered in the same pass: m
  kStreamGradient = 1u << 3,      // G2P of the velocity gradient into the L columns
  kStreamCommit = 1u << 4,        // x <- x_next: x_next (the tile-change test reads the
                                  // key after the range, as one stream)
  kStreamConstitutive = 1u << 5,  // the stress update: sigma, V, H, the material byte
  kStreamShift = 1u << 6,         // MUSL's separation shift: sep_shift (x_next with kStreamCommit)
};
inline constexpr unsigned kStreamTransfer =
    kStreamScatter | kStreamMotion | kStreamGradient | kStreamCommit;

class ParticleLinesAhead {
 public:
  // Particles ahead of the batch being worked on: 2 KiB of a double column.
  // 64, 256 and 512 measured the same at 3*10^6 particles (34.1, 34.1, 34.4
  // ns/particle-step), 2048 slower (35.2): the lines must arrive before the
  // batch, and stay in the cache until it comes.
  static constexpr std::size_t kAhead = 256;

  ParticleLinesAhead() = default;  // requests nothing

  // The columns `streams` touches in P (null columns: the scene has none),
  // for particles [0, P.n). `L_in_columns`: the gradient goes to P.L (false:
  // the fused tail holds it in a per-tile block, which needs no request).
  template <int D, class Real>
  ParticleLinesAhead(const ParticleView<D, Real>& P, unsigned streams, bool L_in_columns)
      : n_(P.n) {
    constexpr int NS = kStressComponents<D>;
    const bool moves_x = (streams & kStreamCommit) || ((streams & kStreamMotion) && !P.x_next[0]);
    if (streams & kStreamTransfer) {
      for (int d = 0; d < D; ++d) {
        add(P.x[d], moves_x);
        add(P.xlo[d], moves_x);
        add(P.lp[d], false);
      }
      add(P.field, false);
    }
    if (streams & (kStreamScatter | kStreamMotion))
      for (int d = 0; d < D; ++d) add(P.v[d], (streams & kStreamMotion) != 0);
    if (streams & (kStreamScatter | kStreamMomentum)) add(P.m, false);
    if (streams & (kStreamScatter | kStreamConstitutive))
      add(P.V, (streams & kStreamConstitutive) != 0);
    if (streams & kStreamConstitutive) {
      for (int c = 0; c < NS; ++c) add(P.s[std::size_t(c)], true);
      for (int c = 0; c < D * D; ++c) add(P.H[std::size_t(c)], true);
      add(P.mat, false);
    } else if (streams & kStreamScatter) {
      // The force reads the in-plane components only (window_block.hpp).
      for (int c = 0; c < (D == 2 ? 3 : NS); ++c) add(P.s[std::size_t(c)], false);
    }
    if ((streams & kStreamGradient) && L_in_columns)
      for (int c = 0; c < D * D; ++c) add(P.L[std::size_t(c)], true);
    if (streams & kStreamMotion)
      for (int d = 0; d < D; ++d) add(P.x_next[d], true);
    if (streams & kStreamCommit)
      for (int d = 0; d < D; ++d) add(P.x_next[d], false);
    if (streams & kStreamShift)
      for (int d = 0; d < D; ++d) add(P.sep_shift[d], true);
  }

  bool on() const { return reads_ + writes_ > 0; }
  int columns() const { return reads_ + writes_; }
  // Bytes of one particle in the columns requested.
  std::size_t bytes_per_particle() const {
    std::size_t b = 0;
    for (int c = 0; c < reads_; ++c) b += read_[std::size_t(c)].bytes;
    for (int c = 0; c < writes_; ++c) b += write_[std::size_t(c)].bytes;
    return b;
  }

  // Called with each batch [first, first + n) a pass starts on: requests
  // the lines of [first + kAhead, first + kAhead + n) of every column.
  [[gnu::always_inline]] void batch(std::size_t first, std::size_t n) const {
    const std::size_t from = first + kAhead;
    if (from >= n_) return;
    const std::size_t to = std::min(from + n, n_);
    for (int c = 0; c < reads_; ++c) request<0>(read_[std::size_t(c)], from, to);
    for (int c = 0; c < writes_; ++c) request<1>(write_[std::size_t(c)], from, to);
  }

 private:
  struct Column {
    std::uintptr_t base = 0;
    std::size_t bytes = 0;  // per particle
  };
  static constexpr int kMaxColumns = 48;
  static constexpr std::uintptr_t kLine = 64;

  template <class T>
  void add(const T* column, bool write) {
    if (!column) return;
    const Column c{reinterpret_cast<std::uintptr_t>(column), sizeof(T)};
    // A column listed twice (x_next read and written) is requested once.
    for (int k = 0; k < reads_; ++k)
      if (read_[std::size_t(k)].base == c.base) return;
    for (int k = 0; k < writes_; ++k)
      if (write_[std::size_t(k)].base == c.base) return;
    if (write && writes_ < kMaxColumns) write_[std::size_t(writes_++)] = c;
    if (!write && reads_ < kMaxColumns) read_[std::size_t(reads_++)] = c;
  }
  // Integer addresses: a request is a hint, never a C++ pointer past an array.
  // Locality 2 (into the L2, not the L1): 256 particles of up to 20 columns
  // are 40 KiB, most of the 48 KiB L1 that the windows' grid rows live in.
  // At 3*10^6 particles 2 and 3 measured the same (36.1-36.2 against
  // 35.8-36.7 ns/particle-step, alternated).
  template <int Write>
  [[gnu::always_inline]] static void request(const Column& c, std::size_t from, std::size_t to) {
    const std::uintptr_t last = c.base + to * c.bytes - 1;
    for (std::uintptr_t a = (c.base + from * c.bytes) & ~(kLine - 1); a <= last; a += kLine)
      __builtin_prefetch(reinterpret_cast<const void*>(a), Write, 2);
  }

  std::size_t n_ = 0;
  int reads_ = 0, writes_ = 0;
  std::array<Column, kMaxColumns> read_{}, write_{};
};

}  // namespace mmpm
