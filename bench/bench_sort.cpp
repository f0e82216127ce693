// Sort/bin cost per particle: what Stepper::sort_particles does (tile keys,
// stable counting sort, permutation of every particle column, tile ranges and
// color lists), for the solver's gimp column set. Two inputs: particles
// already in tile order (a re-sort when nothing moved: the permutation is the
// identity but every column is still copied twice) and a random order (the
// first sort of a scene, or after heavy mixing). The random input is restored
// before each iteration, outside the manual timer. Counters split the parts.
// The cost of re-sorting every step vs every k steps inside a whole step is
// measured in bench_step.cpp (step/.../sort_every:k).
#include <chrono>
#include <numeric>
#include <random>

#include "bench/bench_common.hpp"

namespace mmpm::bench {
namespace {

using Clock = std::chrono::steady_clock;

template <int D, class Real>
struct SortFixture {
  ParticleSet<D, Real> S;
  GridSet<D, Real> grid;
  Binning<D, Real> bins;
  std::vector<std::vector<Real>> shuffled_reals;
  std::vector<std::vector<std::uint8_t>> shuffled_bytes;
  std::vector<std::uint32_t> shuffled_id;
};

template <int D, class Real>
SortFixture<D, Real>& sort_fixture() {
  using F = SortFixture<D, Real>;
  return cached_fixture<F>(0, [] {
    auto fx = std::make_unique<F>();
    BlockSpec b;
    b.gimp = true;
    for (int d = 0; d < D; ++d) b.lo[d] = 2, b.hi[d] = D == 2 ? 252 : 34;
    make_block<D, Real>(fx->S, b);
    fx->grid.setup(D == 2 ? std::array<int, 3>{254, 254, 1} : std::array<int, 3>{36, 36, 36}, 1,
                   false, false);
    fx->bins.template setup<GimpShape>(kDefaultTile<D>, fx->grid.G);
    // A random order of the same particles, kept as the restore source.
    const std::size_t n = fx->S.P.n;
    std::vector<std::uint32_t> order(n);
    std::iota(order.begin(), order.end(), 0u);
    std::mt19937 rng(12345);
    std::shuffle(order.begin(), order.end(), rng);
    for (auto& col : fx->S.reals) {
      std::vector<Real> v(n);
      for (std::size_t i = 0; i < n; ++i) v[i] = col[order[i]];
      fx->shuffled_reals.push_back(std::move(v));
    }
    for (auto& col : fx->S.bytes) {
      std::vector<std::uint8_t> v(n);
      for (std::size_t i = 0; i < n; ++i) v[i] = col[order[i]];
      fx->shuffled_bytes.push_back(std::move(v));
    }
    fx->shuffled_id = order;  // the seed index travels with the particle
    return fx;
  });
}

template <int D, class Real>
void restore_shuffled(SortFixture<D, Real>& fx) {
  const std::size_t n = fx.S.P.n;
  for (std::size_t c = 0; c < fx.S.reals.size(); ++c)
    std::memcpy(fx.S.reals[c].data(), fx.shuffled_reals[c].data(), n * sizeof(Real));
  for (std::size_t c = 0; c < fx.S.bytes.size(); ++c)
    std::memcpy(fx.S.bytes[c].data(), fx.shuffled_bytes[c].data(), n);
  std::memcpy(fx.S.id.data(), fx.shuffled_id.data(), n * sizeof(std::uint32_t));
}

template <int D, class Real>
void bm_sort(benchmark::State& state, bool shuffled, int threads) {
  use_threads(threads);
  auto& fx = sort_fixture<D, Real>();
  if (!shuffled) {  // start from tile order
    restore_shuffled(fx);
    fx.bins.sort(fx.S, fx.grid.G);
  }
  double t_keys = 0, t_count = 0, t_perm = 0, t_ranges = 0;
  const std::size_t n = fx.S.P.n;
  for (auto _ : state) {
    if (shuffled) restore_shuffled(fx);
    const auto t0 = Clock::now();
    fx.bins.compute_keys(fx.S, fx.grid.G);
    const auto t1 = Clock::now();
    fx.bins.count(fx.S);
    const auto t2 = Clock::now();
    fx.bins.permute_keys(fx.S);
    const auto t3 = Clock::now();
    fx.bins.rebuild_ranges(fx.S);  // the new order's ranges say where the columns go
    const auto t3b = Clock::now();
    fx.bins.permute_columns(fx.S);
    const auto t4 = Clock::now();
    keep(fx.bins.schedule.begin.data());
    benchmark::ClobberMemory();
    t_keys += std::chrono::duration<double>(t1 - t0).count();
    t_count += std::chrono::duration<double>(t2 - t1).count();
    t_perm += std::chrono::duration<double>((t3 - t2) + (t4 - t3b)).count();
    t_ranges += std::chrono::duration<double>(t3b - t3).count();
    state.SetIterationTime(std::chrono::duration<double>(t4 - t0).count());
  }
  // Sorted means non-decreasing keys.
  for (std::size_t p = 1; p < n; ++p)
    if (fx.S.P.key[p] < fx.S.P.key[p - 1]) {
      state.SkipWithError("keys not sorted");
      return;
    }
  const double per = 1e9 / (double(state.iterations()) * double(n));
  set_ns_per_particle(state, double(n));
  state.counters["keys_ns_per_particle"] = t_keys * per;
  state.counters["counting_sort_ns_per_particle"] = t_count * per;
  state.counters["permute_ns_per_particle"] = t_perm * per;
  state.counters["ranges_ns_per_particle"] = t_ranges * per;
  state.counters["columns"] = double(fx.S.reals.size() + fx.S.bytes.size() + 1);
  // Permutation traffic: every column read (gathered) and written twice (scratch, copy back).
  set_rate(state, "permute_GBps", 3.0 * double(n) * double(fx.S.bytes_per_particle()));
  state.counters["threads"] = threads;
}

template <int D, class Real>
void register_case() {
  for (bool shuffled : {false, true})
    for (int threads : {1, 2}) {
      const std::string name =
          "sort/dim:" + std::to_string(D) + "/shape:gimp/real:" + real_name<Real>() +
          "/order:" + (shuffled ? "random" : "sorted") + "/threads:" + std::to_string(threads);
      auto* b = benchmark::RegisterBenchmark(
          name.c_str(),
          [shuffled, threads](benchmark::State& st) { bm_sort<D, Real>(st, shuffled, threads); });
      configure(b->UseManualTime()->Unit(benchmark::kMillisecond), 0.1);
    }
}

}  // namespace

void register_sort() {
  register_case<2, double>();
  register_case<3, double>();
}

}  // namespace mmpm::bench
