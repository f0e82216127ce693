// The multimaterial stage alone on the grid of a whole-step scene
// (bench_step.cpp: 2d_gimp_interface, 2d_gimp_inclusions), to set against
// the step. After three real steps the scene's own grid is restored before
// each iteration (untimed), and the solver's own MultimaterialStage (the
// scene's laws, normals, thresholds and node ownership) does what a step
// does: find the nodes, pass A, and pass B once per transfer (twice under
// MUSL, the default scheme). The USL and USF variants of the interface scene
// share one pass B per step, so their difference is USF's carried record of
// held pairs (MultimaterialStage::carry_held_pairs, docs/contact_validation.md §13).
#include <chrono>
#include <cstring>

#include "bench/bench_common.hpp"
#include "solver/stepper.hpp"

namespace mmpm {
// Compiled once in the library (solver/inst/stepper_2d_gimp_double.cpp).
extern template class Stepper<2, GimpShape, double>;
}  // namespace mmpm

namespace mmpm::bench {
namespace {

using Clock = std::chrono::steady_clock;

// scheme: "" runs the scene as it is (shared with bench_step.cpp), else a new
// Simulation of the scene under that scheme.
void bm_mm_scene(benchmark::State& state, const std::string& scene, int threads,
                 const std::string& scheme) {
  use_threads(threads);
  try {
    std::unique_ptr<Simulation> own_sim;
    if (!scheme.empty())
      own_sim = new_step_scene_simulation(scene, {"simulation.scheme=\"" + scheme + "\""});
    Simulation& sim = own_sim ? *own_sim : step_scene_simulation(scene);
    auto* stepper = dynamic_cast<Stepper<2, GimpShape, double>*>(&sim);
    if (!stepper) {
      state.SkipWithError("the scene is not a 2D gimp double Stepper");
      return;
    }
    // Real steps on this thread count: the grid holds a step's fields and
    // the node ownership is the one the step uses.
    for (int k = 0; k < 3; ++k) sim.step();
    GridView<2, double> G = stepper->grid();
    MultimaterialStage<2, double>& mm = stepper->multimaterial();
    const NodeOwnership& own = stepper->ownership();
    const MixedTiles<2>& mixed = stepper->mixed_tiles();
    const std::size_t total = G.nodes * std::size_t(G.fields);
    std::vector<std::vector<double>> saved;
    for (int d = 0; d < 2; ++d) saved.emplace_back(G.p[d], G.p[d] + total);
    for (int d = 0; d < 2; ++d) saved.emplace_back(G.fi[d], G.fi[d] + total);
    // Pass B after each transfer: twice under MUSL (the default scheme), once otherwise.
    const bool musl = scheme.empty() ? step_scene_scheme(scene) == Scheme::MUSL : scheme == "MUSL";
    const int passes_b = musl ? 2 : 1;

    double t_find = 0, t_a = 0, t_b = 0;
    for (auto _ : state) {
      for (int d = 0; d < 2; ++d) {
        restore_owned(G.p[d], saved[std::size_t(d)].data(), G.nodes, G.fields);
        restore_owned(G.fi[d], saved[std::size_t(2 + d)].data(), G.nodes, G.fields);
      }
      const auto t0 = Clock::now();
      mm.find_nodes(G, own, &mixed);
      const auto ta = Clock::now();
      mm.pass_a(G, sim.dt(), sim.dt(), own);
      const auto tb = Clock::now();
      for (int k = 0; k < passes_b; ++k)
        mm.pass_b(G, own, k == 0 ? PassB::after_update : PassB::strain);
      const auto t1 = Clock::now();
      t_find += std::chrono::duration<double>(ta - t0).count();
      t_a += std::chrono::duration<double>(tb - ta).count();
      t_b += std::chrono::duration<double>(t1 - tb).count();
      keep(mm.interface_energy());
      benchmark::ClobberMemory();
      state.SetIterationTime(std::chrono::duration<double>(t1 - t0).count());
    }
    // Leave the simulation's grid as the step left it.
    for (int d = 0; d < 2; ++d) {
      std::memcpy(G.p[d], saved[std::size_t(d)].data(), total * sizeof(double));
      std::memcpy(G.fi[d], saved[std::size_t(2 + d)].data(), total * sizeof(double));
    }
    if (mm.nodes().empty()) {
      state.SkipWithError("no multimaterial nodes in the scene");
      return;
    }
    const double n = double(sim.particle_count());
    set_ns_per_particle(state, n);  // stage time per scene particle
    set_ns_per_item(state, "ns_per_mm_node", double(mm.nodes().size()));
    state.counters["mm_nodes"] = double(mm.nodes().size());
    state.counters["scanned_nodes"] = double(mixed.mixed_node_count());  // of grid_nodes
    state.counters["grid_nodes"] = double(G.nodes);
    const double us = 1e6 / double(state.iterations());
    state.counters["find_us"] = t_find * us;
    state.counters["passA_us"] = t_a * us;
    state.counters["passB_us"] = t_b * us;  // all pass B calls of a step
    state.counters["threads"] = threads;
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
  }
}

}  // namespace

void register_mm_scene() {
  for (const char* scene : {"2d_gimp_interface", "2d_gimp_inclusions"}) {
    for (int threads : {1, 2}) {
      const std::string name =
          std::string("mm_scene/scene:") + scene + "/threads:" + std::to_string(threads);
      auto* b = benchmark::RegisterBenchmark(name.c_str(), [scene, threads](benchmark::State& st) {
        bm_mm_scene(st, scene, threads, "");
      });
      configure(b->UseManualTime()->Unit(benchmark::kMicrosecond), 0.1);
    }
  }
  // USL against USF, one thread, adjacent in the run.
  for (const char* scheme : {"USL", "USF"}) {
    const std::string name = std::string("mm_scene/scene:2d_gimp_interface/scheme:") + scheme;
    auto* b = benchmark::RegisterBenchmark(name.c_str(), [scheme](benchmark::State& st) {
      bm_mm_scene(st, "2d_gimp_interface", 1, scheme);
    });
    configure(b->UseManualTime()->Unit(benchmark::kMicrosecond), 0.1);
  }
}

}  // namespace mmpm::bench
