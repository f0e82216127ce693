// Checks shared by the tests of the [simulation] switches that are hints to
// the hardware (prefetch_grid, prefetch_particles): on by default, written
// back by format_scene only when off, and without any effect on the results.
#pragma once

#include <gtest/gtest.h>
#include <omp.h>

#include <memory>
#include <string>
#include <utility>

#include "bitwise_same.hpp"
#include "scene/format.hpp"
#include "scene/parse.hpp"
#include "solver/simulation.hpp"

namespace mmpm_test {

// A scene resolved before the key existed (the scene a checkpoint stores)
// re-resolves to the same text, so the key is written only when off.
inline void expect_written_back_only_when_off(const std::string& scene_file, const std::string& key,
                                              bool mmpm::SimulationSpec::*member) {
  const mmpm::Scene on = mmpm::parse_scene_file(scene_file, {});
  EXPECT_TRUE(on.simulation.*member) << key;
  EXPECT_EQ(mmpm::format_scene(on).find(key), std::string::npos) << key;
  const mmpm::Scene off = mmpm::parse_scene_file(scene_file, {"simulation." + key + "=false"});
  EXPECT_FALSE(off.simulation.*member) << key;
  const std::string text = mmpm::format_scene(off);
  EXPECT_NE(text.find(key + " = false"), std::string::npos) << text;
  EXPECT_FALSE(mmpm::parse_scene_text(text, "resolved.toml", {}).simulation.*member) << key;
}

// On one and then two threads: `steps` steps of the two simulations that
// make_pair(what) returns (the switch on, the switch off), the whole state
// compared bit for bit every 10 steps and at the end. A null simulation is
// the caller's failure, already reported.
using SimulationPair =
    std::pair<std::unique_ptr<mmpm::Simulation>, std::unique_ptr<mmpm::Simulation>>;
template <class MakePair>
void expect_switch_changes_nothing(const std::string& label, int steps, const MakePair& make_pair) {
  const int saved = omp_get_max_threads();
  for (int threads : {1, 2}) {
    omp_set_num_threads(threads);
    const std::string what = label + ", " + std::to_string(threads) + " thread(s)";
    SimulationPair sims = make_pair(what);
    if (!sims.first || !sims.second) break;
    for (int s = 1; s <= steps; ++s) {
      sims.first->step();
      sims.second->step();
      if (s % 10 == 0 || s == steps)
        mmpm::testing::expect_bitwise_same(*sims.first, *sims.second,
                                           what + ", step " + std::to_string(s));
      if (::testing::Test::HasFailure()) break;
    }
    if (::testing::Test::HasFailure()) break;
  }
  omp_set_num_threads(saved);
}

}  // namespace mmpm_test
