// mmpm_bench: registers the benchmark families in a fixed order and runs them.
// bench/run passes --benchmark_format=json --benchmark_out=bench/results.json
// and the context (git commit, load average) with --benchmark_context.
#include <benchmark/benchmark.h>
#include <omp.h>

#include <cstring>
#include <vector>

#include "bench/bench_common.hpp"

int main(int argc, char** argv) {
  // --quick: half the minimum times (a fast look; bench/run --quick).
  std::vector<char*> args;
  for (int i = 0; i < argc; ++i) {
    if (std::strcmp(argv[i], "--quick") == 0) {
      mmpm::bench::time_scale() = 0.5;
    } else {
      args.push_back(argv[i]);
    }
  }
  argc = int(args.size());
  args.push_back(nullptr);
  argv = args.data();
  mmpm::bench::register_p2g();
  mmpm::bench::register_g2p();
  mmpm::bench::register_separation_shift();
  mmpm::bench::register_grid();
  mmpm::bench::register_multimaterial();
  mmpm::bench::register_sort();
  mmpm::bench::register_step();
  mmpm::bench::register_step_pair();
  mmpm::bench::register_team();
  mmpm::bench::register_step_ab();
  mmpm::bench::register_mm_scene();
  mmpm::bench::register_scaling();
  mmpm::bench::register_seed();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::AddCustomContext("omp_max_threads", std::to_string(omp_get_max_threads()));
#ifdef MMPM_FAST_DEV
  benchmark::AddCustomContext("mmpm_fast_dev", "ON");
#else
  benchmark::AddCustomContext("mmpm_fast_dev", "OFF");
#endif
#ifdef NDEBUG
  benchmark::AddCustomContext("mmpm_asserts", "off");
#else
  benchmark::AddCustomContext("mmpm_asserts", "on");
#endif
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
