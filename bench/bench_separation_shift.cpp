// MUSL's gradient pass (kVelocityGradient | kCommitPosition, the step's
// last G2P) with the separation shift of an interface scene
// (kernels/separation_shift.hpp), three ways in one run:
//   fused:    the shift inside the gradient pass (kSeparationShift, the solver's);
//   separate: the gradient pass, then the shift's own pass
//             (advance_separation_shift; the solver until the fusion);
//   none:     the gradient pass alone (a scene without an interface spring).
// fused - none is what the shift costs a step; separate - fused what the
// fusion saved. Two material fields split at mid-block (as the two-layer
// scene), 2 particles per cell per direction, uncolored chunks as the
// solver runs the pass.
#include <type_traits>

#include "bench/bench_common.hpp"
#include "kernels/g2p.hpp"
#include "kernels/separation_shift.hpp"

namespace mmpm::bench {
namespace {

enum class ShiftKernel { fused, separate, none };

template <int D, class Real>
struct ShiftFixture {
  ParticleSet<D, Real> S;
  GridSet<D, Real> grid;
  Binning<D, Real> bins;
};

template <int D, class Shape, class Real>
ShiftFixture<D, Real>& shift_fixture() {
  using F = ShiftFixture<D, Real>;
  return cached_fixture<F>(0, [] {
    auto fx = std::make_unique<F>();
    BlockSpec b;
    b.ppc = 2;
    b.gimp = std::is_same_v<Shape, GimpShape>;
    b.multifield = true;
    for (int d = 0; d < D; ++d) {
      b.lo[d] = 2;
      b.hi[d] = D == 2 ? 252 : 34;
    }
    b.interface_x = 0.5 * (b.lo[0] + b.hi[0]);
    make_block<D, Real>(fx->S, b);
    const std::size_t n = fx->S.P.n;
    for (int d = 0; d < D; ++d) {
      fx->S.P.x_next[d] = fx->S.add_real(n);
      fx->S.P.sep_shift[d] = fx->S.add_real(n);
    }
    std::array<int, 3> cells{1, 1, 1};
    for (int d = 0; d < D; ++d) cells[d] = D == 2 ? 254 : 36;
    fx->grid.setup(cells, 2, false, true);
    fx->bins.template setup<Shape>(kDefaultTile<D>, fx->grid.G);
    fx->bins.sort(fx->S, fx->grid.G);
    const GridView<D, Real>& G = fx->grid.G;
    for (std::size_t i = 0; i < fx->grid.size(); ++i) {
      const auto x = G.position(i % G.nodes);
      for (int d = 0; d < D; ++d)
        fx->grid.V.vel[d][i] = Real(1e-3 * std::sin(0.05 * x[0] + 0.03 * x[1] + d));
    }
    return fx;
  });
}

template <int D, class Shape, class Real, ShiftKernel Kernel>
void bm_gradient_shift(benchmark::State& state, int threads) {
  use_threads(threads);
  auto& fx = shift_fixture<D, Shape, Real>();
  const ParticleView<D, Real>& P = fx.S.P;
  const GridView<D, Real>& G = fx.grid.G;
  const GridVelocity<D, Real>& V = fx.grid.V;
  std::array<const Real*, D> vstar;
  for (int d = 0; d < D; ++d) vstar[std::size_t(d)] = V.vel[d];
  G2PParams q;
  q.dt = 1e-3;
  q.flip = 0.99;
  const auto key_of = PositionTile<D, Real>::of(fx.bins.tiles, fx.bins.origin, G.h, P.x);
  constexpr unsigned kGradient = kVelocityGradient | kCommitPosition;
  const std::size_t n = P.n, chunks = chunk_count(n);
  std::vector<std::size_t> bad(chunks, SIZE_MAX);
  for (auto _ : state) {
    team_for(n >= kParallelMin, chunks, [&](std::size_t c) {
      const std::size_t b = c * kReduceChunk, e = std::min(n, b + kReduceChunk);
      // x_next = x: the particles stay where they are from one iteration to
      // the next (the work does not depend on the value).
      for (int d = 0; d < D; ++d) std::copy(P.x[d] + b, P.x[d] + e, P.x_next[d] + b);
      if constexpr (Kernel == ShiftKernel::fused) {
        bad[c] = g2p_range<D, Shape, Real, kGradient | kSeparationShift, true, false, false>(
                     P, G, V, q, key_of, b, e)
                     .bad;
      } else {
        if constexpr (Kernel == ShiftKernel::separate)
          if (advance_separation_shift<D, Shape, Real>(P, G, vstar, nullptr, Real(q.dt), b, e) != e)
            bad[c] = b;
        const auto r =
            g2p_range<D, Shape, Real, kGradient, true, false, false>(P, G, V, q, key_of, b, e);
        bad[c] = std::min(bad[c], r.bad);
      }
    });
    keep(P.sep_shift[0]);
    keep(P.L[0]);
    benchmark::ClobberMemory();
  }
  for (std::size_t b : bad)
    if (b != SIZE_MAX) {
      state.SkipWithError("gradient pass: stencil off the grid");
      return;
    }
  set_ns_per_particle(state, double(n));
  state.counters["threads"] = threads;
}

template <int D, class Shape, class Real>
void register_gradient_shift_case() {
  for (int threads : {1, 2})
    for (ShiftKernel k : {ShiftKernel::fused, ShiftKernel::separate, ShiftKernel::none}) {
      const char* kernel = k == ShiftKernel::fused      ? "fused"
                           : k == ShiftKernel::separate ? "separate"
                                                        : "none";
      const std::string name = std::string("g2p_gradient_shift/dim:") + std::to_string(D) +
                               "/shape:" + Shape::name + "/real:" + real_name<Real>() +
                               "/kernel:" + kernel + "/threads:" + std::to_string(threads);
      auto* b = benchmark::RegisterBenchmark(name.c_str(), [k, threads](benchmark::State& st) {
        if (k == ShiftKernel::fused)
          bm_gradient_shift<D, Shape, Real, ShiftKernel::fused>(st, threads);
        else if (k == ShiftKernel::separate)
          bm_gradient_shift<D, Shape, Real, ShiftKernel::separate>(st, threads);
        else
          bm_gradient_shift<D, Shape, Real, ShiftKernel::none>(st, threads);
      });
      configure(b->UseRealTime()->Unit(benchmark::kMillisecond), 0.1);
    }
}

}  // namespace

void register_separation_shift() {
  register_gradient_shift_case<2, LinearShape, double>();
  register_gradient_shift_case<2, GimpShape, double>();
  register_gradient_shift_case<2, GimpShape, float>();
  register_gradient_shift_case<3, GimpShape, double>();
}

}  // namespace mmpm::bench
