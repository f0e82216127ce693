// Seeding cost (make_particles, src/model/bodies.cpp): a 250 x 250 mm
// polymer block on a 254² grid of 1 mm cells, 2 x 2 particles per cell
// (250 000 particles), holding n x n glass disks (radius 0.3 of the pitch)
// that replace the block's particles inside them: the particle-filled
// polymer a user seeds once per run. n = 0 is the block alone, the baseline
// of the ratio in bench/RESULTS.md. The scene is parsed once, outside the
// timer. Before 2026-11-26 every later body tested every particle seeded so
// far (O(particles x bodies)); now only those in its bounding box's cells.
// parse/disks:N times parse_scene_text of the same scenes, per body: it
// was O(bodies^2) (toml11 counted lines from the file's start for each
// body's location, and duplicate names were searched body by body).
#include <string>

#include "bench/bench_common.hpp"
#include "model/bodies.hpp"
#include "scene/parse.hpp"

namespace mmpm::bench {
namespace {

std::string disks_scene(int n) {
  std::string s = std::string(kGimp2DHeader) + kPolymerAndGlass + R"(
[[body]]
material = "polymer"
shape    = "box"
min      = [2.0, 2.0]
max      = [252.0, 252.0]
particles_per_cell = 2
)";
  const double pitch = n > 0 ? 250.0 / n : 0.0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      s += "\n[[body]]\nmaterial = \"glass\"\nshape = \"disk\"\ncenter = [" +
           std::to_string(2.0 + pitch * (i + 0.5)) + ", " +
           std::to_string(2.0 + pitch * (j + 0.5)) + "]\nradius = " + std::to_string(0.3 * pitch) +
           "\nparticles_per_cell = 2\n";
  return s;
}

void bm_seed(benchmark::State& state, int n) {
  const Scene scene = parse_scene_text(disks_scene(n), "disks.toml");
  std::size_t particles = 0;
  for (auto _ : state) {
    const ParticleSeeds s = make_particles(scene);
    particles = s.x.size();
    keep(particles);
  }
  set_ns_per_particle(state, double(particles));
  state.counters["bodies"] = double(scene.bodies.size());
}

void bm_parse(benchmark::State& state, int n) {
  const std::string text = disks_scene(n);
  std::size_t bodies = 0;
  for (auto _ : state) {
    const Scene scene = parse_scene_text(text, "disks.toml");
    bodies = scene.bodies.size();
    keep(bodies);
  }
  // ns per item with 1000 items a body: microseconds per body.
  set_ns_per_item(state, "us_per_body", double(bodies) * 1e3);
  state.counters["bodies"] = double(bodies);
}

}  // namespace

void register_seed() {
  for (int n : {0, 25, 50, 100}) {
    const std::string name = "seed/disks:" + std::to_string(n * n) + "/threads:1";
    auto* b =
        benchmark::RegisterBenchmark(name.c_str(), [n](benchmark::State& st) { bm_seed(st, n); });
    configure(b->Unit(benchmark::kMillisecond)->UseRealTime(), 0.3);
  }
  for (int n : {25, 100, 200}) {
    const std::string name = "parse/disks:" + std::to_string(n * n) + "/threads:1";
    auto* b =
        benchmark::RegisterBenchmark(name.c_str(), [n](benchmark::State& st) { bm_parse(st, n); });
    configure(b->Unit(benchmark::kMillisecond)->UseRealTime(), 0.3);
  }
}

}  // namespace mmpm::bench
