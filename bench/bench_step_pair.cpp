// The 2-thread speed-up of every stage, measured in pairs of adjacent blocks.
//
// Why: step/... runs a scene on 1 thread and on 2 threads as two benchmarks,
// seconds or (in bench/run's passes) minutes apart, and this machine is
// shared: a stage of a few percent of the step, timed over a short interval,
// moves by 20-45 % between such runs, more than the speed-up it is meant to
// show. Here one benchmark alternates blocks of kSteps steps on 1 and on 2
// threads of the same Simulation, in the order 1,2 / 2,1 / 1,2 ... (so a
// steady drift of the host's load favours neither), and each pair of
// adjacent blocks gives one ratio per stage. The counters are the median of
// those paired ratios, with the ratio of the per-thread-count minima next to
// it. One untimed step follows each switch: the solver re-divides the nodes
// among the threads then (Stepper::update_node_ownership), which a run on a
// fixed team never does.
//
// Counters, per stage s (sort, p2g, mm, grid, g2p, constitutive) and for the
// whole step (s = step):
//   speedup_<s>      median over the pairs of t(1 thread) / t(2 threads)
//   speedup_<s>_min  min over blocks of t(1 thread) / min of t(2 threads)
//   ns1_<s>, ns2_<s> the minima, ns per particle per step
// and pairs (the number of pairs). The iteration time (manual) is the two
// blocks of a pair.
#include <algorithm>
#include <chrono>
#include <vector>

#include "bench/bench_common.hpp"
#include "solver/simulation.hpp"

namespace mmpm::bench {
namespace {

constexpr int kSteps = 4;  // timed steps per block

BlockTimes run_block(Simulation& sim, int threads) {
  use_threads(threads);
  return time_block(sim, kSteps);  // its untimed step: the node split for the new team
}

void bm_step_pair(benchmark::State& state, const std::string& scene) {
  try {
    Simulation& sim = step_scene_simulation(scene);
    for (int threads : {1, 2})
      for (int k = 0; k < 2; ++k) {  // first sort, first touch, warm caches
        use_threads(threads);
        sim.step();
      }
    std::vector<BlockTimes> one, two;
    alternate_blocks(
        state, [&] { return run_block(sim, 1); }, [&] { return run_block(sim, 2); }, one, two);
    const double per = 1e9 / (kSteps * double(sim.particle_count()));
    set_paired_counters(state, one, two, per, "ns1_", "ns2_", "speedup_");
    state.counters["pairs"] = double(one.size());
    state.counters["particles"] = double(sim.particle_count());
    state.counters["steps_per_block"] = kSteps;
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
  }
}

}  // namespace

BlockTimes time_block(Simulation& sim, int steps) {
  using Clock = std::chrono::steady_clock;
  sim.step();  // untimed
  const auto s0 = sim.stage_seconds();
  const auto t0 = Clock::now();
  for (int k = 0; k < steps; ++k) sim.step();
  const double wall = std::chrono::duration<double>(Clock::now() - t0).count();
  const auto s1 = sim.stage_seconds();
  BlockTimes t{};
  static_assert(std::tuple_size_v<BlockTimes> == kStageCount + 1);
  for (int s = 0; s < kStageCount; ++s) t[std::size_t(s)] = s1[s] - s0[s];
  t[kStageCount] = wall;
  return t;
}

void set_paired_counters(benchmark::State& state, const std::vector<BlockTimes>& x,
                         const std::vector<BlockTimes>& y, double per, const std::string& nx,
                         const std::string& ny, const std::string& r) {
  for (int s = 0; s <= kStageCount; ++s) {
    if (s == kStageOutput) continue;  // a bench step writes no output
    std::vector<double> ratios;
    double min_x = 1e30, min_y = 1e30;
    for (std::size_t i = 0; i < x.size() && i < y.size(); ++i) {
      const double a = x[i][std::size_t(s)], b = y[i][std::size_t(s)];
      min_x = std::min(min_x, a);
      min_y = std::min(min_y, b);
      if (b > 0) ratios.push_back(a / b);
    }
    const std::string n = s == kStageCount ? "step" : bench_stage_name(s);
    state.counters[nx + n] = min_x * per;
    state.counters[ny + n] = min_y * per;
    state.counters[r + n] = median(ratios);
    state.counters[r + n + "_min"] = min_y > 0 ? min_x / min_y : 0.0;
  }
}

void register_step_pair() {
  for (const char* scene : {"2d_linear_1mat", "2d_gimp_interface", "2d_gimp_inclusions",
                            "3d_gimp_1mat", "2d_linear_10k", "2d_gimp_interface_10k"}) {
    const std::string name = std::string("step_pair/scene:") + scene;
    auto* b = benchmark::RegisterBenchmark(
        name.c_str(), [scene](benchmark::State& st) { bm_step_pair(st, scene); });
    configure(b->UseManualTime()->Unit(benchmark::kMillisecond), 3.0);
  }
}

}  // namespace mmpm::bench
