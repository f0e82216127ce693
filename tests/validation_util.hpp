// Helpers for validation tests that drive the solver through the
// Simulation interface (scene text in, particle fields out).
#pragma once

#include <omp.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "scene/parse.hpp"
#include "solver/simulation.hpp"

namespace mmpm::testing {

// How many values of particle field `name` differ bit for bit between two
// runs (SIZE_MAX: the fields differ in size).
inline std::size_t differing_values(const Simulation& a, const Simulation& b,
                                    const std::string& name) {
  const auto x = a.particle_field(name).values, y = b.particle_field(name).values;
  if (x.size() != y.size()) return SIZE_MAX;
  std::size_t differ = 0;
  for (std::size_t i = 0; i < x.size(); ++i)
    if (std::memcmp(&x[i], &y[i], sizeof(double)) != 0) ++differ;
  return differ;
}

inline std::unique_ptr<Simulation> make_from_text(const std::string& toml,
                                                  const std::vector<std::string>& overrides = {}) {
  return make_simulation(parse_scene_text(toml, "test.toml", overrides));
}

// Steps until the simulated time reaches t_end (the scene's end_time is not consulted).
inline void run_until(Simulation& sim, double t_end) {
  while (sim.time() < t_end - 1e-9 * sim.dt()) sim.step();
}

struct Column {
  std::vector<double> values;
  int components = 1;
  double at(std::size_t p, int c = 0) const {
    return values[p * std::size_t(components) + std::size_t(c)];
  }
};

inline Column field(const Simulation& sim, const std::string& name) {
  auto f = sim.particle_field(name);
  return {std::move(f.values), f.components};
}

}  // namespace mmpm::testing

// Long validation cases (refinement studies) run only under `ctest -L long`
// (which sets MMPM_LONG=1); in CI they report as skipped.
#define MMPM_LONG_TEST()                                                           \
  do {                                                                             \
    if (!std::getenv("MMPM_LONG")) GTEST_SKIP() << "long test: run ctest -L long"; \
  } while (0)

// A validation case the solver does not pass yet: it reports as skipped
// with the reason (and the measured values) unless MMPM_KNOWN=1, which runs
// it and shows the failure. Each one is listed as open in the issue notes.
#define MMPM_KNOWN_LIMITATION(why)                                               \
  do {                                                                           \
    if (!std::getenv("MMPM_KNOWN")) GTEST_SKIP() << "known limitation: " << why; \
  } while (0)
