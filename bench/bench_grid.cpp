// The grid stage's node loops on their own (ns/node, GB/s), 1 and 2 threads,
// with a triad over the same nodes as the machine's limit in the same run.
//
// Kernels (kernels/grid_update.hpp), as the single-material MUSL step runs
// them: `update` = grid_update with the velocities (reads m, p, f; writes p,
// vel, dvel), `velocities` = grid_momentum_velocities (reads m, p; writes
// vel); `triad` = a[i] = b[i] + s c[i] over three node arrays. Bytes count
// every write twice (the store first reads its line), as the roofline's
// triad does: update (1 + 2D + 6D) R, velocities (1 + 3D) R, triad 4 R per
// node.
//
// Cache state (`cache:`):
//   warm    the loop runs again and again: each thread's nodes stay in its
//           own core's caches (the best a node loop can do);
//   evicted before each timed call every thread sweeps a private 64 MiB
//           buffer, so the grid comes from memory, as after a particle pass
//           that streamed more than the L3 (a 250 000-particle block).
// The in-step grid stage (bench_step.cpp's stage_grid counter) sits between
// the two; docs/performance.md compares them. Each thread owns an even
// share of the nodes (NodeOwnership without a split) and touched it first.
//
// Grids: 2D 255 x 255 nodes (the 250 000-particle step's grid), 3D 41^3
// (68 921 nodes), one field.
#include <atomic>
#include <chrono>
#include <cmath>

#include "bench/bench_common.hpp"
#include "kernels/grid_update.hpp"

namespace mmpm::bench {
namespace {

using Clock = std::chrono::steady_clock;

enum class GridKernel { update, velocities, triad };

const char* kernel_name(GridKernel k) {
  switch (k) {
    case GridKernel::update:
      return "update";
    case GridKernel::velocities:
      return "velocities";
    case GridKernel::triad:
      return "triad";
  }
  return "?";
}

template <int D>
double bytes_per_node(GridKernel k, double R) {
  switch (k) {
    case GridKernel::update:
      return (1 + 2 * D + 6 * D) * R;
    case GridKernel::velocities:
      return (1 + 3 * D) * R;
    case GridKernel::triad:
      return 4 * R;
  }
  return 0;
}

template <int D, class Real>
struct GridFixture {
  GridSet<D, Real> grid;
  NodeOwnership even;                   // 2 threads: halves cut on a line
  std::vector<unsigned char> evict[2];  // one sweep buffer per thread
};

constexpr std::size_t kEvictBytes = std::size_t(64) << 20;

template <int D, class Real>
GridFixture<D, Real>& grid_fixture() {
  using F = GridFixture<D, Real>;
  return cached_fixture<F>(D, [] {
    auto fx = std::make_unique<F>();
    const std::array<int, 3> cells =
        D == 2 ? std::array<int, 3>{254, 254, 1} : std::array<int, 3>{40, 40, 40};
    fx->grid.setup(cells, 1, false, true);
    // First touch by the owner (an even split, as the kernels use below),
    // the cut on a multiple of kNodeCutAlign nodes as the Stepper's
    // node_ownership makes it (a cut mid-line slowed the 3D update on 2
    // threads from 0.79 to 1.19 ns/node).
    const GridView<D, Real>& G = fx->grid.G;
    const GridVelocity<D, Real>& V = fx->grid.V;
    fx->even.split = {0, G.nodes / 2 / kNodeCutAlign * kNodeCutAlign, G.nodes};
    use_threads(2);
    team_run(true, [&] {
      for_own_nodes(fx->even, G.nodes, 1, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) {
          // Every node heavy: m between 1 and 4, so the loop does its full work.
          G.m[i] = Real(1) + Real(i % 7) * Real(0.5);
          for (int d = 0; d < D; ++d) {
            G.p[d][i] = Real(0.1) * Real(d + 1);
            G.f[d][i] = Real(0.01);
            V.vel[d][i] = V.dvel[d][i] = Real(0);
          }
        }
      });
    });
    for (auto& e : fx->evict) e.assign(kEvictBytes, 1);
    return fx;
  });
}

// Every thread reads its own 64 MiB, pushing the grid out of the caches it
// shares with the other thread too. Read only: a sweep that wrote would
// leave the caches full of dirty lines, and each line the kernel then
// loads would first write one back (not the state a step leaves).
template <int D, class Real>
void evict_caches(GridFixture<D, Real>& fx) {
  std::atomic<unsigned> sum{0};
  team_run(true, [&] {
    const std::vector<unsigned char>& buf = fx.evict[std::size_t(team_rank()) % 2];
    unsigned mine = 0;
    for (std::size_t i = 0; i < buf.size(); i += 64) mine += buf[i];
    sum += mine;
  });
  keep(sum.load());
}

template <int D, class Real>
void bm_grid(benchmark::State& state, GridKernel kernel, bool evicted, int threads) {
  auto& fx = grid_fixture<D, Real>();  // (its first touch sets 2 threads)
  use_threads(threads);
  const GridView<D, Real>& G = fx.grid.G;
  const GridVelocity<D, Real>& V = fx.grid.V;
  const NodeOwnership& even = fx.even;
  GridUpdateParams q;
  q.dt = 1e-6;  // p drifts by dt f per call: stays finite over any run
  q.mass_threshold = 1e-12;
  q.velocities = true;
  const Real thr = Real(q.mass_threshold);
  const Real s = Real(1.0000001);
  for (auto _ : state) {
    if (evicted) evict_caches(fx);
    const auto t0 = Clock::now();
    switch (kernel) {
      case GridKernel::update:
        keep(grid_update(G, V, q, even));
        break;
      case GridKernel::velocities:
        grid_momentum_velocities(G, V, thr, even);
        break;
      case GridKernel::triad: {
        // The node loops' parallel region and split, over three of their arrays.
        Real* a = V.vel[0];
        const Real* b = G.p[0];
        const Real* c = G.f[0];
        team_run(G.nodes >= kParallelMin, [&] {
          for_own_nodes(even, G.nodes, 1, [&](std::size_t lo, std::size_t hi) {
#pragma omp simd
            for (std::size_t i = lo; i < hi; ++i) a[i] = b[i] + s * c[i];
          });
        });
        break;
      }
    }
    benchmark::ClobberMemory();
    const double t = std::chrono::duration<double>(Clock::now() - t0).count();
    state.SetIterationTime(t);
  }
  const double nodes = double(G.nodes);
  set_ns_per_item(state, "ns_per_node", nodes);
  set_rate(state, "GBps", nodes * bytes_per_node<D>(kernel, double(sizeof(Real))));
  state.counters["nodes"] = nodes;
  state.counters["threads"] = threads;
  if (!std::isfinite(double(V.vel[0][G.nodes / 2])) || !std::isfinite(double(G.p[0][0])))
    state.SkipWithError("non-finite grid values");
}

template <int D, class Real>
void register_case() {
  for (GridKernel k : {GridKernel::update, GridKernel::velocities, GridKernel::triad})
    for (bool evicted : {false, true})
      for (int threads : {1, 2}) {
        const std::string name = "grid/dim:" + std::to_string(D) + "/real:" + real_name<Real>() +
                                 "/kernel:" + kernel_name(k) +
                                 "/cache:" + (evicted ? "evicted" : "warm") +
                                 "/threads:" + std::to_string(threads);
        auto* b =
            benchmark::RegisterBenchmark(name.c_str(), [k, evicted, threads](benchmark::State& st) {
              bm_grid<D, Real>(st, k, evicted, threads);
            });
        configure(b->UseManualTime()->Unit(benchmark::kMicrosecond), 0.03);
      }
}

}  // namespace

void register_grid() {
  register_case<2, double>();
  register_case<2, float>();
  register_case<3, double>();
}

}  // namespace mmpm::bench
