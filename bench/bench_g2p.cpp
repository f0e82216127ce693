// G2P (velocity FLIP/PIC, position, velocity gradient, tile-change test) per
// shape function, and the isotropic constitutive update, per dimension,
// precision and thread count. Same particle blocks as the P2G benchmarks.
#include <type_traits>

#include "bench/bench_common.hpp"
#include "kernels/constitutive.hpp"
#include "kernels/xpic.hpp"

namespace mmpm::bench {
namespace {

template <int D>
BlockSpec g2p_block(bool gimp) {
  BlockSpec b;
  b.ppc = 2;
  b.gimp = gimp;
  for (int d = 0; d < D; ++d) {
    b.lo[d] = 2;
    b.hi[d] = D == 2 ? 252 : 34;
  }
  return b;
}
template <int D>
std::array<int, 3> g2p_cells() {
  return D == 2 ? std::array<int, 3>{254, 254, 1} : std::array<int, 3>{36, 36, 36};
}

template <int D, class Shape, class Real>
struct G2PFixture {
  ParticleSet<D, Real> S;
  GridSet<D, Real> grid;
  Binning<D, Real> bins;
};

template <int D, class Shape, class Real>
G2PFixture<D, Shape, Real>& g2p_fixture() {
  using F = G2PFixture<D, Shape, Real>;
  return cached_fixture<F>(0, [] {
    auto fx = std::make_unique<F>();
    make_block<D, Real>(fx->S, g2p_block<D>(std::is_same_v<Shape, GimpShape>));
    fx->grid.setup(g2p_cells<D>(), 1, false, true);
    fx->bins.template setup<Shape>(kDefaultTile<D>, fx->grid.G);
    fx->bins.sort(fx->S, fx->grid.G);
    // Small smooth grid velocities: particles drift by ~1e-6 cell per iteration.
    const GridView<D, Real>& G = fx->grid.G;
    for (std::size_t i = 0; i < G.nodes; ++i) {
      const auto x = G.position(i);
      for (int d = 0; d < D; ++d) {
        fx->grid.V.vel[d][i] = Real(1e-3 * std::sin(0.05 * x[0] + 0.03 * x[1] + d));
        fx->grid.V.dvel[d][i] = Real(1e-6 * std::cos(0.02 * x[0] + d));
      }
    }
    return fx;
  });
}

// The G2P benchmarks' step parameters: particles drift by ~1e-6 cell per
// call.
inline G2PParams g2p_bench_params() {
  G2PParams q;
  q.dt = 1e-3;
  q.flip = 0.99;
  return q;
}

// The gathers compared in one run: the solver's (g2p_range), the windowed
// one without pairs of particles per vector (G2PGather::kPairs), and the
// pointwise reference (kernels/g2p.hpp).
enum class Gather { solver, one_per_vector, pointwise };

template <int D, class Shape, class Real, Gather Kernel>
void bm_g2p(benchmark::State& state, int threads) {
  use_threads(threads);
  auto& fx = g2p_fixture<D, Shape, Real>();
  const ParticleView<D, Real>& P = fx.S.P;
  const GridView<D, Real>& G = fx.grid.G;
  const GridVelocity<D, Real>& V = fx.grid.V;
  constexpr unsigned What = kUpdateMotion | kVelocityGradient;
  const G2PParams q = g2p_bench_params();
  // The tile-change test as the Stepper runs it (its KeyFn).
  const auto key_of = PositionTile<D, Real>::of(fx.bins.tiles, fx.bins.origin, G.h, P.x);
  const std::size_t n = P.n, chunks = chunk_count(n);
  std::vector<G2PRangeResult> res(chunks);
  for (auto _ : state) {
    // As Stepper::g2p: fixed chunks, static schedule.
    team_for(n >= kParallelMin, chunks, [&](std::size_t c) {
      const std::size_t b = c * kReduceChunk, e = std::min(n, b + kReduceChunk);
      if constexpr (Kernel == Gather::solver)
        res[c] = g2p_range<D, Shape, Real, What, false, false, false>(P, G, V, q, key_of, b, e);
      else if constexpr (Kernel == Gather::one_per_vector)
        res[c] = g2p_range_impl<D, Shape, Real, What, false, false, false, true, false>(
            P, G, V, q, key_of, b, e);
      else
        res[c] = g2p_range_pointwise<D, Shape, Real, What, false, false, false>(P, G, V, q, key_of,
                                                                                b, e);
    });
    keep(res.data());
    benchmark::ClobberMemory();
  }
  for (const auto& r : res)
    if (r.bad != SIZE_MAX) {
      state.SkipWithError("G2P: stencil off the grid or non-finite velocity");
      return;
    }
  set_ns_per_particle(state, double(n));
  // Particle bytes: read x, v, key (+ lp), write x, v, L.
  const double bytes =
      double(sizeof(Real)) * (4 * D + D * D + (std::is_same_v<Shape, GimpShape> ? D : 0)) + 4.0;
  set_rate(state, "particle_GBps", double(n) * bytes);
  set_rate(state, "Gnode_reads_per_s", double(n) * Stencil<D, Shape, Real>::count);
  state.counters["threads"] = threads;
}

// MUSL's fused pass (G2P of the updated velocity + P2G of m v into the
// zeroed grid momentum, kUpdateMotion | kScatterMomentum), colored tile by
// tile as the Stepper runs it. solver: g2p_range, the solver's choice
// (packed in 2D linear, kernels/g2p_packed.hpp; pairs of particles per
// vector in 3D double); one_particle: the one-particle windowed kernel, the
// baseline in the same run; inline_block / after_batch: the solver's
// gathers with the momenta scattered where named (MomentumScatterAt), both
// measured where the solver picks between them (3D double).
enum class Fused { solver, one_particle, inline_block, after_batch };

template <int D, class Shape, class Real, Fused Kernel, class KeyFn>
G2PRangeResult fused_range(const ParticleView<D, Real>& P, const GridView<D, Real>& G,
                           const GridVelocity<D, Real>& V, const G2PParams& q, const KeyFn& key_of,
                           std::size_t b, std::size_t e) {
  constexpr unsigned What = kUpdateMotion | kScatterMomentum;
  if constexpr (Kernel == Fused::solver)
    return g2p_range<D, Shape, Real, What, false, false, false>(P, G, V, q, key_of, b, e);
  else if constexpr (Kernel == Fused::one_particle)
    return g2p_range_impl<D, Shape, Real, What, false, false, false, true, false>(P, G, V, q,
                                                                                  key_of, b, e);
  else {
    constexpr MomentumScatterAt at = Kernel == Fused::inline_block ? MomentumScatterAt::inline_block
                                                                   : MomentumScatterAt::after_batch;
    return g2p_range_impl<D, Shape, Real, What, false, false, false, true, true, at>(P, G, V, q,
                                                                                     key_of, b, e);
  }
}

template <int D, class Shape, class Real, Fused Kernel>
void bm_g2p_fused(benchmark::State& state, int threads) {
  use_threads(threads);
  auto& fx = g2p_fixture<D, Shape, Real>();
  const ParticleView<D, Real>& P = fx.S.P;
  const GridView<D, Real>& G = fx.grid.G;
  const GridVelocity<D, Real>& V = fx.grid.V;
  const G2PParams q = g2p_bench_params();
  const auto key_of = PositionTile<D, Real>::of(fx.bins.tiles, fx.bins.origin, G.h, P.x);
  std::size_t bad = SIZE_MAX;
  for (auto _ : state) {
    for (int d = 0; d < D; ++d) std::fill(G.p[d], G.p[d] + G.nodes, Real(0));
    bad = std::min(bad, colored_tiles(fx.bins.schedule, P.n, [&](std::size_t b, std::size_t e) {
                     return fused_range<D, Shape, Real, Kernel>(P, G, V, q, key_of, b, e).bad;
                   }));
    keep(G.p[0]);
    benchmark::ClobberMemory();
  }
  if (bad != SIZE_MAX) {
    state.SkipWithError("fused G2P: stencil off the grid or non-finite velocity");
    return;
  }
  set_ns_per_particle(state, double(P.n));
  state.counters["threads"] = threads;
}

// XPIC's interpolation of a grid velocity field to the particles
// (kernels/xpic.hpp), on the G2P blocks: on the windows (the solver's,
// wherever the grid holds a window) against node by node on the stencil,
// in the particle ranges the Stepper uses.
enum class Interpolation { windowed, pointwise };

template <int D, class Shape, class Real, Interpolation Kernel>
void bm_xpic_interpolation(benchmark::State& state, int threads) {
  use_threads(threads);
  auto& fx = g2p_fixture<D, Shape, Real>();
  const ParticleView<D, Real>& P = fx.S.P;
  const GridView<D, Real>& G = fx.grid.G;
  std::array<const Real*, D> u;
  for (int d = 0; d < D; ++d) u[d] = fx.grid.V.vel[d];
  std::vector<Real> out_storage(static_cast<std::size_t>(D) * P.n);
  std::array<Real*, D> out;
  for (int d = 0; d < D; ++d) out[d] = out_storage.data() + std::size_t(d) * P.n;
  const std::size_t n = P.n, chunks = chunk_count(n);
  std::vector<std::size_t> stopped(chunks);
  for (auto _ : state) {
    team_for(n >= kParallelMin, chunks, [&](std::size_t c) {
      const std::size_t b = c * kReduceChunk, e = std::min(n, b + kReduceChunk);
      if constexpr (Kernel == Interpolation::windowed)
        stopped[c] =
            interpolate_to_particles_windowed<D, Shape, Real>(P, G, u, into_arrays(out), b, e) - e;
      else
        stopped[c] =
            interpolate_to_particles_pointwise<D, Shape, Real>(P, G, u, into_arrays(out), b, e) - e;
    });
    keep(out[0]);
    benchmark::ClobberMemory();
  }
  for (std::size_t s : stopped)
    if (s != 0) {
      state.SkipWithError("XPIC interpolation: stencil off the grid");
      return;
    }
  set_ns_per_particle(state, double(n));
  state.counters["threads"] = threads;
}

template <int D, class Shape, class Real, Interpolation Kernel>
void register_xpic_interpolation_kernel(const char* kernel) {
  for (int threads : {1, 2}) {
    const std::string name = std::string("xpic_interpolation/dim:") + std::to_string(D) +
                             "/shape:" + Shape::name + "/real:" + real_name<Real>() +
                             "/kernel:" + kernel + "/threads:" + std::to_string(threads);
    auto* b = benchmark::RegisterBenchmark(name.c_str(), [threads](benchmark::State& st) {
      bm_xpic_interpolation<D, Shape, Real, Kernel>(st, threads);
    });
    configure(b->UseRealTime()->Unit(benchmark::kMillisecond), 0.1);
  }
}

template <int D, class Shape, class Real>
void register_xpic_interpolation_case() {
  register_xpic_interpolation_kernel<D, Shape, Real, Interpolation::windowed>("windowed");
  register_xpic_interpolation_kernel<D, Shape, Real, Interpolation::pointwise>("pointwise");
}

template <int D, class Real>
struct ConstitutiveFixture {
  ParticleSet<D, Real> S;
};

template <int D, class Real>
void bm_constitutive(benchmark::State& state, int threads) {
  use_threads(threads);
  using F = ConstitutiveFixture<D, Real>;
  auto& fx = cached_fixture<F>(0, [] {
    auto f = std::make_unique<F>();
    make_block<D, Real>(f->S, g2p_block<D>(false));
    return f;
  });
  const ParticleView<D, Real>& P = fx.S.P;
  ElasticKernelConstants c;
  const double E = 2400, nu = 0.33;
  c.lambda = E * nu / ((1 + nu) * (1 - 2 * nu));
  c.mu = E / (2 * (1 + nu));
  c.density = 1.2e-3;
  c.plane_stress = false;
  const double dt = 1e-4;
  const IsotropicPoint<D, Real> update(c, dt);
  for (auto _ : state) {
    // As Stepper::constitutive runs it: each thread its block of particles.
    team_run(P.n >= kParallelMin, [&] {
      const auto [first, last] =
          thread_block(P.n, std::size_t(team_size()), std::size_t(team_rank()));
      update_particles(P, nullptr, first, last, update);
    });
    keep(P.s[0]);
    benchmark::ClobberMemory();
  }
  if (!std::isfinite(double(P.s[0][0])) || !(P.V[0] > 0)) {
    state.SkipWithError("constitutive: non-finite stress or volume");
    return;
  }
  constexpr int NS = kStressComponents<D>;
  set_ns_per_particle(state, double(P.n));
  // Read L, s, V; write s, V.
  set_rate(state, "particle_GBps", double(P.n) * double(sizeof(Real)) * (D * D + 2 * NS + 2));
  state.counters["threads"] = threads;
}

template <int D, class Shape, class Real, Gather Kernel>
void register_g2p_kernel(const char* family) {
  for (int threads : {1, 2}) {
    const std::string name = std::string(family) + "/dim:" + std::to_string(D) +
                             "/shape:" + Shape::name + "/real:" + real_name<Real>() +
                             "/threads:" + std::to_string(threads);
    auto* b = benchmark::RegisterBenchmark(name.c_str(), [threads](benchmark::State& st) {
      bm_g2p<D, Shape, Real, Kernel>(st, threads);
    });
    configure(b->UseRealTime()->Unit(benchmark::kMillisecond), 0.1);
  }
}

template <int D, class Shape, class Real>
void register_g2p_case() {
  register_g2p_kernel<D, Shape, Real, Gather::solver>("g2p");
  // Only where the solver pairs particles, so the two differ.
  if constexpr (G2PGather<D, Shape, Real, true>::kPairs)
    register_g2p_kernel<D, Shape, Real, Gather::one_per_vector>("g2p_one_per_vector");
  register_g2p_kernel<D, Shape, Real, Gather::pointwise>("g2p_pointwise");
}

template <int D, class Shape, class Real, Fused Kernel>
void register_g2p_fused_kernel(const char* kernel) {
  for (int threads : {1, 2}) {
    const std::string name = std::string("g2p_fused/dim:") + std::to_string(D) +
                             "/shape:" + Shape::name + "/real:" + real_name<Real>() +
                             "/kernel:" + kernel + "/threads:" + std::to_string(threads);
    auto* b = benchmark::RegisterBenchmark(name.c_str(), [threads](benchmark::State& st) {
      bm_g2p_fused<D, Shape, Real, Kernel>(st, threads);
    });
    configure(b->UseRealTime()->Unit(benchmark::kMillisecond), 0.1);
  }
}

template <int D, class Shape, class Real>
void register_g2p_fused_case() {
  register_g2p_fused_kernel<D, Shape, Real, Fused::solver>("solver");
  register_g2p_fused_kernel<D, Shape, Real, Fused::one_particle>("one_particle");
  // 3D double: where the solver picks between the two. 2D linear: where a
  // target without AVX-512 runs the one-particle windows (16 vector
  // registers: the inline block competes with the gather's sums).
  if constexpr (D == 3 || std::is_same_v<Shape, LinearShape>) {
    register_g2p_fused_kernel<D, Shape, Real, Fused::inline_block>("inline_block");
    register_g2p_fused_kernel<D, Shape, Real, Fused::after_batch>("after_batch");
  }
}

template <int D, class Real>
void register_dim_real() {
  register_g2p_case<D, LinearShape, Real>();
  register_g2p_case<D, GimpShape, Real>();
  register_g2p_case<D, BSpline2Shape, Real>();
  register_g2p_case<D, BSpline3Shape, Real>();
  for (int threads : {1, 2}) {
    const std::string name = "constitutive/dim:" + std::to_string(D) +
                             "/law:isotropic/real:" + real_name<Real>() +
                             "/threads:" + std::to_string(threads);
    auto* b = benchmark::RegisterBenchmark(
        name.c_str(), [threads](benchmark::State& st) { bm_constitutive<D, Real>(st, threads); });
    configure(b->UseRealTime()->Unit(benchmark::kMillisecond), 0.1);
  }
}

}  // namespace

void register_g2p() {
  register_xpic_interpolation_case<2, LinearShape, double>();
  register_xpic_interpolation_case<2, GimpShape, double>();
  register_xpic_interpolation_case<2, BSpline2Shape, double>();
  register_xpic_interpolation_case<2, LinearShape, float>();
  register_xpic_interpolation_case<3, LinearShape, double>();
  register_xpic_interpolation_case<2, GimpShape, float>();
  register_xpic_interpolation_case<3, GimpShape, double>();
  register_g2p_fused_case<2, LinearShape, double>();
  register_g2p_fused_case<2, LinearShape, float>();
  register_g2p_fused_case<3, GimpShape, double>();
  register_g2p_fused_case<3, BSpline2Shape, double>();
  register_g2p_fused_case<3, BSpline3Shape, double>();  // where the solver defers the momenta
  register_dim_real<2, double>();
  register_dim_real<2, float>();
  register_dim_real<3, double>();
  register_dim_real<3, float>();
}

}  // namespace mmpm::bench
