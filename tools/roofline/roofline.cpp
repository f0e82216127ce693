// mmpm_roofline: how close the hot kernels and the whole step run to this
// machine's limits (docs/performance.md "Roofline counts").
//
// 1. The machine: STREAM-like triad bandwidth (a = b + s c, 3 arrays of 2^24
//    doubles, bytes counted as 4 per element moved because the store
//    allocates its line) and the peak FMA rate (12 independent FMA chains
//    of one register each per thread, 2 flops per lane).
// 2. Whole-solver steps of a block filling the grid (one material), for
//    each case in the default scheme (MUSL, its step tail fused: P2G runs
//    inside the tail on columns the tail's G2P has just read) and in USL
//    (one transfer each way, every pass on its own), per-stage times from
//    the Stepper's timers, in blocks of K steps.
// 3. Paired with the machine: a triad runs right before and right after
//    every block (then one untimed step, so the block does not start on
//    caches the triad emptied), and each block's ratio time / bound uses the
//    mean of its two triads. This host's bandwidth moves by 25 % within
//    minutes (other tenants), so a bound from a triad measured once, minutes
//    away from the kernel, says little. Reported: the median of the
//    blocks' ratios, and best time / bound at the best triad.
// 4. Counts, per particle and step, the compulsory bytes (every persistent
//    particle column a stage reads read once, every one it writes written
//    once; grid arrays read and written once per step, amortised over the
//    particles) and the flops of the pointwise arithmetic; the bound is
//    max(bytes / triad bandwidth, flops / peak). The "step" row counts the
//    columns of the whole step once: how far the step is from streaming
//    its particles once per step.
// Usage: kUsage below (mmpm_roofline --help).
#include <omp.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include "kernels/lanes.hpp"
#include "kernels/team.hpp"
#include "scene/parse.hpp"
#include "solver/simulation.hpp"

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// The triad's arrays, allocated and first touched once (by the threads that
// use them). The triad and the FMA loop run on the solver's team
// (kernels/team.hpp), as its blocks do: an OpenMP region here left
// libgomp's idle thread spinning for ~2.5 ms on the core the next block's
// team member needed.
struct Triad {
  static constexpr std::size_t n = std::size_t(1) << 24;
  std::unique_ptr<double[]> a{new double[n]}, b{new double[n]}, c{new double[n]};
  explicit Triad(int threads) {
    omp_set_num_threads(threads);
    mmpm::team_for(true, n, [&](std::size_t i) { a[i] = 0.0, b[i] = 1.0, c[i] = 2.0; });
  }
  // GB/s, best of `reps` passes.
  double measure(int threads, int reps) {
    omp_set_num_threads(threads);
    double best = 1e30;
    double* __restrict x = a.get();
    const double* __restrict y = b.get();
    const double* __restrict z = c.get();
    for (int rep = 0; rep < reps; ++rep) {
      const auto t0 = Clock::now();
      const double s = 1.0 + rep * 1e-9;
      mmpm::team_run(true, [&] {
        const auto [lo, hi] =
            mmpm::thread_block(n, std::size_t(mmpm::team_size()), std::size_t(mmpm::team_rank()));
#pragma omp simd
        for (std::size_t i = lo; i < hi; ++i) x[i] = y[i] + s * z[i];
      });
      best = std::min(best, seconds_since(t0));
    }
    volatile double sink = a[n / 2];
    (void)sink;
    return 4.0 * 8.0 * double(n) / best / 1e9;
  }
};

// One register of doubles per chain, and fewer chains than registers: 16
// chains of 8 doubles are 32 registers on an AVX2 target (16 ymm), whose
// spills halved the measured peak (19.6 against 46.6 GFLOP/s on a 2445 MHz
// Zen 3 core; docs/performance.md "The peak FMA rate on AVX2 targets").
// 12 chains cover the FMA latency times the FMA ports (4 x 2) with room.
inline constexpr int kPeakLanes = int(mmpm::kRegisterVectorBytes / sizeof(double));
inline constexpr int kPeakChains = 12;

double peak_gflops(int threads, long iters = 20000000) {
  constexpr int kChains = kPeakChains, kLanes = kPeakLanes;
  omp_set_num_threads(threads);
  std::atomic<long> total_flops{0};
  const auto t0 = Clock::now();
  mmpm::team_run(true, [&] {
    double acc[kChains][kLanes];
    const double x = 1.0 + 1e-9 * mmpm::team_rank(), y = 0.999999999;
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
    total_flops += 2 * (iters / kChains) * kChains * kLanes;
  });
  return double(total_flops.load()) / seconds_since(t0) / 1e9;
}

struct Case {
  const char* label;
  int dim;
  const char* shape;
  const char* precision;
  int S;  // stencil width per direction
};

std::string block_scene(const Case& c, const char* scheme) {
  const bool d3 = c.dim == 3;
  std::string s = "[simulation]\ndimension = " + std::to_string(c.dim) +
                  "\nend_time = 1.0\ncfl = 0.5\nscheme = \"" + scheme + "\"\nprecision = \"" +
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

// Bytes and flops per particle and step of one row (docs/performance.md
// derives the counts).
struct Row {
  const char* stage;
  int idx;  // Stepper stage, or -1: the whole step
  double bytes, flops;
};

std::vector<Row> rows_of(const Case& c, bool musl, double nodes_per_particle) {
  const int D = c.dim, NS = D == 2 ? 4 : 6, nodes = D == 2 ? c.S * c.S : c.S * c.S * c.S;
  const double R = std::strcmp(c.precision, "double") == 0 ? 8.0 : 4.0;
  // uGIMP half-widths move no bytes: one body, one particle spacing, so the
  // Stepper keeps the one value in the particle view (before 2026-12-01
  // every uGIMP step read D columns of them, counted here then).
  const double grid = nodes_per_particle * R * 2.0;  // one grid array read + written per step
  // The force needs the in-plane stresses only: 3 of the 4 in 2D (not zz).
  const int NS_force = D == 2 ? 3 : 6;
  const double p2g_bytes = R * (2 * D + 2 + NS_force) + grid * (1 + 2 * D);
  // L goes through memory in USL (G2P writes it, the constitutive pass
  // reads it); MUSL's fused tail keeps it in a per-thread block of one tile
  // (solver/stepper_impl.hpp fused_step_tail), so it moves no bytes there.
  const int L = musl ? 0 : D * D;
  // USL's G2P reads x, v and writes v, x, L; MUSL's two passes (the
  // first scatters m v, the gradient pass moves x) read m too, once.
  const double g2p_bytes = R * (2 * D + (musl ? 1 : 0)) + 4 + R * (2 * D + L) + grid / 2 * (2 * D);
  const double con_bytes = R * (L + NS + 1) + R * (NS + 1);
  // The step: every persistent column once; reads x, v, m, V, sigma, key;
  // writes x, v, V, sigma (and L in USL); the grid's m, p, f, vel, dvel.
  const double step_bytes =
      R * (2 * D + 2 + NS) + 4 + R * (2 * D + 1 + NS + L) + grid * (1 + 4 * D);
  const double stencil = D * (c.S == 2 ? 4.0 : 14.0) + nodes * (D + 1.0);
  const double p2g_flops = stencil + 2 * D + NS + nodes * (2.0 + 2 * D + 4.0 * D);
  const double one_g2p = stencil + nodes * (4.0 * D + 2.0 * D * D) + 6 * D;
  // MUSL: a second gather (the velocity, then its gradient) and the
  // momentum scatter's n (1 + D) products and sums.
  const double g2p_flops = musl ? 2 * one_g2p + nodes * 2.0 * (1 + D) : one_g2p;
  const double con_flops = D == 2 ? 30 : 60;
  return {{"p2g", mmpm::kStageP2G, p2g_bytes, p2g_flops},
          {"g2p", mmpm::kStageG2P, g2p_bytes, g2p_flops},
          {"constitutive", mmpm::kStageConstitutive, con_bytes, con_flops},
          {"step", -1, step_bytes, p2g_flops + g2p_flops + con_flops}};
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

constexpr const char* kUsage =
    "Usage: mmpm_roofline [--threads N] [--steps K] [--blocks B] [--only TEXT]\n"
    "  --threads N  OpenMP threads (default 1)\n"
    "  --steps K    steps per timed block (default 20)\n"
    "  --blocks B   timed blocks per case and scheme (default 7)\n"
    "  --only TEXT  only the cases whose label contains TEXT (e.g. \"2D linear\")\n"
    "Runs ~3 minutes per thread count on a 2-core host; prints one table.\n";

// The whole of s as an integer in [1, 10^6], into out.
bool parse_count(const char* s, int& out) {
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(s, &end, 10);
  if (end == s || *end != '\0' || errno != 0 || v < 1 || v > 1000000) return false;
  out = int(v);
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  int threads = 1, steps = 20, blocks = 7;
  const char* only = nullptr;
  // Every argument checked before anything runs: a mistyped option must not
  // start minutes of measurement (or be ignored).
  for (int i = 1; i < argc; ++i) {
    const char* arg = argv[i];
    if (!std::strcmp(arg, "--help") || !std::strcmp(arg, "-h")) {
      std::fputs(kUsage, stdout);
      return 0;
    }
    const bool text = !std::strcmp(arg, "--only");
    int* count = !std::strcmp(arg, "--threads")  ? &threads
                 : !std::strcmp(arg, "--steps")  ? &steps
                 : !std::strcmp(arg, "--blocks") ? &blocks
                                                 : nullptr;
    if (!text && !count) {
      std::fprintf(stderr, "mmpm_roofline: unknown option '%s'\n%s", arg, kUsage);
      return 2;
    }
    if (i + 1 >= argc) {
      std::fprintf(stderr, "mmpm_roofline: %s expects a value\n%s", arg, kUsage);
      return 2;
    }
    const char* value = argv[++i];
    if (text) {
      only = value;
    } else if (!parse_count(value, *count)) {
      std::fprintf(stderr, "mmpm_roofline: %s expects an integer from 1 to 1000000, got '%s'\n",
                   arg, value);
      return 2;
    }
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
  Triad triad(threads);
  // The machine right now: a triad (best of 3) and a short peak-FMA run.
  struct Machine {
    double gbs = 0, gflops = 0;
  };
  auto machine_now = [&] {
    Machine m{triad.measure(threads, 3), peak_gflops(threads, 4000000)};
    omp_set_num_threads(threads);
    return m;
  };
  std::printf(
      "machine (%d thread%s): triad (a = b + s c, 3 x 128 MiB) and peak FMA (double, %d chains "
      "of %d lanes) measured around every block of %d steps, %d blocks per case and scheme\n\n",
      threads, threads > 1 ? "s" : "", kPeakChains, kPeakLanes, steps, blocks);
  std::printf("%-17s %-5s %-12s %8s %6s %6s %7s %7s %8s %8s %8s %12s %12s\n", "case", "sch.",
              "stage", "ns/part", "B/part", "fl/p", "GB/s", "GFLOP/s", "bound ns", "x bound",
              "x b. min", "triad GB/s", "peak GFLOP/s");
  std::vector<double> all_gbs, all_gflops;
  for (const Case& c : cases) {
    if (!selected(c)) continue;
    for (const char* scheme : {"MUSL", "USL"}) {
      std::unique_ptr<mmpm::Simulation> sim;
      try {
        sim =
            mmpm::make_simulation(mmpm::parse_scene_text(block_scene(c, scheme), "roofline.toml"));
      } catch (const std::exception& e) {
        std::printf("%-17s %-5s skipped: %s\n", c.label, scheme, e.what());
        continue;
      }
      omp_set_num_threads(threads);
      sim->step();  // the first step sorts; not timed
      const double np = double(sim->particle_count()), nn = double(sim->node_count());
      const bool musl = std::strcmp(scheme, "MUSL") == 0;
      const std::vector<Row> rows = rows_of(c, musl, nn / np);
      // float runs twice the lanes of the double peak
      const double lanes = std::strcmp(c.precision, "double") == 0 ? 1.0 : 2.0;
      // Per block: each row's ns per particle, and the machine around it.
      std::vector<std::vector<double>> t(rows.size());
      std::vector<Machine> at;
      for (int b = 0; b < blocks; ++b) {
        const Machine before = machine_now();
        sim->step();  // after the triad: caches as a run's step finds them
        const auto s0 = sim->stage_seconds();
        const auto w0 = Clock::now();
        for (int k = 0; k < steps; ++k) sim->step();
        const double wall = seconds_since(w0);
        const auto s1 = sim->stage_seconds();
        const Machine after = machine_now();
        at.push_back({0.5 * (before.gbs + after.gbs), 0.5 * (before.gflops + after.gflops)});
        for (const Machine& m : {before, after})
          all_gbs.push_back(m.gbs), all_gflops.push_back(m.gflops);
        for (std::size_t r = 0; r < rows.size(); ++r) {
          const double sec = rows[r].idx < 0 ? wall : s1[rows[r].idx] - s0[rows[r].idx];
          t[r].push_back(sec / steps / np * 1e9);
        }
      }
      Machine best;
      for (const Machine& m : at)
        best.gbs = std::max(best.gbs, m.gbs), best.gflops = std::max(best.gflops, m.gflops);
      double low_gbs = best.gbs, low_gflops = best.gflops;
      for (const Machine& m : at)
        low_gbs = std::min(low_gbs, m.gbs), low_gflops = std::min(low_gflops, m.gflops);
      for (std::size_t r = 0; r < rows.size(); ++r) {
        const Row& row = rows[r];
        auto bound = [&](const Machine& m) {  // ns: bytes / (GB/s) = ns
          return std::max(row.bytes / m.gbs, row.flops / (lanes * m.gflops));
        };
        std::vector<double> ratio;
        for (int b = 0; b < blocks; ++b) ratio.push_back(t[r][b] / bound(at[std::size_t(b)]));
        const double tmin = *std::min_element(t[r].begin(), t[r].end());
        std::printf(
            "%-17s %-5s %-12s %8.2f %6.0f %6.0f %7.2f %7.2f %8.2f %8.2f %8.2f %5.1f-%-6.1f "
            "%5.0f-%-6.0f\n",
            c.label, scheme, row.stage, tmin, row.bytes, row.flops, row.bytes / tmin,
            row.flops / tmin, bound(best), median(ratio), tmin / bound(best), low_gbs, best.gbs,
            low_gflops, best.gflops);
      }
    }
  }
  std::printf(
      "\nns/part: best block. bound ns: max(bytes / triad, flops / peak) at the best triad and "
      "peak. x bound: median over the blocks of time / bound at the block's own machine "
      "(mean of the measurements before and after it); x b. min: best time / best bound. "
      "Below 1: the stage found columns in the cache that the count charges to memory (the "
      "constitutive update reads sigma, and in USL L, right after the G2P pass).\n");
  if (all_gbs.empty()) return 1;  // every case was skipped
  std::printf(
      "Over the run: triad %.1f to %.1f GB/s (median %.1f), peak %.0f to %.0f GFLOP/s "
      "(median %.0f).\n",
      *std::min_element(all_gbs.begin(), all_gbs.end()),
      *std::max_element(all_gbs.begin(), all_gbs.end()), median(all_gbs),
      *std::min_element(all_gflops.begin(), all_gflops.end()),
      *std::max_element(all_gflops.begin(), all_gflops.end()), median(all_gflops));
  return 0;
}
