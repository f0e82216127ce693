// The local block of the windowed scatter (kernels/window.hpp): the sums of
// one window's particles for every grid quantity a transfer writes, added
// to the grid when the window changes (P2GWhat selects the quantities).
#pragma once

#include <cstddef>
#include <cstdint>

#include "kernels/grid_view.hpp"
#include "kernels/particle_prefetch.hpp"
#include "kernels/particle_view.hpp"
#include "kernels/position_sum.hpp"
#include "kernels/weight_batch.hpp"
#include "kernels/window.hpp"

namespace mmpm {

// What a P2G pass scatters (bit mask).
enum P2GWhat : unsigned {
  kMassMomentum = 1u,     // m, p
  kForce = 2u,            // internal force -V sigma.G, traction force S fext
  kMultimaterial = 4u,    // mx, Omega  (ALGORITHM §1, P-10/13, P-19)
  kMomentumOnly = 8u,     // p alone (MUSL's second transfer)
  kDomainGradient = 16u,  // g (P-33), with kMultimaterial, for the mvg/avg/rigid normals only
};

struct P2GOptions {
  bool position_separation = false;  // mx holds positions (else displacements)
  double inv_thickness = 1.0;        // 2D: Omega and g are areas (P-19, P-33)
  bool prefetch_grid = true;         // 2D: the grid lines a line ahead (kernels/grid_prefetch.hpp)
  // The particle columns a batch ahead (kernels/particle_prefetch.hpp); null: none.
  const ParticleLinesAhead* particles_ahead = nullptr;
};

// The per-particle factors a transfer scatters (ALGORITHM §1-2).
template <int D, class Real>
struct ScatterSource {
  static constexpr int NS = kStressComponents<D>;
  Real m = 0;        // mass
  Real mv[D] = {};   // momentum
  Real vs[NS] = {};  // V sigma
  Real fe[D] = {};   // traction force
  Real area = 0;     // nodal-domain weight (P-19)
  Real mw[D] = {};   // mass times displacement (or position)
};

// The per-particle factors of particle p (what WindowBlock::accumulate
// scatters), for P2G and MUSL's inline momentum scatter in G2P, written
// into q in place. With What = kMomentumOnly only m and mv are set (opt and
// inv_t are not read); the other fields keep what they held. The batch
// loops (p2g_range_grouped, G2P's deferred momentum scatter) fill a
// ScatterSourceBatch instead (below); filling an array of these structs
// first went through stack temporaries, each copy waiting on a failed
// store-to-load forward (docs/performance.md "Scatter sources filled in
// place"), then stored every lane on its own.
template <int D, class Real, unsigned What, bool Traction>
[[gnu::always_inline]] inline void fill_scatter_source(ScatterSource<D, Real>& q,
                                                       const ParticleView<D, Real>& P,
                                                       const P2GOptions& opt, Real inv_t,
                                                       std::size_t p) {
  constexpr int NS = kStressComponents<D>;
  const Real m = P.m[p];
  q.m = m;
  for (int d = 0; d < D; ++d) q.mv[d] = m * P.v[d][p];
  if constexpr ((What & kForce) != 0) {
    const Real V = P.V[p];
    for (int c = 0; c < NS; ++c) q.vs[c] = V * P.s[c][p];
    if constexpr (Traction)
      for (int d = 0; d < D; ++d) q.fe[d] = P.fext[d][p];
  }
  if constexpr ((What & kMultimaterial) != 0) {
    q.area = P.V[p] * (D == 2 ? inv_t : Real(1));
    for (int d = 0; d < D; ++d)
      q.mw[d] = m * separation_coordinate(P, opt.position_separation, d, p);
  }
}

// The same factors as a value (the one-block scatters keep it in registers).
template <int D, class Real, unsigned What, bool Traction>
[[gnu::always_inline]] inline ScatterSource<D, Real> scatter_source(const ParticleView<D, Real>& P,
                                                                    const P2GOptions& opt,
                                                                    Real inv_t, std::size_t p) {
  ScatterSource<D, Real> q;
  fill_scatter_source<D, Real, What, Traction>(q, P, opt, inv_t, p);
  return q;
}

// The factors of a batch of particles (at most kWeightBatch), field by
// field: what the grouped scatter (GroupedScatter below) reads for each
// particle of a run once per group. Why by field and not as an array of
// ScatterSource: the fill loop, which GCC vectorises across particles,
// then stores one vector per field and 8 particles, where filling structs
// stored every lane on its own (13 scalar stores and their extracts per 3D
// particle: most of the fill loop's ~13 % of the 3D uGIMP P2G samples,
// docs/performance.md "Scatter sources stored by field"). Same products,
// so the same bits. Fields a transfer does not scatter stay unwritten and
// are never read.
template <int D, class Real>
struct ScatterSourceBatch {
  static constexpr int NS = kStressComponents<D>;
  Real mv[D][kWeightBatch], vs[NS][kWeightBatch], area[kWeightBatch], mw[D][kWeightBatch];
  // The masses and traction forces are read in place (a copy loop became a
  // call to memmove).
  const Real* m = nullptr;
  const Real* fe[D] = {};

  // Entries 0 .. count - 1 from particles first .. first + count - 1, the
  // products of fill_scatter_source.
  template <unsigned What, bool Traction>
  [[gnu::always_inline]] void fill(const ParticleView<D, Real>& P, const P2GOptions& opt,
                                   Real inv_t, std::size_t first, std::size_t count) {
    const Real* __restrict pm = P.m + first;
    m = pm;
    for (int d = 0; d < D; ++d) {
      const Real* __restrict pv = P.v[d] + first;
      for (std::size_t i = 0; i < count; ++i) mv[d][i] = pm[i] * pv[i];
    }
    if constexpr ((What & kForce) != 0) {
      const Real* __restrict pV = P.V + first;
      for (int c = 0; c < NS; ++c) {
        const Real* __restrict ps = P.s[c] + first;
        for (std::size_t i = 0; i < count; ++i) vs[c][i] = pV[i] * ps[i];
      }
      if constexpr (Traction)
        for (int d = 0; d < D; ++d) fe[d] = P.fext[d] + first;
    }
    if constexpr ((What & kMultimaterial) != 0) {
      for (std::size_t i = 0; i < count; ++i) area[i] = P.V[first + i] * (D == 2 ? inv_t : Real(1));
      for (int d = 0; d < D; ++d)
        for (std::size_t i = 0; i < count; ++i)
          mw[d][i] = pm[i] * separation_coordinate(P, opt.position_separation, d, first + i);
    }
  }

  // Entry k as the one-particle factors (only What's fields are read; the
  // compiler keeps them as memory operands of the multiply-adds).
  template <unsigned What, bool Traction>
  [[gnu::always_inline]] ScatterSource<D, Real> at(std::size_t k) const {
    ScatterSource<D, Real> q;
    q.m = m[k];
    for (int d = 0; d < D; ++d) q.mv[d] = mv[d][k];
    if constexpr ((What & kForce) != 0) {
      for (int c = 0; c < NS; ++c) q.vs[c] = vs[c][k];
      if constexpr (Traction)
        for (int d = 0; d < D; ++d) q.fe[d] = fe[d][k];
    }
    if constexpr ((What & kMultimaterial) != 0) {
      q.area = area[k];
      for (int d = 0; d < D; ++d) q.mw[d] = mw[d][k];
    }
    return q;
  }
};

// Offset of particle p's field in the field-major grid arrays (0 with one field).
template <bool MultiField, int D, class Real>
[[gnu::always_inline]] inline std::size_t field_offset(const ParticleView<D, Real>& P,
                                                       const GridView<D, Real>& G, std::size_t p) {
  return MultiField ? std::size_t(P.field[p]) * G.nodes : 0;
}

// Sums for UG units of the window (all of them by default), units as Units
// lays them out (kernels/window.hpp: ScatterUnits, or RowUnits, the
// benchmarks' baseline); the member templates take the first unit U0 of the
// group (GroupedScatter below splits the window into groups when one block
// would not fit in the registers; the last group may hold fewer units).
template <int D, class Shape, class Real, unsigned What, bool Traction,
          int UG = ScatterUnits<D, Shape, Real>::units, class Units = ScatterUnits<D, Shape, Real>>
struct WindowBlock {
  using Win = Window<D, Shape, Real>;
  using V = typename Units::V;
  static constexpr int U = UG;
  // Units of the group starting at window unit U0.
  static constexpr int count(int U0) { return U0 + U <= Units::units ? U : Units::units - U0; }
  static constexpr bool kMass = (What & kMassMomentum) != 0;
  static constexpr bool kMom = (What & (kMassMomentum | kMomentumOnly)) != 0;
  static constexpr bool kFrc = (What & kForce) != 0;
  static constexpr bool kMM = (What & kMultimaterial) != 0;
  static constexpr bool kGrad = kMM && (What & kDomainGradient) != 0;
  // Vectors summed per unit.
  static constexpr int kQuantities =
      int(kMass) + (kMom ? D : 0) + (kFrc ? D : 0) + (kMM ? 1 + D : 0) + (kGrad ? D : 0);

  V am[U], ap[D][U], af[D][U], avol[U], amx[D][U], ag[D][U];
  std::size_t current = SIZE_MAX;  // window base (with field offset) the block holds

  WindowBlock() { clear(); }

  void clear() {
    for (int u = 0; u < U; ++u) {
      if constexpr (kMass) am[u] = V{};
      for (int d = 0; d < D; ++d) {
        if constexpr (kMom) ap[d][u] = V{};
        if constexpr (kFrc) af[d][u] = V{};
        if constexpr (kMM) amx[d][u] = V{};
        if constexpr (kGrad) ag[d][u] = V{};
      }
      if constexpr (kMM) avol[u] = V{};
    }
  }

  // Adds the block to the grid at `current` (if it holds anything).
  template <int U0 = 0>
  void flush(const GridView<D, Real>& G, const typename Win::Offsets& off) {
    if (current == SIZE_MAX) return;
    const std::size_t b = current;
    static_for<count(U0)>([&](auto uc) __attribute__((always_inline)) {
      constexpr int u = decltype(uc)::value, wu = U0 + u;  // block unit, window unit
      if constexpr (kMass) Units::template add<wu>(G.m + b, off, am[u]);
      for (int d = 0; d < D; ++d) {
        if constexpr (kMom) Units::template add<wu>(G.p[d] + b, off, ap[d][u]);
        if constexpr (kFrc) Units::template add<wu>(G.f[d] + b, off, af[d][u]);
        if constexpr (kMM) Units::template add<wu>(G.mx[d] + b, off, amx[d][u]);
        if constexpr (kGrad) Units::template add<wu>(G.g[d] + b, off, ag[d][u]);
      }
      if constexpr (kMM) Units::template add<wu>(G.vol + b, off, avol[u]);
    });
  }

  // Moves the block to window base b, writing out what it held before.
  template <int U0 = 0>
  void at(std::size_t b, const GridView<D, Real>& G, const typename Win::Offsets& off) {
    if (b == current) return;
    if (current != SIZE_MAX) {
      flush<U0>(G, off);
      clear();
    }
    current = b;
  }

  template <int U0 = 0>
  void accumulate(const Win& win, const ScatterSource<D, Real>& q) {
    const V X = Units::X(win), GXl = Units::GX(win);
    static_for<count(U0)>([&](auto uc) __attribute__((always_inline)) {
      constexpr int u = decltype(uc)::value, wu = U0 + u;  // block unit, window unit
      const V Yu = Units::template Y<wu>(win);
      const V s = X * Yu;
      const V Gx = GXl * Yu, Gy = X * Units::template GY<wu>(win);
      if constexpr (kMass) am[u] += s * q.m;
      if constexpr (kMom)
        for (int d = 0; d < D; ++d) ap[d][u] += s * q.mv[d];
      if constexpr (kFrc) {
        // f = -V sigma . G (+ S fext); 2D sigma: xx, yy, xy, zz; 3D Voigt: xx, yy, zz, yz, xz, xy.
        // Each term subtracted on its own: one negated multiply-add per
        // term, where subtracting the sum cost a multiply, a multiply-add
        // per further term and a subtraction (the sum's order is fixed
        // without -ffast-math). The 2D uGIMP P2G is bound by its vector
        // instructions (docs/performance.md "The force's terms subtracted
        // one by one").
        if constexpr (D == 2) {
          af[0][u] -= q.vs[0] * Gx;
          af[0][u] -= q.vs[2] * Gy;
          af[1][u] -= q.vs[2] * Gx;
          af[1][u] -= q.vs[1] * Gy;
        } else {
          const V Gz = X * Units::template GZ<wu>(win);
          af[0][u] -= q.vs[0] * Gx;
          af[0][u] -= q.vs[5] * Gy;
          af[0][u] -= q.vs[4] * Gz;
          af[1][u] -= q.vs[5] * Gx;
          af[1][u] -= q.vs[1] * Gy;
          af[1][u] -= q.vs[3] * Gz;
          af[2][u] -= q.vs[4] * Gx;
          af[2][u] -= q.vs[3] * Gy;
          af[2][u] -= q.vs[2] * Gz;
        }
        if constexpr (Traction)
          for (int d = 0; d < D; ++d) af[d][u] += s * q.fe[d];
      }
      if constexpr (kMM) {
        avol[u] += s * q.area;
        for (int d = 0; d < D; ++d) amx[d][u] += s * q.mw[d];
      }
      if constexpr (kGrad) {
        ag[0][u] += Gx * q.area;
        ag[1][u] += Gy * q.area;
        if constexpr (D == 3) ag[2][u] += (X * Units::template GZ<wu>(win)) * q.area;
      }
    });
  }
};

// Vector registers one window block may keep its sums in: AVX-512 has 32,
// AVX2 16, and the weights and factors of the particle need a few.
#ifdef __AVX512F__
inline constexpr int kVectorRegisters = 28;
#else
inline constexpr int kVectorRegisters = 12;
#endif
// The same budget in vectors of type V (one of 64 bytes is two AVX2
// registers; one of 32 bytes, a row of 4 doubles, is one register either way).
template <class V>
constexpr int block_register_budget() {
  constexpr int bytes = int(sizeof(V));
  constexpr int reg = int(kRegisterVectorBytes);
  return kVectorRegisters / (bytes > reg ? bytes / reg : 1);
}

// Units per block group: all of the scatter's units when their sums fit in
// the registers, else as few groups as fit, of equal size but for a smaller
// last one (3D uGIMP and B-splines in double: 64 nodes x 7 quantities = 56
// vectors of 8 lanes, 2 groups of 4; binned by the nearest node,
// kernels/shape.hpp: 5 units of 2 rows x 7 = 35 vectors, groups of 3 and 2).
template <int D, class Shape, class Real, unsigned What, bool Traction,
          class Units = ScatterUnits<D, Shape, Real>>
constexpr int block_group_units() {
  constexpr int q = WindowBlock<D, Shape, Real, What, Traction, 1, Units>::kQuantities;
  constexpr int units = Units::units;
  constexpr int fit = block_register_budget<typename Units::V>() / q;
  constexpr int groups = fit < 1 ? units : (units + fit - 1) / fit;
  return (units + groups - 1) / groups;
}

// Scatters windows a batch at a time with the window's units in groups of
// UG, each group's sums in registers (kernels/p2g.hpp says why). Each run of
// particles with the same window is taken whole, group after group, and a
// run cut by the end of a batch carries its sums into the next one, so
// every node gets the same sums in the same order as with one block of all
// units: bitwise equal results (tests/test_p2g.cpp). Scattering group by
// group over a whole batch instead would reorder the adds of overlapping
// windows.
template <int D, class Shape, class Real, unsigned What, bool Traction, int UG,
          class Units = ScatterUnits<D, Shape, Real>>
class GroupedScatter {
 public:
  using Win = Window<D, Shape, Real>;
  using Block = WindowBlock<D, Shape, Real, What, Traction, UG, Units>;
  static constexpr int kGroups = (Units::units + UG - 1) / UG;  // the last one may be short

  explicit GroupedScatter(const GridView<D, Real>& G) : G_(G), off_(Win::offsets(G)) {}

  // Windows w[0, count) in particle order, with their bases (field offset
  // included) and sources; `more`: particles follow, so a run reaching
  // count may go on in the next call.
  void add(const Win* w, const std::size_t* base, const ScatterSourceBatch<D, Real>& q,
           std::size_t count, bool more) {
    if (carrying_ && (count == 0 || base[0] != carried_[0].current)) finish();
    for (std::size_t i = 0; i < count;) {
      std::size_t j = i + 1;
      while (j < count && base[j] == base[i]) ++j;
      const bool resume = i == 0 && carrying_;
      const bool cut = j == count && more;
      static_for<kGroups>([&](auto gc) __attribute__((always_inline)) {
        constexpr int g = decltype(gc)::value;
        Block block;  // a local the compiler keeps in registers
        if (resume) block = carried_[g];
        block.current = base[i];
        for (std::size_t k = i; k < j; ++k)
          block.template accumulate<g * UG>(w[k], q.template at<What, Traction>(k));
        if (cut)
          carried_[g] = block;
        else
          block.template flush<g * UG>(G_, off_);
      });
      carrying_ = cut;
      i = j;
    }
  }

  // Writes out a carried run (call once the particles are done).
  void finish() {
    if (!carrying_) return;
    static_for<kGroups>([&](auto gc) __attribute__((always_inline)) {
      constexpr int g = decltype(gc)::value;
      carried_[g].template flush<g * UG>(G_, off_);
      carried_[g].clear();
    });
    carrying_ = false;
  }

 private:
  GridView<D, Real> G_;
  typename Win::Offsets off_;
  Block carried_[kGroups];  // each group's sums of the run the last batch ended in
  bool carrying_ = false;
};

}  // namespace mmpm
