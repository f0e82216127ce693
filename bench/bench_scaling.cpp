// Problem-size scaling of a whole step (issue: 10^4 to 10^7 particles, 2D):
// the 2D linear one-material scene of bench_step.cpp (a square elastic
// block, 2 x 2 particles per cell, moving, fixed on one face, MUSL) with
// N particles, 1 and 2 threads. Counters: ns/particle/step and the stage
// split, and the bytes the step's arrays occupy, so the table can show
// where the grid and the particle arrays leave the L2 (1 MiB per core) and
// the L3 (32 MiB) of this machine:
//   grid_MiB      nodes x 9 arrays (m, p, f, vel, dvel: 1 + 4 x 2) x 8 bytes
//   particle_MiB  particles x 16 arrays (x, v, m, V, stress 4, x0, x_next,
//                 key and id) x 8 bytes; L stays in the fused tail's
//                 per-tile block since 2026-11-26 (20 arrays before)
// Only one scene is alive at a time (10^7 particles take ~1.7 GB).
#include <cmath>
#include <map>
#include <memory>
#include <string>

#include "bench/bench_common.hpp"
#include "scene/parse.hpp"
#include "solver/simulation.hpp"

namespace mmpm::bench {
namespace {

// Cells per side of the block for n particles (2 x 2 per cell).
int block_cells(double n) {
  return int(std::lround(std::sqrt(n / 4.0)));
}

}  // namespace

std::string linear_block_scene(int cells) {
  const int grid = cells + 4;
  return R"(
[simulation]
dimension = 2
plane     = "strain"
thickness = 1.0
end_time  = 1.0
cfl       = 0.4

[grid]
origin = [0.0, 0.0]
cell   = [1.0, 1.0]
cells  = [)" +
         std::to_string(grid) + ", " + std::to_string(grid) + R"(]
shape  = "linear"

[[material]]
name    = "steel"
type    = "isotropic"
density = 7.8e-3
E       = 200000.0
nu      = 0.3

[[body]]
name     = "block"
material = "steel"
shape    = "box"
min      = [2.0, 2.0]
max      = [)" +
         std::to_string(cells + 2) + ".0, " + std::to_string(cells + 2) + R"(.0]
particles_per_cell = 2
velocity = [0.5, 0.0]

[[boundary]]
where = { x = 2.0 }
fix   = ["x"]
)";
}

namespace {

Simulation& scaling_simulation(int cells) {
  static std::unique_ptr<Simulation> sim;
  static int sim_cells = -1;
  if (!sim || sim_cells != cells) {
    sim.reset();
    if (fixture_release()) fixture_release()();
    sim = make_simulation(parse_scene_text(linear_block_scene(cells), "scaling.toml"));
    sim_cells = cells;
    for (int k = 0; k < 2; ++k) sim->step();  // first sort, first touch
  }
  return *sim;
}

void bm_scaling(benchmark::State& state, double target, int threads) {
  use_threads(threads);
  try {
    const int cells = block_cells(target);
    Simulation& sim = scaling_simulation(cells);
    sim.step();  // warm the caches with this thread count
    const auto s0 = sim.stage_seconds();
    for (auto _ : state) {
      sim.step();
      benchmark::ClobberMemory();
    }
    const auto s1 = sim.stage_seconds();
    const double n = double(sim.particle_count());
    const double steps = double(state.iterations());
    set_ns_per_particle(state, n);
    set_stage_counters(state, s0, s1, steps, n);
    const double nodes = double(cells + 5) * double(cells + 5);
    state.counters["grid_MiB"] = nodes * 9 * 8 / 1048576.0;
    state.counters["particle_MiB"] = n * 16 * 8 / 1048576.0;
    state.counters["threads"] = threads;
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
  }
}

}  // namespace

void register_scaling() {
  for (double n : {1e4, 3e4, 1e5, 3e5, 1e6, 3e6, 1e7})
    for (int threads : {1, 2}) {
      char label[32];
      std::snprintf(label, sizeof label, "%.0e", n);
      const std::string name =
          std::string("scaling/particles:") + label + "/threads:" + std::to_string(threads);
      auto* b = benchmark::RegisterBenchmark(
          name.c_str(), [n, threads](benchmark::State& st) { bm_scaling(st, n, threads); });
      // Small sizes need many steps for a stable time; 10^7 needs a few.
      configure(b->UseRealTime()->Unit(benchmark::kMillisecond), n >= 3e6 ? 1.5 : 0.5);
    }
}

}  // namespace mmpm::bench
