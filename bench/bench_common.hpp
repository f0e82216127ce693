// Shared pieces of the benchmarks: particle blocks and grids built straight
// from the kernel views (no scene, no Stepper), the binning the solver does
// before its colored scatter, the two comparison scatters (serial, atomic),
// and the counters every benchmark reports.
//
// Benchmark names are "family/key:value/key:value/..." so bench/table.py can
// read them back (Google Benchmark appends "/real_time" or "/manual_time").
#pragma once

#include <benchmark/benchmark.h>
#include <omp.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <functional>
#include <initializer_list>
#include <memory>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "kernels/binning.hpp"
#include "kernels/g2p.hpp"
#include "kernels/grid_update.hpp"
#include "kernels/grid_view.hpp"
#include "kernels/node_ownership.hpp"
#include "kernels/p2g.hpp"
#include "kernels/particle_view.hpp"
#include "kernels/reduce.hpp"
#include "kernels/shape.hpp"
#include "kernels/team.hpp"
#include "kernels/weights.hpp"
#include "model/staggered_array.hpp"
#include "solver/storage.hpp"

namespace mmpm {
class Simulation;
enum class Scheme;
}  // namespace mmpm

namespace mmpm::bench {

// Registration entry points, called in this order by bench_main.cpp.
void register_p2g();
void register_g2p();
void register_separation_shift();
void register_grid();
void register_multimaterial();
void register_sort();
void register_step();
void register_mm_scene();
void register_scaling();
void register_step_pair();
void register_team();
void register_step_ab();
void register_seed();

// The 2D linear one-material scene (bench_scaling.cpp): a square block of
// `cells` x `cells` cells, 2 x 2 particles per cell, in a grid 4 cells wider.
// bench_step.cpp's 2d_linear_1mat is linear_block_scene(250).
std::string linear_block_scene(int cells);
// The stages' names in counter names (Simulation's kStageNames, with "mm"
// for the multimaterial stage; bench_step.cpp); bench/table.py reads them.
const char* bench_stage_name(int stage);
// Per-stage counters stage_<name>_ns_per_particle from two stage_seconds()
// readings (bench_step.cpp); returns the per-stage seconds between them.
std::array<double, 7> set_stage_counters(benchmark::State& state,
                                         const std::array<double, 7>& before,
                                         const std::array<double, 7>& after, double steps,
                                         double particles);

// The whole-step scenes of bench_step.cpp that bench_mm_scene.cpp and
// bench_step_pair.cpp also use, by name ("2d_linear_1mat",
// "2d_gimp_interface", "2d_gimp_inclusions", "3d_gimp_1mat"), and their
// schemes. The Simulation is the one the step/... benchmarks of that scene
// (without overrides) step.
Simulation& step_scene_simulation(const std::string& scene);
// A new Simulation of the scene with --set style overrides
// ("simulation.fuse_step_tail=false"), owned by the caller: bench_step_ab.cpp
// compares two of the same age, where a shared one would have been stepped
// by every benchmark before (its block moved on, its arrays placed earlier).
std::unique_ptr<Simulation> new_step_scene_simulation(const std::string& scene,
                                                      const std::vector<std::string>& overrides);
Scheme step_scene_scheme(const std::string& scene);

// Paired blocks (bench_step_pair.cpp, bench_step_ab.cpp): the seconds of one
// block of timed steps, per stage and (last) for the whole step, after one
// untimed step.
using BlockTimes = std::array<double, 8>;
BlockTimes time_block(Simulation& sim, int steps);
// One pair of blocks per benchmark iteration, in the order x,y / y,x / ...
// (so a steady drift of the host's load favours neither side): run_x() and
// run_y() time one block each, appended to x and y. The iteration's time
// is the pair's wall time.
template <class RunX, class RunY>
void alternate_blocks(benchmark::State& state, RunX&& run_x, RunY&& run_y,
                      std::vector<BlockTimes>& x, std::vector<BlockTimes>& y) {
  for (auto _ : state) {
    const bool x_first = x.size() % 2 == 0;
    const BlockTimes first = x_first ? run_x() : run_y();
    const BlockTimes second = x_first ? run_y() : run_x();
    x.push_back(x_first ? first : second);
    y.push_back(x_first ? second : first);
    benchmark::ClobberMemory();
    state.SetIterationTime(first.back() + second.back());  // the last entry: the wall time
  }
}
// Per stage and the whole step ("step"), from blocks x[i] and y[i] of the
// same pairs: <nx><s> and <ny><s>, the minima in ns per particle per step
// (`per` = 1e9 / (steps x particles)); <r><s>, the median over the pairs
// of x / y; <r><s>_min, min x / min y.
void set_paired_counters(benchmark::State& state, const std::vector<BlockTimes>& x,
                         const std::vector<BlockTimes>& y, double per, const std::string& nx,
                         const std::string& ny, const std::string& r);

// The median of a sample (0 for none): the paired benchmarks' statistic.
inline double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

// dst <- src for an array of fields x nodes, each thread copying the nodes
// it owns under an even NodeOwnership (kernels/node_ownership.hpp), as the
// solver's node loops do: restoring a grid array on one thread between
// iterations would leave it in that core's cache, which is not where the
// step leaves it, and make a multi-thread measurement of the next pass
// pay for cache-line transfers the solver does not have.
template <class Real>
inline void restore_owned(Real* dst, const Real* src, std::size_t nodes, int fields) {
  const NodeOwnership even;
  team_run(nodes * std::size_t(fields) >= kParallelMin, [&] {
    for_own_nodes(even, nodes, fields, [&](std::size_t b, std::size_t e) {
      std::memcpy(dst + b, src + b, (e - b) * sizeof(Real));
    });
  });
}

template <class Real>
inline const char* real_name() {
  return sizeof(Real) == 8 ? "double" : "float";
}

// The solver's default tile edges (solver/stepper_impl.hpp setup_grid).
template <int D>
inline constexpr int kDefaultTile = D == 2 ? 16 : 8;

// ---------------------------------------------------------------- scenes
// The 2D uGIMP scenes' simulation and grid: 254 x 254 cells of 1 mm.
inline constexpr const char* kGimp2DHeader = R"(
[simulation]
dimension = 2
plane     = "strain"
thickness = 1.0
end_time  = 1.0
cfl       = 0.4

[grid]
origin = [0.0, 0.0]
cell   = [1.0, 1.0]
cells  = [254, 254]
shape  = "gimp"
)";

// The particle-filled polymer's two materials (bench_step's 625 disks,
// bench_seed's blocks of disks).
inline constexpr const char* kPolymerAndGlass = R"(
[[material]]
name    = "polymer"
type    = "isotropic"
density = 1.2e-3
E       = 2400.0
nu      = 0.33

[[material]]
name    = "glass"
type    = "isotropic"
density = 2.5e-3
E       = 70000.0
nu      = 0.22
)";

// ---------------------------------------------------------------- counters
// ns_per_particle = (time per iteration) / particles, as a rate counter: the
// value particles * 1e-9 per iteration, divided by the (real or manual) time
// and inverted, reads directly in nanoseconds.
inline void set_ns_per_item(benchmark::State& state, const char* name, double items) {
  state.counters[name] = benchmark::Counter(
      items * 1e-9, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
inline void set_ns_per_particle(benchmark::State& state, double particles) {
  set_ns_per_item(state, "ns_per_particle", particles);
  state.counters["particles"] = particles;
}
// Throughput of a quantity counted per iteration (e.g. bytes, flops), scaled
// by `unit` (1e-9: giga per second).
inline void set_rate(benchmark::State& state, const char* name, double per_iteration,
                     double unit = 1e-9) {
  state.counters[name] =
      benchmark::Counter(per_iteration * unit, benchmark::Counter::kIsIterationInvariantRate);
}

// Scale of every benchmark's minimum time (bench_main: --quick sets 0.25).
inline double& time_scale() {
  static double scale = 1.0;
  return scale;
}
inline double min_time(double seconds) {
  return seconds * time_scale();
}

// Minimum time of one registered benchmark. Each benchmark runs once per
// process; bench/run runs the whole binary several times (passes, minutes
// apart) and bench/table.py takes the minimum over the passes for headline
// times: on a shared machine, load from other jobs comes in bursts, and
// back-to-back repetitions would all fall into the same burst.
inline benchmark::internal::Benchmark* configure(benchmark::internal::Benchmark* b,
                                                 double seconds) {
  b->MinTime(min_time(seconds));
  return b;
}

// benchmark::DoNotOptimize through a const reference: the value is an asm
// input, never rewritten. (The non-const overload of Google Benchmark 1.7.1
// uses an "+m,r" constraint that GCC miscompiles for doubles: google/benchmark
// issue #903, GCC bug 92597 — it returned pointer bits as a double here.)
template <class T>
inline void keep(const T& value) {
  benchmark::DoNotOptimize(value);
}

// Thread count for the OpenMP kernels of one benchmark.
inline void use_threads(int threads) {
  omp_set_num_threads(threads);
}

// ---------------------------------------------------------------- particles
template <int D, class Real>
struct ParticleSet {
  std::vector<StaggeredArray<Real>> reals;  // every real column, permuted together
  std::vector<StaggeredArray<std::uint8_t>> bytes;
  std::vector<StaggeredArray<Real>> transient;  // L: lives within a step, never permuted
  StaggeredArray<std::uint32_t> key;
  StaggeredArray<std::uint32_t> id;  // seed index (the Stepper's tie-break in the sort)
  ParticleView<D, Real> P;
  int slot = 0;

  ParticleSet() {
    reals.reserve(64);
    bytes.reserve(4);
    transient.reserve(16);
  }
  ParticleSet(const ParticleSet&) = delete;
  ParticleSet& operator=(const ParticleSet&) = delete;
  Real* add_real(std::size_t n) {
    reals.emplace_back(n, slot++);
    return reals.back().data();
  }
  std::uint8_t* add_byte(std::size_t n) {
    bytes.emplace_back(n, slot++);
    return bytes.back().data();
  }
  Real* add_transient(std::size_t n) {
    transient.emplace_back(n, slot++);
    return transient.back().data();
  }
  std::size_t size() const { return P.n; }
  // Bytes a particle occupies over all its columns.
  std::size_t bytes_per_particle() const {
    return (reals.size() + transient.size()) * sizeof(Real) + bytes.size() +
           2 * sizeof(std::uint32_t);
  }
};

// A block of particles on a regular lattice: `ppc` per direction in every
// cell of [lo, hi) (cells of size 1, grid origin 0), generated x fastest.
struct BlockSpec {
  std::array<int, 3> lo{2, 2, 2}, hi{4, 4, 4};
  int ppc = 2;
  bool gimp = false;          // allocate the uGIMP half-widths (the solver does for gimp only)
  bool multifield = false;    // allocate the field index
  double interface_x = 1e30;  // particles with x > interface_x belong to material/field 1
};

template <int D, class Real>
void make_block(ParticleSet<D, Real>& S, const BlockSpec& b) {
  constexpr int NS = kStressComponents<D>;
  std::size_t n = 1;
  for (int d = 0; d < D; ++d) n *= std::size_t(b.hi[d] - b.lo[d]) * std::size_t(b.ppc);
  ParticleView<D, Real>& P = S.P;
  P.n = n;
  // Same column set as the Stepper (solver/stepper_impl.hpp setup_particles).
  for (int d = 0; d < D; ++d) P.x[d] = S.add_real(n);
  for (int d = 0; d < D; ++d) P.v[d] = S.add_real(n);
  P.m = S.add_real(n);
  P.V = S.add_real(n);
  for (int c = 0; c < NS; ++c) P.s[c] = S.add_real(n);
  for (int c = 0; c < D * D; ++c) P.L[c] = S.add_transient(n);
  for (int d = 0; d < D; ++d) P.x0[d] = S.add_real(n);
  // uGIMP half-widths: one value for the whole block (uniform particles per
  // cell), no column, as the Stepper's (kernels/particle_view.hpp half_width).
  if (b.gimp)
    for (int d = 0; d < D; ++d) P.lp_all[std::size_t(d)] = Real(0.5 / b.ppc);
  P.mat = S.add_byte(n);
  if (b.multifield) P.field = S.add_byte(n);
  S.key.allocate(n, S.slot++);
  P.key = S.key.data();
  S.id.allocate(n, S.slot++);
  for (std::size_t p = 0; p < n; ++p) S.id[p] = std::uint32_t(p);

  const double spacing = 1.0 / b.ppc;
  const double vol = std::pow(spacing, D);
  std::array<int, 3> count{1, 1, 1};
  for (int d = 0; d < D; ++d) count[d] = (b.hi[d] - b.lo[d]) * b.ppc;
  std::size_t p = 0;
  for (int k = 0; k < (D == 3 ? count[2] : 1); ++k)
    for (int j = 0; j < count[1]; ++j)
      for (int i = 0; i < count[0]; ++i, ++p) {
        const int idx[3] = {i, j, k};
        double x[3];
        for (int d = 0; d < D; ++d) x[d] = b.lo[d] + (idx[d] + 0.5) * spacing;
        const int material = x[0] > b.interface_x ? 1 : 0;
        for (int d = 0; d < D; ++d) {
          P.x[d][p] = Real(x[d]);
          P.x0[d][p] = Real(x[d]);
          // A smooth, non-trivial velocity field (values matter only for realism).
          P.v[d][p] = Real(0.1 * (1.0 + 0.3 * std::sin(0.05 * x[(d + 1) % D] + d)));
        }
        P.m[p] = Real(1.2e-3 * vol);
        P.V[p] = Real(vol);
        for (int c = 0; c < NS; ++c) P.s[c][p] = Real(1.0 + 0.1 * c + 0.01 * std::sin(0.1 * x[0]));
        for (int c = 0; c < D * D; ++c) P.L[c][p] = Real(1e-3 * (1 + c) * std::cos(0.07 * x[1]));
        P.mat[p] = std::uint8_t(material);
        if (P.field) P.field[p] = std::uint8_t(material);
      }
}

// ---------------------------------------------------------------- grid
template <int D, class Real>
struct GridSet {
  std::vector<StaggeredArray<Real>> cols;
  GridView<D, Real> G;
  GridVelocity<D, Real> V;
  int slot = 32;  // staggered slots distinct from the particle columns

  GridSet() { cols.reserve(64); }
  GridSet(const GridSet&) = delete;
  GridSet& operator=(const GridSet&) = delete;
  Real* add(std::size_t n) {
    cols.emplace_back(n, slot++);
    return cols.back().data();
  }
  // cells per direction; `mm` adds vol, mx, g, fi (the multimaterial fields);
  // `velocities` adds the G2P velocity arrays.
  void setup(const std::array<int, 3>& cells, int fields, bool mm, bool velocities) {
    G.fields = fields;
    G.nodes = 1;
    for (int d = 0; d < D; ++d) {
      G.nodes_per_dim[d] = cells[d] + 1;
      G.h[d] = Real(1);
      G.origin[d] = Real(0);
      G.nodes *= std::size_t(cells[d] + 1);
    }
    const std::size_t n = G.nodes * std::size_t(fields);
    G.m = add(n);
    for (int d = 0; d < D; ++d) G.p[d] = add(n), G.f[d] = add(n);
    if (mm) {
      G.vol = add(n);
      for (int d = 0; d < D; ++d) G.mx[d] = add(n), G.g[d] = add(n), G.fi[d] = add(n);
    }
    if (velocities)
      for (int d = 0; d < D; ++d) V.vel[d] = add(n), V.dvel[d] = add(n);
  }
  std::size_t size() const { return G.nodes * std::size_t(G.fields); }
  void zero() {
    for (auto& c : cols) std::memset(static_cast<void*>(c.data()), 0, c.size() * sizeof(Real));
  }
};

// ---------------------------------------------------------------- binning
// The solver's sort (Stepper::sort_particles): keys by tile, stable counting
// sort (a cell's particles in seed order), the keys permuted, tile ranges
// and color lists of the new order, then every other column permuted into
// the threads' ranges of that order.
template <int D, class Real>
struct Binning {
  TileLayout<D> tiles;
  std::vector<std::uint32_t> offsets, perm;
  TileSchedule schedule;
  std::vector<Real> scratch;
  std::vector<std::uint8_t> scratch_bytes;
  std::vector<std::uint32_t> scratch_keys;

  std::array<Real, 3> origin{};  // key_origins of the grid (kernels/shape.hpp)

  template <class Shape>
  void setup(int tile_edge, const GridView<D, Real>& G) {
    std::array<int, 3> cells{1, 1, 1};
    for (int d = 0; d < D; ++d) cells[d] = G.nodes_per_dim[d] - 1;
    tiles.setup(tile_edge, cells);
    origin = key_origins<D, Shape>(G.origin, G.h);
  }
  std::uint32_t key_of(const ParticleView<D, Real>& P, const GridView<D, Real>& G,
                       std::size_t p) const {
    std::array<int, 3> c{0, 0, 0};
    for (int d = 0; d < D; ++d) c[d] = cell_of(P.x[d][p], origin[d], Real(1) / G.h[d]);
    return tiles.key(c);
  }
  void compute_keys(ParticleSet<D, Real>& S, const GridView<D, Real>& G) const {
    const std::size_t n = S.P.n;
    team_for(n >= kParallelMin, n, [&](std::size_t p) { S.P.key[p] = key_of(S.P, G, p); });
  }
  void count(ParticleSet<D, Real>& S) {
    counting_sort(S.P.key, S.P.n, tiles.key_count(), offsets, perm, S.id.data());
  }
  void permute_keys(ParticleSet<D, Real>& S) {
    scratch_keys.resize(S.P.n);
    permute_in_place(S.P.key, scratch_keys.data(), perm.data(), S.P.n);
  }
  void rebuild_ranges(const ParticleSet<D, Real>& S) { schedule.build(tiles, S.P.key, S.P.n); }
  void permute_columns(ParticleSet<D, Real>& S) {
    permute_particle_columns(S, perm.data(), S.P.n, schedule, scratch_keys, scratch, scratch_bytes);
  }
  void sort(ParticleSet<D, Real>& S, const GridView<D, Real>& G) {
    compute_keys(S, G);
    count(S);
    permute_keys(S);
    rebuild_ranges(S);
    permute_columns(S);
  }
};

// ---------------------------------------------------------------- scatters
// The colored pass of the Stepper's scatters (Stepper::p2g, MUSL's fused
// G2P): colors in turn, the tiles of a color in parallel, each thread its
// share. range(b, e) runs one tile's particles and returns its first bad
// particle or SIZE_MAX; the smallest is returned.
template <class Range>
std::size_t colored_tiles(const TileSchedule& S, std::size_t n, const Range& range) {
  std::atomic<std::size_t> first_bad{SIZE_MAX};
  for (std::size_t c = 0; c < S.tiles.size(); ++c) {
    if (S.tiles[c].empty()) continue;
    team_run(n >= kParallelMin, [&] {
      std::size_t bad = SIZE_MAX;
      for (auto [k, last] = S.share(c, std::size_t(team_size()), std::size_t(team_rank()));
           k < last; ++k) {
        const std::uint32_t t = S.tiles[c][k];
        bad = std::min(bad, range(std::size_t(S.begin[t]), std::size_t(S.begin[t + 1])));
      }
      offer_min(first_bad, bad);
    });
  }
  return first_bad.load();
}

// (a) The solver's colored scatter (Stepper::p2g), each tile added straight
// into the grid. Windowed = false runs the pointwise reference kernel in the
// same tiles; Units, the windowed block's vector layout (RowUnits: the
// one-row units the two-row scatter units replaced, kernels/window.hpp).
template <int D, class Shape, class Real, unsigned What, bool MultiField, bool Traction,
          bool Windowed = true, class Units = ScatterUnits<D, Shape, Real>>
std::size_t p2g_colored(const ParticleView<D, Real>& P, const GridView<D, Real>& G,
                        const P2GOptions& opt, const Binning<D, Real>& B) {
  return colored_tiles(B.schedule, P.n, [&](std::size_t b, std::size_t e) {
    const std::size_t r =
        Windowed ? p2g_range<D, Shape, Real, What, MultiField, Traction, Units>(P, G, opt, b, e)
                 : p2g_range_pointwise<D, Shape, Real, What, MultiField, Traction>(P, G, opt, b, e);
    return r == e ? SIZE_MAX : r;
  });
}

// (b) Serial scatter: one thread, particle order.
template <int D, class Shape, class Real, unsigned What, bool Windowed = true>
std::size_t p2g_serial(const ParticleView<D, Real>& P, const GridView<D, Real>& G,
                       const P2GOptions& opt) {
  const std::size_t r =
      Windowed ? p2g_range<D, Shape, Real, What, false, false>(P, G, opt, 0, P.n)
               : p2g_range_pointwise<D, Shape, Real, What, false, false>(P, G, opt, 0, P.n);
  return r == P.n ? SIZE_MAX : r;
}

// (c) Atomic scatter: particles split statically across the threads, every
// grid addition atomic (the same sums as p2g_range with kMassMomentum |
// kForce, one field, no traction). A relaxed std::atomic_ref add compiles to
// the compare-and-swap loop `omp atomic` makes of a floating-point add; it
// runs on the solver's team, as every other parallel bench loop: a libgomp
// region would leave its idle thread spinning for ~2.5 ms on the core the
// next benchmark's team member needs (kernels/team.hpp).
template <int D, class Shape, class Real>
std::size_t p2g_atomic(const ParticleView<D, Real>& P, const GridView<D, Real>& G) {
  constexpr int NS = kStressComponents<D>;
  const std::array<Real, 3> inv_h{Real(1) / G.h[0], Real(1) / G.h[1], Real(1) / G.h[2]};
  const std::size_t n = P.n;
  auto add = [](Real& to, Real v) {
    std::atomic_ref<Real>(to).fetch_add(v, std::memory_order_relaxed);
  };
  std::atomic<std::size_t> first_bad{SIZE_MAX};
  team_run(true, [&] {
    Stencil<D, Shape, Real> st{};
    std::size_t bad = SIZE_MAX;
    const auto [first, last] = thread_block(n, std::size_t(team_size()), std::size_t(team_rank()));
    for (std::size_t p = first; p < last; ++p) {
      if (!st.build(P, G, inv_h, p)) {
        bad = std::min(bad, p);
        continue;
      }
      const Real mp = P.m[p];
      Real mv[D], vs[NS];
      for (int d = 0; d < D; ++d) mv[d] = mp * P.v[d][p];
      for (int c = 0; c < NS; ++c) vs[c] = P.V[p] * P.s[c][p];
      for (int k = 0; k < st.count; ++k) {
        const std::size_t i = st.base + st.node[k];
        const Real w = st.w[k];
        const auto& gk = st.g[k];
        Real f[D];
        if constexpr (D == 2) {
          f[0] = -(vs[0] * gk[0] + vs[2] * gk[1]);
          f[1] = -(vs[2] * gk[0] + vs[1] * gk[1]);
        } else {
          f[0] = -(vs[0] * gk[0] + vs[5] * gk[1] + vs[4] * gk[2]);
          f[1] = -(vs[5] * gk[0] + vs[1] * gk[1] + vs[3] * gk[2]);
          f[2] = -(vs[4] * gk[0] + vs[3] * gk[1] + vs[2] * gk[2]);
        }
        add(G.m[i], w * mp);
        for (int d = 0; d < D; ++d) {
          add(G.p[d][i], w * mv[d]);
          add(G.f[d][i], f[d]);
        }
      }
    }
    offer_min(first_bad, bad);
  });
  return first_bad.load();
}

// Floating-point operations of the kMassMomentum | kForce scatter per stencil
// node (one field, no traction): m 2, p 2D, f D * (2D) (D products, D-1 sums,
// one subtraction into the grid). Stencil construction is not counted.
template <int D>
inline constexpr int kP2GFlopsPerNode = 2 + 2 * D + D * 2 * D;

// Particle bytes the scatter streams in (x, v, m, V, stress, lp for gimp).
template <int D, class Shape, class Real>
inline constexpr std::size_t kP2GParticleBytes = sizeof(Real) *
                                                 (2 * D + 2 + kStressComponents<D> +
                                                  (std::is_same_v<Shape, GimpShape> ? D : 0));

// ---------------------------------------------------------------- fixture cache
// Benchmarks of one family share their (large) fixture across the repeated
// calls Google Benchmark makes; only one fixture is alive at a time.
inline std::function<void()>& fixture_release() {
  static std::function<void()> release;
  return release;
}
template <class Fixture, class Key, class Make>
Fixture& cached_fixture(const Key& key, Make&& make) {
  static std::unique_ptr<Fixture> fx;
  static Key fx_key{};
  if (!fx || !(fx_key == key)) {
    if (fixture_release()) fixture_release()();
    fx = make();
    fx_key = key;
    fixture_release() = [] { fx.reset(); };
  }
  return *fx;
}

}  // namespace mmpm::bench
