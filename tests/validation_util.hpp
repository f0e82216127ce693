// Helpers for validation tests that drive the solver through the
// Simulation interface (scene text in, particle fields out).
#pragma once

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
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

// `text` with the part from the first `begin` up to the first `end` after it
// replaced by `with`: a shipped scene with one of its blocks swapped (say its
// [[interaction]], up to the next [[boundary]]). Throws when either is missing.
inline std::string replace_between(std::string text, const std::string& begin,
                                   const std::string& end, const std::string& with) {
  const std::size_t from = text.find(begin);
  const std::size_t to = from == std::string::npos ? from : text.find(end, from);
  if (to == std::string::npos)
    throw std::runtime_error("replace_between: '" + begin + "' ... '" + end + "' not found");
  return text.replace(from, to - from, with);
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

// The mean of displacement component c over the particles seeded within
// `within` of `seed` along `axis` (the seed: position − displacement), as a
// row or a column of a box of particles; NaN when there is none.
inline double seeded_mean_displacement(const Simulation& sim, int axis, double seed, double within,
                                       int c) {
  const Column x = field(sim, "position"), u = field(sim, "displacement");
  double sum = 0, count = 0;
  for (std::size_t p = 0; p < sim.particle_count(); ++p)
    if (std::abs(x.at(p, axis) - u.at(p, axis) - seed) < within) sum += u.at(p, c), count += 1;
  return sum / count;
}

// The row of particles seeded at height y0 (2D: y of position − displacement).
inline double row_mean_displacement(const Simulation& sim, double y0, int c) {
  return seeded_mean_displacement(sim, 1, y0, 1e-6, c);
}

// A model on mirror planes against the whole body it mirrors: the largest
// stress and velocity of the whole body's particles with a twin in the half
// model (the same seed position, x - u), and the largest differences
// between twins. `twins`: how many of the half model's particles found one.
struct HalfWholeDifference {
  double s_max = 0, s_diff = 0, v_max = 0, v_diff = 0;
  std::size_t twins = 0;
};

inline HalfWholeDifference half_against_whole(const Simulation& half, const Simulation& whole,
                                              int dim) {
  const Column hx = field(half, "position"), hu = field(half, "displacement"),
               hs = field(half, "stress"), hv = field(half, "velocity");
  const Column wx = field(whole, "position"), wu = field(whole, "displacement"),
               ws = field(whole, "stress"), wv = field(whole, "velocity");
  // Seeds in 1/16 mm: (x0, y0 + 1000 z0).
  auto key = [&](const Column& x, const Column& u, std::size_t p) {
    const long z = dim == 3 ? std::lround(16 * (x.at(p, 2) - u.at(p, 2))) : 0;
    return std::make_pair(std::lround(16 * (x.at(p, 0) - u.at(p, 0))),
                          std::lround(16 * (x.at(p, 1) - u.at(p, 1))) + 1000 * z);
  };
  std::map<std::pair<long, long>, std::size_t> by_seed;
  for (std::size_t p = 0; p < whole.particle_count(); ++p) by_seed[key(wx, wu, p)] = p;
  HalfWholeDifference r;
  for (std::size_t p = 0; p < half.particle_count(); ++p) {
    const auto it = by_seed.find(key(hx, hu, p));
    if (it == by_seed.end()) continue;
    ++r.twins;
    const std::size_t q = it->second;
    for (int k = 0; k < hs.components; ++k) {
      r.s_max = std::max(r.s_max, std::abs(ws.at(q, k)));
      r.s_diff = std::max(r.s_diff, std::abs(hs.at(p, k) - ws.at(q, k)));
    }
    for (int d = 0; d < dim; ++d) {
      r.v_max = std::max(r.v_max, std::abs(wv.at(q, d)));
      r.v_diff = std::max(r.v_diff, std::abs(hv.at(p, d) - wv.at(q, d)));
    }
  }
  return r;
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
