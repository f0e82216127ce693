// Two settings of one scene compared in pairs of adjacent blocks.
//
// Why: the step/... rows of a scene with and without a setting run seconds
// apart, and on this shared host a whole step moves by 10-50 % between such
// runs (fast and slow spells of minutes), more than most settings change.
// Here one benchmark holds two new Simulations of the scene, A with the
// solver's defaults and B with one override, and alternates blocks of
// kSteps steps of each in the order A,B / B,A / ... on the same thread
// count. Each pair of adjacent blocks gives one ratio t(B) / t(A) per stage
// and for the whole step, so both sides see the same minutes. One untimed
// step opens each block: the other Simulation has just pushed this one's
// grid and particles out of the caches, which a run of one Simulation
// never does to its first timed step.
//
// Both Simulations are made for the benchmark, so they start at the same
// step: the shared Simulation of the step/... rows has been stepped by
// every benchmark before and made A 1-2 % slower than a new B in the
// 2026-11-26 run (its constitutive stage up to 16 %). The same_settings
// row runs B with the defaults too: what the harness itself puts between
// two equal Simulations (one made after the other).
//
// Counters, per stage s (sort, p2g, mm, grid, g2p, constitutive) and the
// whole step (s = step):
//   b_over_a_<s>      median over the pairs of t(B) / t(A): > 1, A faster
//   b_over_a_<s>_min  min over B blocks / min over A blocks
//   nsA_<s>, nsB_<s>  the minima, ns per particle per step
// and pairs. The iteration time (manual) is the two blocks of a pair.
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "bench/bench_common.hpp"
#include "solver/simulation.hpp"

namespace mmpm::bench {
namespace {

constexpr int kSteps = 4;  // timed steps per block

void bm_step_ab(benchmark::State& state, const std::string& scene, const std::string& override_b,
                int threads) {
  use_threads(threads);
  try {
    const std::unique_ptr<Simulation> sim_a = new_step_scene_simulation(scene, {});
    const std::unique_ptr<Simulation> sim_b = new_step_scene_simulation(
        scene, override_b.empty() ? std::vector<std::string>{} : std::vector{override_b});
    Simulation& a = *sim_a;
    Simulation& b = *sim_b;
    for (int k = 0; k < 3; ++k) a.step(), b.step();  // first sort, first touch
    std::vector<BlockTimes> ta, tb;
    // Each block's untimed step: the caches after the other Simulation's block.
    alternate_blocks(
        state, [&] { return time_block(a, kSteps); }, [&] { return time_block(b, kSteps); }, ta,
        tb);
    const double per = 1e9 / (kSteps * double(a.particle_count()));
    set_paired_counters(state, tb, ta, per, "nsB_", "nsA_", "b_over_a_");
    state.counters["pairs"] = double(ta.size());
    state.counters["particles"] = double(a.particle_count());
    state.counters["threads"] = threads;
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
  }
}

}  // namespace

void register_step_ab() {
  // B: one setting away from the defaults (A). fuse_step_tail: MUSL's step
  // tail as three separate passes; particle_order: particles stored in
  // plain tile order instead of color by color; skip_empty_nodes: the node
  // passes over every node of every field; tile: another tile edge;
  // prefetch_grid: the 2D transfers without the grid lines requested a line
  // ahead; prefetch_particles: the transfers without the particle columns
  // requested a batch ahead; xpic_2: XPIC(2) particle velocities (what one
  // term of the series costs, kernels/xpic.hpp); force_limit_false: the
  // two-layer interface (Dt = 5, where the limit never fires) without the
  // limit, so without MUSL's separation shift (Stepper::shifts_separation):
  // what the shift costs a step; same_settings: B as A (the control).
  const std::pair<const char*, const char*> settings[] = {
      {"fuse_step_tail_false", "simulation.fuse_step_tail=false"},
      {"particle_order_tile", "simulation.particle_order=\"tile\""},
      {"skip_empty_nodes_false", "simulation.skip_empty_nodes=false"},
      {"tile_32", "grid.tile=32"},
      {"tile_16", "grid.tile=16"},
      {"prefetch_grid_false", "simulation.prefetch_grid=false"},
      {"prefetch_particles_false", "simulation.prefetch_particles=false"},
      {"xpic_2", "simulation.xpic_order=2"},
      {"force_limit_false", "interaction[0].force_limit=false"},
      {"same_settings", ""}};
  for (const auto& [label, override_b] : settings)
    for (const char* scene : {"2d_linear_1mat", "2d_gimp_interface", "2d_gimp_inclusions",
                              "3d_gimp_1mat", "2d_linear_room", "2d_linear_1e6"})
      for (int threads : {1, 2}) {
        // The roomy grid and the 10^6 block only for the setting each is
        // there for; the tile edge the other way from the default: 32 on
        // the 254^2 grids, whose default is 16, 16 on the 10^6 block's
        // 504^2 grid, whose default is 32 (Stepper::setup_grid); not in 3D.
        // The grid prefetch (2D only) and the particle prefetch on the 10^6
        // block too, where the grid and the particles have left the caches.
        const std::string sc = scene, lb = label;
        if (lb != "same_settings") {
          if (sc == "2d_linear_room" && lb != "skip_empty_nodes_false") continue;
          const bool prefetch = lb == "prefetch_grid_false" || lb == "prefetch_particles_false";
          if (sc == "2d_linear_1e6" && lb != "tile_16" && !prefetch) continue;
          if (prefetch && (sc == "3d_gimp_1mat" || sc == "2d_linear_room")) continue;
          if (lb == "tile_16" && sc != "2d_linear_1e6") continue;
          if (lb == "xpic_2" && sc == "2d_gimp_inclusions") continue;
          if (lb == "force_limit_false" && sc != "2d_gimp_interface") continue;
          if (lb == "tile_32" && (sc == "3d_gimp_1mat" || sc == "2d_linear_room")) continue;
        }
        const std::string name = std::string("step_ab/scene:") + scene + "/b:" + label +
                                 "/threads:" + std::to_string(threads);
        const std::string b = override_b;
        auto* bm = benchmark::RegisterBenchmark(
            name.c_str(), [=](benchmark::State& st) { bm_step_ab(st, scene, b, threads); });
        configure(bm->UseManualTime()->Unit(benchmark::kMillisecond), 3.0);
      }
}

}  // namespace mmpm::bench
