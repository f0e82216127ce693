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

using Clock = std::chrono::steady_clock;
constexpr int kSteps = 4;               // timed steps per block
constexpr int kStepPart = kStageCount;  // after the stages: the whole step (wall clock)
constexpr int kParts = kStageCount + 1;

using Times = std::array<double, kParts>;  // seconds of one block, per stage and the step

Times run_block(Simulation& sim, int threads) {
  use_threads(threads);
  sim.step();  // untimed: the node split for the new team
  const auto s0 = sim.stage_seconds();
  const auto t0 = Clock::now();
  for (int k = 0; k < kSteps; ++k) sim.step();
  const double wall = std::chrono::duration<double>(Clock::now() - t0).count();
  const auto s1 = sim.stage_seconds();
  Times t{};
  for (int s = 0; s < kStageCount; ++s) t[std::size_t(s)] = s1[s] - s0[s];
  t[kStepPart] = wall;
  return t;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

void bm_step_pair(benchmark::State& state, const std::string& scene) {
  try {
    Simulation& sim = step_scene_simulation(scene);
    for (int threads : {1, 2})
      for (int k = 0; k < 2; ++k) {  // first sort, first touch, warm caches
        use_threads(threads);
        sim.step();
      }
    std::vector<Times> one, two;
    for (auto _ : state) {
      const bool one_first = one.size() % 2 == 0;
      const Times a = run_block(sim, one_first ? 1 : 2);
      const Times b = run_block(sim, one_first ? 2 : 1);
      one.push_back(one_first ? a : b);
      two.push_back(one_first ? b : a);
      benchmark::ClobberMemory();
      state.SetIterationTime(a[kStepPart] + b[kStepPart]);
    }
    const double per = 1e9 / (kSteps * double(sim.particle_count()));
    for (int s = 0; s < kParts; ++s) {
      if (s == kStageOutput) continue;  // a bench step writes no output
      std::vector<double> ratios;
      double min1 = 1e30, min2 = 1e30;
      for (std::size_t i = 0; i < one.size(); ++i) {
        const double t1 = one[i][std::size_t(s)], t2 = two[i][std::size_t(s)];
        min1 = std::min(min1, t1);
        min2 = std::min(min2, t2);
        if (t2 > 0) ratios.push_back(t1 / t2);
      }
      const std::string n = s == kStepPart ? "step" : bench_stage_name(s);
      state.counters["ns1_" + n] = min1 * per;
      state.counters["ns2_" + n] = min2 * per;
      state.counters["speedup_" + n] = median(ratios);
      state.counters["speedup_" + n + "_min"] = min2 > 0 ? min1 / min2 : 0.0;
    }
    state.counters["pairs"] = double(one.size());
    state.counters["particles"] = double(sim.particle_count());
    state.counters["steps_per_block"] = kSteps;
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
  }
}

}  // namespace

void register_step_pair() {
  for (const char* scene :
       {"2d_linear_1mat", "2d_gimp_interface", "2d_gimp_inclusions", "3d_gimp_1mat"}) {
    const std::string name = std::string("step_pair/scene:") + scene;
    auto* b = benchmark::RegisterBenchmark(
        name.c_str(), [scene](benchmark::State& st) { bm_step_pair(st, scene); });
    configure(b->UseManualTime()->Unit(benchmark::kMillisecond), 3.0);
  }
}

}  // namespace mmpm::bench
