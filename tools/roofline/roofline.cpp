// mmpm_roofline: how close the hot kernels run to this machine's limits.
//
// 1. Measures the machine: STREAM-like triad bandwidth (a = b + s c, 3
//    arrays of 2^24 doubles, best of 5; bytes counted as 4 per element moved
//    because the store allocates its line) and the peak FMA rate (16
//    independent vector FMA chains per thread, 2 flops per lane).
// 2. Runs whole-solver steps (USL, one material, a block filling the grid)
//    for each case and takes the per-stage times from the Stepper's timers,
//    best of 5 blocks of K steps.
// 3. Counts, per particle and step, the compulsory bytes each stage must
//    move (particle arrays read/written once; grid arrays read and written
//    once per step, amortised over the particles) and the flops of the
//    kernel's arithmetic (docs/performance.md derives the counts), and prints
//    achieved GB/s and GFLOP/s next to the bound
//    max(bytes / bandwidth, flops / peak) and the ratio time / bound.
// Usage: mmpm_roofline [--threads N] [--steps K] [--only TEXT]
//   --only runs the cases whose label contains TEXT (e.g. "2D linear").
#include <omp.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iterator>
#include <string>
#include <vector>

#include "scene/parse.hpp"
#include "solver/simulation.hpp"

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

double triad_bandwidth(int threads) {
  const std::size_t n = std::size_t(1) << 24;
  std::vector<double> a(n), b(n, 1.0), c(n, 2.0);
  omp_set_num_threads(threads);
#pragma omp parallel for schedule(static)
  for (std::size_t i = 0; i < n; ++i) a[i] = 0.0;  // first touch
  double best = 1e30;
  for (int rep = 0; rep < 5; ++rep) {
    const auto t0 = Clock::now();
    const double s = 1.0 + rep * 1e-9;
#pragma omp parallel for schedule(static)
    for (std::size_t i = 0; i < n; ++i) a[i] = b[i] + s * c[i];
    best = std::min(best, seconds_since(t0));
  }
  volatile double sink = a[n / 2];
  (void)sink;
  return 4.0 * 8.0 * double(n) / best / 1e9;
}

double peak_gflops(int threads) {
  constexpr int kChains = 16, kLanes = 8;
  const long iters = 20000000;
  omp_set_num_threads(threads);
  double total_flops = 0;
  const auto t0 = Clock::now();
#pragma omp parallel reduction(+ : total_flops)
  {
    double acc[kChains][kLanes];
    const double x = 1.0 + 1e-9 * omp_get_thread_num(), y = 0.999999999;
    for (int c = 0; c < kChains; ++c)
      for (int l = 0; l < kLanes; ++l) acc[c][l] = 1.0 + 1e-6 * (c * kLanes + l);
    for (long it = 0; it < iters / kChains; ++it)
      for (int c = 0; c < kChains; ++c)
#pragma omp simd
        for (int l = 0; l < kLanes; ++l) acc[c][l] = acc[c][l] * y + x;
    double s = 0;
    for (int c = 0; c < kChains; ++c)
      for (int l = 0; l < kLanes; ++l) s += acc[c][l];
    if (s == 42.0) std::printf("!");
    total_flops += 2.0 * double(iters / kChains) * kChains * kLanes;
  }
  return total_flops / seconds_since(t0) / 1e9;
}

struct Case {
  const char* label;
  int dim;
  const char* shape;
  const char* precision;
  int S;  // stencil width per direction
};

std::string block_scene(const Case& c) {
  const bool d3 = c.dim == 3;
  std::string s =
      "[simulation]\ndimension = " + std::to_string(c.dim) +
      "\nend_time = 1.0\ncfl = 0.5\nscheme = \"USL\"\nfuse_constitutive = false\nprecision = \"" +
      c.precision + "\"\n";
  s += d3 ? "[grid]\norigin = [-2.0, -2.0, -2.0]\ncell = [1.0, 1.0, 1.0]\ncells = [54, 54, 54]\n"
          : "[grid]\norigin = [-2.0, -2.0]\ncell = [1.0, 1.0]\ncells = [254, 254]\n";
  s += std::string("shape = \"") + c.shape + "\"\n";
  s += "[[material]]\nname = \"m\"\ntype = \"isotropic\"\ndensity = 1.0e-3\nE = 1000.0\nnu = 0.3\n";
  s += d3 ? "[[body]]\nmaterial = \"m\"\nshape = \"box\"\nmin = [0.0, 0.0, 0.0]\nmax = [50.0, "
            "50.0, 50.0]\n"
          : "[[body]]\nmaterial = \"m\"\nshape = \"box\"\nmin = [0.0, 0.0]\nmax = [250.0, 250.0]\n";
  s += "particles_per_cell = 2\n";
  s += d3 ? "velocity = [0.1, 0.05, 0.0]\n" : "velocity = [0.1, 0.05]\n";
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  int threads = 1, steps = 20;
  const char* only = nullptr;
  for (int i = 1; i + 1 < argc; ++i) {
    if (!std::strcmp(argv[i], "--only")) only = argv[i + 1];
    if (!std::strcmp(argv[i], "--threads")) threads = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--steps")) steps = std::atoi(argv[i + 1]);
  }
  const Case cases[] = {{"2D linear double", 2, "linear", "double", 2},
                        {"2D gimp double", 2, "gimp", "double", 3},
                        {"2D gimp float", 2, "gimp", "float", 3},
                        {"3D gimp double", 3, "gimp", "double", 3}};
  auto selected = [only](const Case& c) { return !only || std::strstr(c.label, only); };
  if (std::none_of(std::begin(cases), std::end(cases), selected)) {
    std::fprintf(stderr, "mmpm_roofline: --only \"%s\" matches no case label (", only);
    for (const Case& c : cases) std::fprintf(stderr, "%s\"%s\"", &c == cases ? "" : ", ", c.label);
    std::fprintf(stderr, ")\n");
    return 2;
  }
  const double bw = triad_bandwidth(threads), peak = peak_gflops(threads);
  std::printf("machine (%d thread%s): triad %.1f GB/s, peak FMA %.1f GFLOP/s (double, 8 lanes)\n\n",
              threads, threads > 1 ? "s" : "", bw, peak);
  std::printf("%-22s %-13s %9s %9s %9s %8s %8s %9s %7s\n", "case", "stage", "ns/part", "B/part",
              "flop/part", "GB/s", "GFLOP/s", "bound ns", "x bound");
  for (const Case& c : cases) {
    if (!selected(c)) continue;
    mmpm::Scene scene;
    try {
      scene = mmpm::parse_scene_text(block_scene(c), "roofline.toml");
    } catch (const std::exception& e) {
      std::printf("%s: %s\n", c.label, e.what());
      continue;
    }
    std::unique_ptr<mmpm::Simulation> sim;
    try {
      sim = mmpm::make_simulation(scene);
    } catch (const std::exception& e) {
      std::printf("%-22s skipped: %s\n", c.label, e.what());
      continue;
    }
    omp_set_num_threads(threads);
    sim->step();  // first step sorts; not timed
    // Best of 5 blocks of `steps` steps per stage: one block is one sample
    // of a shared host's load (the triad is best of 5 too).
    std::array<double, mmpm::kStageCount> best;
    best.fill(1e30);
    for (int rep = 0; rep < 5; ++rep) {
      const auto before = sim->stage_seconds();
      for (int k = 0; k < steps; ++k) sim->step();
      const auto after = sim->stage_seconds();
      for (int st = 0; st < mmpm::kStageCount; ++st)
        best[std::size_t(st)] = std::min(best[std::size_t(st)], after[st] - before[st]);
    }
    const double np = double(sim->particle_count()), nn = double(sim->node_count());
    const int D = c.dim, NS = D == 2 ? 4 : 6, nodes = D == 2 ? c.S * c.S : c.S * c.S * c.S;
    const double R = std::strcmp(c.precision, "double") == 0 ? 8.0 : 4.0;
    const bool gimp = std::strcmp(c.shape, "gimp") == 0;
    // Compulsory traffic per particle (docs/performance.md).
    const double grid_per_p = nn / np * R * 2.0;  // one array read + written once per step
    // The force needs the in-plane stresses only: 3 of the 4 in 2D (not zz).
    const int NS_force = D == 2 ? 3 : 6;
    const double p2g_bytes = R * (2 * D + 2 + NS_force + (gimp ? D : 0)) + grid_per_p * (1 + 2 * D);
    const double g2p_bytes =
        R * (2 * D + (gimp ? D : 0)) + 4 + R * (2 * D + D * D) + grid_per_p / 2 * (2 * D);
    const double con_bytes = R * (D * D + NS + 1) + R * (NS + 1);
    const double stencil_flops = D * (c.S == 2 ? 4.0 : 14.0) + nodes * (D + 1.0);
    const double p2g_flops = stencil_flops + 2 * D + NS + nodes * (2.0 + 2 * D + 4.0 * D);
    const double g2p_flops = stencil_flops + nodes * (4.0 * D + 2.0 * D * D) + 6 * D;
    const double con_flops = D == 2 ? 30 : 60;
    struct Row {
      const char* stage;
      int idx;
      double bytes, flops;
    } rows[] = {{"p2g", mmpm::kStageP2G, p2g_bytes, p2g_flops},
                {"g2p", mmpm::kStageG2P, g2p_bytes, g2p_flops},
                {"constitutive", mmpm::kStageConstitutive, con_bytes, con_flops}};
    const double peak_real = R == 8.0 ? peak : 2 * peak;
    for (const Row& r : rows) {
      const double t = best[std::size_t(r.idx)] / steps / np * 1e9;      // ns per particle
      const double bound = std::max(r.bytes / bw, r.flops / peak_real);  // ns (bytes / (GB/s) = ns)
      std::printf("%-22s %-13s %9.2f %9.0f %9.0f %8.2f %8.2f %9.2f %7.2f\n", c.label, r.stage, t,
                  r.bytes, r.flops, r.bytes / t, r.flops / t, bound, t / bound);
    }
  }
  return 0;
}
