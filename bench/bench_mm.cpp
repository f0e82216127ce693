// The multimaterial pass (kernels/multimaterial.hpp): ns per multimaterial
// node for each law (stick, frictionless, friction, interface) and each
// normal method (mvg, avg, specified, radial), on a grid with one straight
// two-material interface.
//
// The grid is filled once by a real multi-field P2G of two particle blocks
// side by side (interface on a cell midplane, x = 8.5 in 2D, 6.5 in 3D),
// moving towards each other and sliding along the interface, with opposite
// displacements so both contact and interface laws do their full work.
// Each iteration restores the momenta and interface forces (untimed) and
// times, with a manual timer, what the solver's multimaterial stage does:
// find the nodes, pass A, pass B. Counters split the three parts.
#include <chrono>

#include "bench/bench_common.hpp"
#include "kernels/multimaterial.hpp"
#include "scene/format.hpp"

namespace mmpm::bench {
namespace {

using Clock = std::chrono::steady_clock;

template <int D>
struct MMGeometry {
  std::array<int, 3> cells;
  BlockSpec block;
};

// 2D: 16 x 2050 cells, particles in [2,14) x [2,2048): ~4 100 multimaterial
// nodes (two node columns), 98 208 particles. 3D: 12 x 64 x 64 cells,
// particles in [2,10) x [2,62)^2: ~7 900 nodes, 230 400 particles.
template <int D>
MMGeometry<D> mm_geometry() {
  MMGeometry<D> g;
  g.block.ppc = 2;
  g.block.gimp = true;
  g.block.multifield = true;
  if constexpr (D == 2) {
    g.cells = {16, 2050, 1};
    g.block.lo = {2, 2, 0};
    g.block.hi = {14, 2048, 1};
    g.block.interface_x = 8.5;
  } else {
    g.cells = {12, 64, 64};
    g.block.lo = {2, 2, 2};
    g.block.hi = {10, 62, 62};
    g.block.interface_x = 6.5;
  }
  return g;
}

template <int D, class Real>
struct MMFixture {
  ParticleSet<D, Real> S;
  GridSet<D, Real> grid;
  std::vector<std::vector<Real>> pristine;  // p[d] then fi[d] after P2G
  Real mass_threshold = 0;
  std::size_t mm_nodes = 0;
};

template <int D, class Real>
MMFixture<D, Real>& mm_fixture() {
  using F = MMFixture<D, Real>;
  return cached_fixture<F>(0, [] {
    auto fx = std::make_unique<F>();
    const MMGeometry<D> geo = mm_geometry<D>();
    make_block<D, Real>(fx->S, geo.block);
    ParticleView<D, Real>& P = fx->S.P;
    // Field 0 moves +x (towards field 1) and slides +y; field 1 the opposite.
    // Displacements u = x - x0 of opposite signs give an overlap (δ_n < 0)
    // and a tangential opening.
    const Real vel[3] = {Real(1.0), Real(0.5), Real(0.2)};
    const Real disp[3] = {Real(0.002), Real(0.004), Real(0.001)};
    double min_mass = 1e300;
    for (std::size_t p = 0; p < P.n; ++p) {
      const Real s = P.field[p] == 0 ? Real(1) : Real(-1);
      for (int d = 0; d < D; ++d) {
        P.v[d][p] = s * vel[d];
        P.x0[d][p] = P.x[d][p] - s * disp[d];
      }
      min_mass = std::min(min_mass, double(P.m[p]));
    }
    fx->grid.setup(geo.cells, 2, true, false);
    const GridView<D, Real>& G = fx->grid.G;
    P2GOptions opt;  // displacement separation, thickness 1
    constexpr unsigned What = kMassMomentum | kForce | kMultimaterial | kDomainGradient;
    p2g_range<D, GimpShape, Real, What, true, false>(P, G, opt, 0, P.n);
    // As MultimaterialStage: 1e-9 of the lightest particle x 1000.
    fx->mass_threshold = Real(1e-9 * min_mass * 1000);
    const std::size_t n = fx->grid.size();
    for (int d = 0; d < D; ++d) fx->pristine.emplace_back(G.p[d], G.p[d] + n);
    for (int d = 0; d < D; ++d) fx->pristine.emplace_back(G.fi[d], G.fi[d] + n);
    std::vector<std::uint32_t> list;
    find_multimaterial_nodes(G, fx->mass_threshold, list);
    fx->mm_nodes = list.size();
    return fx;
  });
}

template <int D, class Real>
void restore(MMFixture<D, Real>& fx) {
  const GridView<D, Real>& G = fx.grid.G;
  for (int d = 0; d < D; ++d) {
    restore_owned(G.p[d], fx.pristine[std::size_t(d)].data(), G.nodes, G.fields);
    restore_owned(G.fi[d], fx.pristine[std::size_t(D + d)].data(), G.nodes, G.fields);
  }
}

template <int D, class Real>
void bm_mm(benchmark::State& state, Law law, NormalMethod normal, int threads) {
  use_threads(threads);
  auto& fx = mm_fixture<D, Real>();
  GridView<D, Real> G = fx.grid.G;

  PairParams<Real> pp;
  pp.law = law;
  pp.friction = Real(0.3);
  pp.Dn = PairParams<Real>::kPerfect;  // the two-layer specimen: Dn perfect, Dt = 5
  pp.Dt = Real(5);
  pp.normal_method = normal;
  pp.normal_vector = {Real(1), Real(0), Real(0)};
  // Radial: a centre far to the left, so the normals are close to +x.
  pp.radial_center = {Real(-1000), Real(G.nodes_per_dim[1] / 2), Real(G.nodes_per_dim[2] / 2)};
  pp.first_field = 0;
  pp.separation = Separation::displacement;
  pp.force_limit = true;
  pp.integration = Integration::explicit_;
  const int pair[4] = {-1, 0, 0, -1};
  MMConfig<D, Real> cfg;
  cfg.fields = 2;
  cfg.pair = pair;
  cfg.params = &pp;
  cfg.dt = Real(1e-4);
  cfg.thickness = Real(1);
  cfg.mass_threshold = fx.mass_threshold;
  if (const char* why = validate_multimaterial(G, cfg)) {
    state.SkipWithError(why);
    return;
  }

  std::vector<std::uint32_t> list;
  std::vector<unsigned char> flags;
  PassAGeometry<D, Real> geometry;  // as the solver's stage: pass B reuses it
  MMStats stats;
  double t_find = 0, t_a = 0, t_b = 0;
  for (auto _ : state) {
    restore(fx);
    const auto t0 = Clock::now();
    find_multimaterial_nodes(G, cfg.mass_threshold, list);
    const auto t1 = Clock::now();
    stats.reset(cfg.fields);
    multimaterial_pass_a(G, list, cfg, stats, flags, {}, &geometry);
    const auto t2 = Clock::now();
    multimaterial_pass_b(G, list, cfg, flags, stats, {}, &geometry);
    const auto t3 = Clock::now();
    keep(stats.interface_energy);
    benchmark::ClobberMemory();
    t_find += std::chrono::duration<double>(t1 - t0).count();
    t_a += std::chrono::duration<double>(t2 - t1).count();
    t_b += std::chrono::duration<double>(t3 - t2).count();
    state.SetIterationTime(std::chrono::duration<double>(t3 - t0).count());
  }
  const double nodes = double(list.size());
  if (list.empty() || !std::isfinite(stats.interface_energy)) {
    state.SkipWithError("no multimaterial nodes or non-finite interface energy");
    return;
  }
  const double per = 1e9 / (double(state.iterations()) * nodes);
  set_ns_per_item(state, "ns_per_mm_node", nodes);
  state.counters["mm_nodes"] = nodes;
  state.counters["find_ns_per_mm_node"] = t_find * per;
  state.counters["passA_ns_per_mm_node"] = t_a * per;
  state.counters["passB_ns_per_mm_node"] = t_b * per;
  state.counters["grid_nodes"] = double(G.nodes);
  state.counters["interface_energy"] = stats.interface_energy;
  state.counters["threads"] = threads;
}

template <int D>
void register_dim() {
  for (Law law : {Law::stick, Law::frictionless, Law::friction, Law::interface})
    for (NormalMethod normal :
         {NormalMethod::mvg, NormalMethod::avg, NormalMethod::specified, NormalMethod::radial})
      for (int threads : {1, 2}) {
        const std::string name = "mm/dim:" + std::to_string(D) +
                                 "/law:" + std::string(scene_name(law)) +
                                 "/normal:" + std::string(scene_name(normal)) +
                                 "/real:double/threads:" + std::to_string(threads);
        auto* b = benchmark::RegisterBenchmark(name.c_str(),
                                               [law, normal, threads](benchmark::State& st) {
                                                 bm_mm<D, double>(st, law, normal, threads);
                                               });
        configure(b->UseManualTime()->Unit(benchmark::kMicrosecond), 0.05);
      }
}

}  // namespace

void register_multimaterial() {
  register_dim<2>();
  register_dim<3>();
}

}  // namespace mmpm::bench
