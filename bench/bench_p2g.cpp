// P2G: the three scatter strategies side by side (ARCHITECTURE "Parallel
// scatter without races") for every shape function, 2D and 3D, double and
// float, 1 and 2 threads; and the tile edge of the colored scatter.
//
// Problem: a block of particles filling most of the grid, 2 per cell and
// direction: 2D 250x250 cells in a 254x254 grid (250 000 particles), 3D
// 32^3 cells in a 36^3 grid (262 144 particles). What is scattered is the
// solver's single-material USL transfer: mass, momentum, internal force.
// Every strategy reads the same particle arrays, sorted by tile key as the
// solver keeps them (sorting is measured on its own in bench_sort.cpp).
// The grid is zeroed once per run, not per iteration (zeroing is O(nodes)
// and appears in the whole-step numbers); a check at the end compares the
// grid's total mass with iterations x particle mass, so a strategy that
// loses additions is reported as an error.
#include "bench/bench_common.hpp"

namespace mmpm::bench {
namespace {

// colored / serial: the solver's windowed kernel (kernels/window.hpp);
// colored_pointwise / serial_pointwise: the reference kernel that adds every
// particle into its stencil node by node (the scatter before the window);
// colored_row_units: the windowed kernel with one window row per vector unit
// (RowUnits), registered where the solver's units (ScatterUnits) take two
// rows: 3D uGIMP and quadratic B-splines in double.
enum class Strategy {
  colored,
  serial,
  atomic,
  colored_pointwise,
  serial_pointwise,
  colored_row_units
};

const char* strategy_name(Strategy s) {
  switch (s) {
    case Strategy::colored:
      return "colored";
    case Strategy::serial:
      return "serial";
    case Strategy::atomic:
      return "atomic";
    case Strategy::colored_pointwise:
      return "colored_pointwise";
    case Strategy::serial_pointwise:
      return "serial_pointwise";
    case Strategy::colored_row_units:
      return "colored_row_units";
  }
  return "?";
}

// The block's edge in cells: 250 in 2D, 32 in 3D, unless a size sweep
// (p2g_size) asks for another; the grid is the block plus 2 cells a side.
template <int D>
constexpr int kDefaultBlockCells = D == 2 ? 250 : 32;

template <int D>
BlockSpec p2g_block(bool gimp, int cells) {
  BlockSpec b;
  b.ppc = 2;
  b.gimp = gimp;
  for (int d = 0; d < D; ++d) {
    b.lo[d] = 2;
    b.hi[d] = 2 + cells;
  }
  return b;
}
template <int D>
std::array<int, 3> p2g_cells(int cells) {
  return {cells + 4, cells + 4, D == 2 ? 1 : cells + 4};
}

template <int D, class Shape, class Real>
struct P2GFixture {
  ParticleSet<D, Real> S;
  GridSet<D, Real> grid;
  Binning<D, Real> bins;
  double total_mass = 0;
};

template <int D, class Shape, class Real>
P2GFixture<D, Shape, Real>& p2g_fixture(int tile, int cells) {
  using F = P2GFixture<D, Shape, Real>;
  return cached_fixture<F>(std::pair{tile, cells}, [tile, cells] {
    auto fx = std::make_unique<F>();
    make_block<D, Real>(fx->S, p2g_block<D>(std::is_same_v<Shape, GimpShape>, cells));
    fx->grid.setup(p2g_cells<D>(cells), 1, false, false);
    fx->bins.template setup<Shape>(tile, fx->grid.G);
    fx->bins.sort(fx->S, fx->grid.G);
    for (std::size_t p = 0; p < fx->S.P.n; ++p) fx->total_mass += double(fx->S.P.m[p]);
    return fx;
  });
}

template <int D, class Shape, class Real>
void bm_p2g(benchmark::State& state, Strategy strategy, int tile, int threads,
            int cells = kDefaultBlockCells<D>) {
  use_threads(threads);
  auto& fx = p2g_fixture<D, Shape, Real>(tile, cells);
  const ParticleView<D, Real>& P = fx.S.P;
  const GridView<D, Real>& G = fx.grid.G;
  constexpr unsigned What = kMassMomentum | kForce;
  const P2GOptions opt;
  fx.grid.zero();
  std::size_t bad = SIZE_MAX;
  for (auto _ : state) {
    switch (strategy) {
      case Strategy::colored:
        bad = p2g_colored<D, Shape, Real, What, false, false>(P, G, opt, fx.bins);
        break;
      case Strategy::serial:
        bad = p2g_serial<D, Shape, Real, What>(P, G, opt);
        break;
      case Strategy::colored_pointwise:
        bad = p2g_colored<D, Shape, Real, What, false, false, false>(P, G, opt, fx.bins);
        break;
      case Strategy::serial_pointwise:
        bad = p2g_serial<D, Shape, Real, What, false>(P, G, opt);
        break;
      case Strategy::atomic:
        bad = p2g_atomic<D, Shape, Real>(P, G);
        break;
      case Strategy::colored_row_units:
        bad = p2g_colored<D, Shape, Real, What, false, false, true, RowUnits<D, Shape, Real>>(
            P, G, opt, fx.bins);
        break;
    }
    keep(bad);
    keep(G.m);
    benchmark::ClobberMemory();
  }
  if (bad != SIZE_MAX) {
    state.SkipWithError("a stencil left the grid");
    return;
  }
  double grid_mass = 0;
  for (std::size_t i = 0; i < G.nodes; ++i) grid_mass += double(G.m[i]);
  const double expect = double(state.iterations()) * fx.total_mass;
  const double tol = sizeof(Real) == 8 ? 1e-9 : 1e-3;
  if (std::abs(grid_mass - expect) > tol * expect) {
    state.SkipWithError("grid mass differs from iterations x particle mass");
    return;
  }
  const double n = double(P.n);
  constexpr int nodes = Stencil<D, Shape, Real>::count;
  set_ns_per_particle(state, n);
  set_rate(state, "Gnode_updates_per_s", n * nodes);
  set_rate(state, "Gflops", n * nodes * kP2GFlopsPerNode<D>);
  set_rate(state, "particle_GBps", n * double(kP2GParticleBytes<D, Shape, Real>));
  state.counters["tile"] = fx.bins.tiles.T;  // TileLayout rounds up to a power of two >= 4
  state.counters["threads"] = threads;
}

template <int D, class Shape, class Real>
void register_case() {
  const std::string base = "p2g/dim:" + std::to_string(D) + "/shape:" + Shape::name +
                           "/real:" + real_name<Real>() + "/strategy:";
  auto add = [&](Strategy s, int tile, int threads) {
    std::string name = base + strategy_name(s);
    if (s == Strategy::colored || s == Strategy::colored_pointwise ||
        s == Strategy::colored_row_units)
      name += "/tile:" + std::to_string(tile);
    name += "/threads:" + std::to_string(threads);
    auto* b = benchmark::RegisterBenchmark(name.c_str(), [s, tile, threads](benchmark::State& st) {
      bm_p2g<D, Shape, Real>(st, s, tile, threads);
    });
    configure(b->UseRealTime()->Unit(benchmark::kMillisecond), 0.1);
  };
  const int T = kDefaultTile<D>;
  add(Strategy::serial, T, 1);
  add(Strategy::atomic, T, 1);
  add(Strategy::atomic, T, 2);
  add(Strategy::colored, T, 1);
  add(Strategy::colored, T, 2);
  add(Strategy::serial_pointwise, T, 1);
  add(Strategy::colored_pointwise, T, 1);
  add(Strategy::colored_pointwise, T, 2);
  if constexpr (!std::is_same_v<ScatterUnits<D, Shape, Real>, RowUnits<D, Shape, Real>>) {
    add(Strategy::colored_row_units, T, 1);
    add(Strategy::colored_row_units, T, 2);
  }
}

// Tile edge sweep of the colored scatter (the solver's default is 8 in 2D, 4 in
// 3D). TileLayout rounds the edge up to a power of two of at least 4 (keys by
// shifts), so 3 is no longer a distinct layout; 32 takes its place.
template <int D, class Shape, class Real>
void register_tiles() {
  for (int tile : {4, 8, 16, 32})
    for (int threads : {1, 2}) {
      const std::string name = "p2g_tile/dim:" + std::to_string(D) + "/shape:" + Shape::name +
                               "/real:" + real_name<Real>() +
                               "/strategy:colored/tile:" + std::to_string(tile) +
                               "/threads:" + std::to_string(threads);
      auto* b = benchmark::RegisterBenchmark(name.c_str(), [tile, threads](benchmark::State& st) {
        bm_p2g<D, Shape, Real>(st, Strategy::colored, tile, threads);
      });
      configure(b->UseRealTime()->Unit(benchmark::kMillisecond), 0.1);
    }
}

// The solver's colored scatter on blocks from a few thousand particles,
// whose arrays and grid sit in the core's L2 (1 MiB here), to the 250 000
// of p2g/ (L3). One thread. Why: the roofline bound (tools/roofline)
// charges P2G its bytes at the triad's rate; if the kernel takes the same
// time per particle when nothing comes from memory, its time is its own
// instructions, and no memory-side change can bring it to that bound
// (docs/performance.md "P2G's time without memory").
template <int D, class Shape, class Real>
void register_sizes(std::initializer_list<int> edges) {
  for (int cells : edges) {
    const std::string name = "p2g_size/dim:" + std::to_string(D) + "/shape:" + Shape::name +
                             "/real:" + real_name<Real>() + "/cells:" + std::to_string(cells) +
                             "/threads:1";
    auto* b = benchmark::RegisterBenchmark(name.c_str(), [cells](benchmark::State& st) {
      bm_p2g<D, Shape, Real>(st, Strategy::colored, kDefaultTile<D>, 1, cells);
    });
    configure(b->UseRealTime()->Unit(benchmark::kMicrosecond), 0.1);
  }
}

template <int D, class Real>
void register_shapes() {
  register_case<D, LinearShape, Real>();
  register_case<D, GimpShape, Real>();
  register_case<D, BSpline2Shape, Real>();
  register_case<D, BSpline3Shape, Real>();
}

}  // namespace

void register_p2g() {
  register_shapes<2, double>();
  register_shapes<2, float>();
  register_shapes<3, double>();
  register_shapes<3, float>();
  register_tiles<2, LinearShape, double>();
  register_tiles<2, GimpShape, double>();
  register_tiles<2, BSpline2Shape, double>();
  register_tiles<2, BSpline3Shape, double>();
  register_tiles<3, LinearShape, double>();
  register_tiles<3, GimpShape, double>();
  register_tiles<3, BSpline2Shape, double>();
  register_tiles<3, BSpline3Shape, double>();
  register_sizes<2, LinearShape, double>({24, 48, 96, 250});
  register_sizes<2, GimpShape, double>({24, 48, 96, 250});
  register_sizes<2, GimpShape, float>({24, 48, 96, 250});
  register_sizes<3, GimpShape, double>({8, 12, 20, 32});
}

}  // namespace mmpm::bench
