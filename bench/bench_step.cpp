// Whole steps through the Simulation interface (make_simulation on a scene
// parsed from text, step() in the loop), 1 and 2 threads:
//   2d_linear_1mat    2D linear, one elastic material, 250 000 particles
//   2d_gimp_interface 2D gimp two-layer specimen: two boxes side by side,
//                     [[interaction]] interface, Dn perfect, Dt 5, specified
//                     normal [1,0], 250 000 particles (the paper's two-layer)
//   3d_gimp_1mat      3D gimp, one elastic material, 101 376 particles
//   2d_linear_room    2d_linear_1mat's block in a grid of 504 x 504 cells
//                     (step_ab only: node passes over empty nodes)
//   2d_linear_1e6     the same block with 10^6 particles, grid 504 x 504
//                     cells (step_ab only: the tile edge at large N)
//   2d_gimp_inclusions 2D gimp, 625 glass disks in a polymer block, interface
//                     (inclusions_scene); with mm_fields_share = 1 (fields
//                     always apart), and the two-layer scene with 0 (always
//                     with the first P2G)
// "Unused feature costs nothing" (same geometry, loads and supports as the
// two-layer scene):
//   2d_gimp_1mat      both boxes of one material (the baseline)
//   2d_gimp_2mat_shared  two materials, no interaction names them: they share
//                     one velocity field, so no multimaterial pass exists
// Re-sorting: 2d_linear_1mat with [simulation] sort_every = 1, 10, 100 (the
// default 0 re-bins only when a particle changes tile).
// Scenes use the solver's default scheme (MUSL); 2d_linear_1mat also runs
// with scheme = "USL" (one transfer fewer). 2d_linear_1mat and
// 2d_gimp_interface also run with fuse_constitutive = true (the constitutive
// update inside the G2P gradient pass instead of a pass of its own).
//
// Counters: ns per particle per step; the Stepper's own stage timers as ns
// per particle per step (sort, p2g, mm, grid, g2p, constitutive); the
// multimaterial stage's share of the step and its ns per multimaterial node.
// The scenes vibrate (initial velocity, fixed face) or are loaded by a
// traction, so the step does its full work; motions stay small, so the
// default re-binning rarely triggers.
#include <algorithm>
#include <iterator>
#include <map>
#include <stdexcept>

#include "bench/bench_common.hpp"
#include "scene/parse.hpp"
#include "solver/simulation.hpp"

namespace mmpm::bench {
namespace {

const char* kGimp3D = R"(
[simulation]
dimension = 3
end_time  = 1.0
cfl       = 0.4

[grid]
origin = [0.0, 0.0, 0.0]
cell   = [1.0, 1.0, 1.0]
cells  = [28, 28, 26]
shape  = "gimp"

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
min      = [2.0, 2.0, 2.0]
max      = [26.0, 26.0, 24.0]
particles_per_cell = 2
velocity = [0.5, 0.0, 0.0]

[[boundary]]
where = { x = 2.0 }
fix   = ["x"]
)";

// The two-layer family: `right_material` names the right box's material;
// `second_material` adds layer_b; `interaction` adds the interface.
std::string two_layer(bool second_material, bool interaction) {
  std::string s = std::string(kGimp2DHeader) + R"(

[[material]]
name    = "layer_a"
type    = "isotropic"
density = 1.2e-3
E       = 2400.0
nu      = 0.33
)";
  if (second_material)
    s += R"(
[[material]]
name    = "layer_b"
type    = "isotropic"
density = 1.2e-3
E       = 2400.0
nu      = 0.33
)";
  s += R"(
[[body]]
name     = "left"
material = "layer_a"
shape    = "box"
min      = [2.0, 2.0]
max      = [127.0, 252.0]
particles_per_cell = 2

[[body]]
name     = "right"
shape    = "box"
min      = [127.0, 2.0]
max      = [252.0, 252.0]
particles_per_cell = 2
)";
  s += second_material ? "material = \"layer_b\"\n" : "material = \"layer_a\"\n";
  if (interaction)
    s += R"(
[[interaction]]
materials     = ["layer_a", "layer_b"]
law           = "interface"
Dn            = "perfect"
Dt            = 5.0
normal        = "specified"
normal_vector = [1.0, 0.0]
)";
  s += R"(
[[boundary]]
where = { y = 2.0 }
fix   = ["x", "y"]

[[load]]
kind     = "traction"
where    = { body = "left", face = "y_max" }
traction = [0.0, 0.5]
)";
  return s;
}

// 2d_gimp_inclusions: a polymer block (250 x 250 mm, 2 x 2 particles per
// 1 mm cell) holding 625 glass disks of radius 3 mm on a 10 mm pitch, an
// imperfect interface (Dn = Dt = 1e4, mvg normal: g is scattered too),
// vibrating (initial velocity, fixed face). Nearly every tile reaches an
// interface: the case where the multimaterial fields are best scattered
// with the first P2G ([simulation] mm_fields_share).
std::string inclusions_scene() {
  std::string s = std::string(kGimp2DHeader) + kPolymerAndGlass + R"(
[[body]]
name     = "block"
material = "polymer"
shape    = "box"
min      = [2.0, 2.0]
max      = [252.0, 252.0]
particles_per_cell = 2
velocity = [0.5, 0.0]
)";
  for (int i = 0; i < 25; ++i)
    for (int j = 0; j < 25; ++j)
      s += "\n[[body]]\nname = \"disk" + std::to_string(25 * i + j) +
           "\"\nmaterial = \"glass\"\nshape = \"disk\"\ncenter = [" +
           std::to_string(7.0 + 10.0 * i) + ", " + std::to_string(7.0 + 10.0 * j) +
           "]\nradius = 3.0\nparticles_per_cell = 2\n";
  return s + R"(
[[interaction]]
materials = ["glass", "polymer"]
law       = "interface"
Dn        = 1.0e4
Dt        = 1.0e4
normal    = "mvg"

[[boundary]]
where = { x = 2.0 }
fix   = ["x"]
)";
}

struct StepCase {
  std::string scene;  // name used in the benchmark name and the fixture key
  std::string text;
  std::vector<std::string> overrides;
};

std::unique_ptr<Simulation> make_case_simulation(const StepCase& c) {
  if (fixture_release()) fixture_release()();  // free the kernel fixtures
  return make_simulation(parse_scene_text(c.text, c.scene + ".toml", c.overrides));
}

// Simulations stay alive for the whole step family (a few hundred MB at
// most), so the 1- and 2-thread runs and the interleaved pairs share them.
Simulation& simulation_for(const StepCase& c) {
  static std::map<std::string, std::unique_ptr<Simulation>> sims;
  std::string key = c.scene;
  for (const auto& o : c.overrides) key += "|" + o;
  auto& sim = sims[key];
  if (!sim) sim = make_case_simulation(c);
  return *sim;
}

void bm_step(benchmark::State& state, const StepCase& c, int threads) {
  use_threads(threads);
  try {
    Simulation& sim = simulation_for(c);
    for (int k = 0; k < 3; ++k) sim.step();  // first sort, first touch, warm caches
    const auto s0 = sim.stage_seconds();
    for (auto _ : state) {
      sim.step();
      benchmark::ClobberMemory();
    }
    const auto s1 = sim.stage_seconds();
    const double n = double(sim.particle_count());
    const double steps = double(state.iterations());
    set_ns_per_particle(state, n);
    const auto ds = set_stage_counters(state, s0, s1, steps, n);
    double staged = 0;
    for (double x : ds) staged += x;
    state.counters["staged_ns_per_particle"] = staged * 1e9 / (steps * n);
    const StepCounters sc = sim.counters();
    state.counters["mm_nodes"] = double(sc.multimaterial_nodes);
    state.counters["mm_share"] = staged > 0 ? ds[kStageMultimaterial] / staged : 0.0;
    if (sc.multimaterial_nodes > 0)
      state.counters["mm_ns_per_mm_node"] =
          ds[kStageMultimaterial] * 1e9 / (steps * double(sc.multimaterial_nodes));
    state.counters["fields"] = sim.field_count();
    state.counters["tile"] = sim.tile_edge();
    state.counters["threads"] = threads;
    state.counters["dt"] = sim.dt();
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
  }
}

void add(const StepCase& c, int threads) {
  std::string name = "step/scene:" + c.scene;
  for (const auto& o : c.overrides) {
    // "simulation.sort_every=10" -> "/sort_every:10"
    const auto dot = o.find('.'), eq = o.find('=');
    std::string value = o.substr(eq + 1);
    value.erase(std::remove(value.begin(), value.end(), '"'), value.end());
    name += "/" + o.substr(dot + 1, eq - dot - 1) + ":" + value;
  }
  name += "/threads:" + std::to_string(threads);
  auto* b = benchmark::RegisterBenchmark(
      name.c_str(), [c, threads](benchmark::State& st) { bm_step(st, c, threads); });
  configure(b->UseRealTime()->Unit(benchmark::kMillisecond), 0.6);
}

StepCase shared_case(const std::string& scene) {
  if (scene == "2d_linear_1mat") return {scene, linear_block_scene(250), {}};
  if (scene == "3d_gimp_1mat") return {scene, kGimp3D, {}};
  if (scene == "2d_gimp_interface") return {scene, two_layer(true, true), {}};
  if (scene == "2d_gimp_inclusions") return {scene, inclusions_scene(), {}};
  // The 2D linear block in a grid twice as wide and tall: three quarters
  // of the nodes are empty, as around a body with room to move.
  if (scene == "2d_linear_room") return {scene, linear_block_scene(250), {"grid.cells=[504, 504]"}};
  if (scene == "2d_linear_1e6") return {scene, linear_block_scene(500), {}};
  // The small scenes researchers run most (the shipped inputs/ scenes hold
  // 256 to 10 240 particles): 2d_linear_1mat's block with 10^4 particles,
  // and the two-layer scene on cells 5x wider (10^4 particles).
  if (scene == "2d_linear_10k") return {scene, linear_block_scene(50), {}};
  if (scene == "2d_gimp_interface_10k")
    return {scene,
            two_layer(true, true),
            {"grid.origin=[-3.0, -3.0]", "grid.cell=[5.0, 5.0]", "grid.cells=[52, 52]"}};
  throw std::invalid_argument("no whole-step scene named " + scene);
}

}  // namespace

const char* bench_stage_name(int stage) {
  static const char* const names[] = {"sort", "p2g", "mm", "grid", "g2p", "constitutive", "output"};
  static_assert(std::size(names) == kStageCount);
  return names[stage];
}

std::array<double, 7> set_stage_counters(benchmark::State& state,
                                         const std::array<double, 7>& before,
                                         const std::array<double, 7>& after, double steps,
                                         double particles) {
  static_assert(kStageCount == 7);
  std::array<double, kStageCount> ds{};
  for (int s = 0; s < kStageCount; ++s) {
    ds[s] = after[s] - before[s];
    if (s != kStageOutput)
      state.counters[std::string("stage_") + bench_stage_name(s) + "_ns_per_particle"] =
          ds[s] * 1e9 / (steps * particles);
  }
  return ds;
}

Scheme step_scene_scheme(const std::string& scene) {
  const StepCase c = shared_case(scene);
  return parse_scene_text(c.text, c.scene + ".toml").simulation.scheme;
}

Simulation& step_scene_simulation(const std::string& scene) {
  return simulation_for(shared_case(scene));
}

std::unique_ptr<Simulation> new_step_scene_simulation(const std::string& scene,
                                                      const std::vector<std::string>& overrides) {
  StepCase c = shared_case(scene);
  c.overrides.insert(c.overrides.end(), overrides.begin(), overrides.end());
  return make_case_simulation(c);
}

void register_step() {
  const StepCase linear{"2d_linear_1mat", linear_block_scene(250), {}};
  const StepCase interface {
    "2d_gimp_interface", two_layer(true, true), {}
  };
  const StepCase gimp3d{"3d_gimp_1mat", kGimp3D, {}};
  const StepCase one_mat{"2d_gimp_1mat", two_layer(false, false), {}};
  const StepCase shared{"2d_gimp_2mat_shared", two_layer(true, false), {}};
  for (int threads : {1, 2}) add(linear, threads);
  // The default scheme is MUSL (two transfers); USL is the single-transfer baseline.
  for (int threads : {1, 2})
    add({"2d_linear_1mat", linear_block_scene(250), {"simulation.scheme=\"USL\""}}, threads);
  for (int threads : {1, 2}) add(interface, threads);
  // MUSL's last particle stages and the next P2G as separate passes
  // (fuse_step_tail = false), interleaved with the default rows above.
  for (int threads : {1, 2}) {
    add({"2d_linear_1mat", linear_block_scene(250), {"simulation.fuse_step_tail=false"}}, threads);
    add({"2d_gimp_interface", two_layer(true, true), {"simulation.fuse_step_tail=false"}}, threads);
  }
  // The constitutive update fused into the gradient pass
  // (fuse_constitutive = true), interleaved with the default rows above.
  for (int threads : {1, 2}) {
    add({"2d_linear_1mat", linear_block_scene(250), {"simulation.fuse_constitutive=true"}},
        threads);
    add({"2d_gimp_interface", two_layer(true, true), {"simulation.fuse_constitutive=true"}},
        threads);
  }
  // Multimaterial fields apart (default for the two-layer scene) or with
  // the first P2G (default for the inclusions), each against the other
  // choice forced, interleaved.
  const StepCase inclusions{"2d_gimp_inclusions", inclusions_scene(), {}};
  for (int threads : {1, 2}) {
    add({"2d_gimp_interface", two_layer(true, true), {"simulation.mm_fields_share=0.0"}}, threads);
    add(inclusions, threads);
    add({"2d_gimp_inclusions", inclusions_scene(), {"simulation.mm_fields_share=1.0"}}, threads);
  }
  for (int threads : {1, 2}) add(gimp3d, threads);
  // The unused-feature pair, interleaved.
  for (int threads : {1, 2}) {
    add(one_mat, threads);
    add(shared, threads);
  }
  for (int every : {1, 10, 100})
    for (int threads : {1, 2})
      add({"2d_linear_1mat",
           linear_block_scene(250),
           {"simulation.sort_every=" + std::to_string(every)}},
          threads);
}

}  // namespace mmpm::bench
