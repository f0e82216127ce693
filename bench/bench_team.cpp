// The step's parallel regions on the persistent team (kernels/team.hpp)
// against the same regions as OpenMP `parallel` regions, on two threads, in
// one run.
//
// One benchmark per scene steps one Simulation on 2 threads and alternates
// blocks of kSteps steps with the team (A) and with OpenMP regions (B), in
// the order A,B / B,A / ... (so a steady drift of the host's load favours
// neither); one untimed step opens every block. Counters, per stage s and
// for the whole step (s = step):
//   speedup_<s>      median over the pairs of t(OpenMP) / t(team): > 1, the
//                    team is faster
//   speedup_<s>_min  min over the OpenMP blocks / min over the team blocks
//   nsA_<s>, nsB_<s> the minima, ns per particle per step (A team, B OpenMP)
// The 10^4-particle scenes are where the regions' fixed cost shows: a step
// there is ~100 us on two threads, with ~34 regions.
#include <chrono>
#include <thread>
#include <vector>

#include "bench/bench_common.hpp"
#include "kernels/team.hpp"
#include "solver/simulation.hpp"

namespace mmpm::bench {
namespace {

constexpr int kSteps = 8;  // timed steps per block

BlockTimes run_block(Simulation& sim, bool openmp) {
  use_openmp_regions(openmp);
  // The other side's idle threads stop spinning first (libgomp's after
  // ~2.5 ms, the team's after ~0.6 ms): a spinning thread of one runtime
  // holds the core the other's member needs. The untimed step of
  // time_block then wakes this side's threads.
  std::this_thread::sleep_for(std::chrono::milliseconds(5));
  return time_block(sim, kSteps);
}

void bm_team(benchmark::State& state, const std::string& scene) {
  try {
    Simulation& sim = step_scene_simulation(scene);
    use_threads(2);
    for (bool openmp : {false, true, false}) {  // first sort, first touch, warm caches
      use_openmp_regions(openmp);
      sim.step();
    }
    std::vector<BlockTimes> team, openmp;
    alternate_blocks(
        state, [&] { return run_block(sim, false); }, [&] { return run_block(sim, true); }, team,
        openmp);
    use_openmp_regions(false);
    const double per = 1e9 / (kSteps * double(sim.particle_count()));
    set_paired_counters(state, openmp, team, per, "nsB_", "nsA_", "speedup_");
    state.counters["pairs"] = double(team.size());
    state.counters["particles"] = double(sim.particle_count());
    state.counters["steps_per_block"] = kSteps;
  } catch (const std::exception& e) {
    use_openmp_regions(false);
    state.SkipWithError(e.what());
  }
}

}  // namespace

void register_team() {
  for (const char* scene :
       {"2d_linear_10k", "2d_gimp_interface_10k", "2d_linear_1mat", "2d_gimp_interface"}) {
    const std::string name = std::string("team_ab/scene:") + scene + "/threads:2";
    auto* b = benchmark::RegisterBenchmark(name.c_str(),
                                           [scene](benchmark::State& st) { bm_team(st, scene); });
    configure(b->UseManualTime()->Unit(benchmark::kMillisecond), 3.0);
  }
}

}  // namespace mmpm::bench
