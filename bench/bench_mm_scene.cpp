// The multimaterial pass alone on the grid of the whole-step two-layer scene
// (bench_step.cpp, 2d_gimp_interface), to set against the step: after a real
// step, the scene's own grid is restored before each iteration (untimed) and
// the stage's work is timed as the step does it: find the nodes, pass A, and
// pass B once per transfer (twice under MUSL, the default scheme).
#include <chrono>

#include "bench/bench_common.hpp"
#include "kernels/multimaterial.hpp"
#include "solver/stepper.hpp"

namespace mmpm {
// Compiled once in the library (solver/inst/stepper_2d_gimp_double.cpp).
extern template class Stepper<2, GimpShape, double>;
}  // namespace mmpm

namespace mmpm::bench {
namespace {

using Clock = std::chrono::steady_clock;

void bm_mm_scene(benchmark::State& state, int threads) {
  use_threads(threads);
  try {
    Simulation& sim = two_layer_interface_simulation();
    auto* stepper = dynamic_cast<Stepper<2, GimpShape, double>*>(&sim);
    if (!stepper) {
      state.SkipWithError("the two-layer scene is not a 2D gimp double Stepper");
      return;
    }
    sim.step();  // the grid now holds a real step's fields
    GridView<2, double> G = stepper->grid();
    const ParticleView<2, double>& P = stepper->particles();
    const std::size_t total = G.nodes * std::size_t(G.fields);
    std::vector<std::vector<double>> saved;
    for (int d = 0; d < 2; ++d) saved.emplace_back(G.p[d], G.p[d] + total);
    for (int d = 0; d < 2; ++d) saved.emplace_back(G.fi[d], G.fi[d] + total);

    // The scene's interaction: interface, Dn perfect, Dt 5, specified normal
    // [1, 0] from layer_a (field 0), displacement separation, force limit.
    PairParams<double> pp;
    pp.law = Law::interface;
    pp.Dn = PairParams<double>::kPerfect;
    pp.Dt = 5.0;
    pp.normal_method = NormalMethod::specified;
    pp.normal_vector = {1.0, 0.0, 0.0};
    pp.first_field = 0;
    pp.separation = Separation::displacement;
    pp.force_limit = true;
    const int pair[4] = {-1, 0, 0, -1};
    MMConfig<2, double> cfg;
    cfg.fields = 2;
    cfg.pair = pair;
    cfg.params = &pp;
    cfg.dt = sim.dt();
    cfg.thickness = 1.0;
    double min_mass = 1e300;
    for (std::size_t p = 0; p < P.n; ++p) min_mass = std::min(min_mass, P.m[p]);
    cfg.mass_threshold = 1e-9 * min_mass * 1000;  // as Stepper + MultimaterialStage
    if (const char* why = validate_multimaterial(G, cfg)) {
      state.SkipWithError(why);
      return;
    }
    // Pass B after each transfer: twice under MUSL (the default scheme), once otherwise.
    const int passes_b = two_layer_interface_scheme() == Scheme::MUSL ? 2 : 1;

    std::vector<std::uint32_t> list;
    std::vector<unsigned char> flags;
    std::vector<SavedGeometry<2, double>> geometry;  // as the solver's stage: pass B reuses it
    MMStats stats;
    double t_find = 0, t_a = 0, t_b = 0;
    for (auto _ : state) {
      for (int d = 0; d < 2; ++d) {
        restore_owned(G.p[d], saved[std::size_t(d)].data(), G.nodes, G.fields);
        restore_owned(G.fi[d], saved[std::size_t(2 + d)].data(), G.nodes, G.fields);
      }
      const auto t0 = Clock::now();
      find_multimaterial_nodes(G, cfg.mass_threshold, list);
      const auto ta = Clock::now();
      stats.reset(cfg.fields);
      multimaterial_pass_a(G, list, cfg, stats, flags, {}, &geometry);
      const auto tb = Clock::now();
      for (int k = 0; k < passes_b; ++k)
        multimaterial_pass_b(G, list, cfg, flags, stats, {}, &geometry);
      const auto t1 = Clock::now();
      t_find += std::chrono::duration<double>(ta - t0).count();
      t_a += std::chrono::duration<double>(tb - ta).count();
      t_b += std::chrono::duration<double>(t1 - tb).count();
      keep(stats.interface_energy);
      benchmark::ClobberMemory();
      state.SetIterationTime(std::chrono::duration<double>(t1 - t0).count());
    }
    for (int d = 0; d < 2; ++d)  // leave the simulation's grid as the step left it
      std::memcpy(G.p[d], saved[std::size_t(d)].data(), total * sizeof(double));
    if (list.empty()) {
      state.SkipWithError("no multimaterial nodes in the two-layer scene");
      return;
    }
    set_ns_per_particle(state, double(P.n));  // stage time per scene particle
    set_ns_per_item(state, "ns_per_mm_node", double(list.size()));
    state.counters["mm_nodes"] = double(list.size());
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
  for (int threads : {1, 2}) {
    const std::string name = "mm_scene/scene:2d_gimp_interface/threads:" + std::to_string(threads);
    auto* b = benchmark::RegisterBenchmark(
        name.c_str(), [threads](benchmark::State& st) { bm_mm_scene(st, threads); });
    configure(b->UseManualTime()->Unit(benchmark::kMicrosecond), 0.1);
  }
}

}  // namespace mmpm::bench
