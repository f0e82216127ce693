// uGIMP half-width columns only where the particles differ
// (solver/stepper_impl.hpp setup_particles): a scene whose bodies share one
// particle spacing keeps the value in the particle view and has no lp
// column (the transfers then build its lanes once per batch,
// kernels/window.hpp); bodies with different spacings keep the columns.
// That the windows are bitwise those of the columns is
// WindowBatch.SharedHalfWidthGivesTheColumnsWindows (test_window_batch.cpp).
// Scene: inputs/two_layer.toml (uGIMP, two bodies of 2 particles per cell),
// and the same with 3 per cell in its second body.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "io/checkpoint.hpp"
#include "scene/parse.hpp"
#include "solver/simulation.hpp"

namespace {

using namespace mmpm;

const std::string kInputs = std::string(MMPM_SOURCE_DIR) + "/inputs/";

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The two-layer scene; with `second_ppc` particles per cell in its second body.
std::unique_ptr<Simulation> two_layer(int second_ppc) {
  std::string text = read_text(kInputs + "two_layer.toml");
  const std::string key = "particles_per_cell = 2";
  const std::size_t first = text.find(key);
  const std::size_t second = text.find(key, first + key.size());
  EXPECT_NE(second, std::string::npos);
  if (second == std::string::npos) return nullptr;
  text.replace(second, key.size(), "particles_per_cell = " + std::to_string(second_ppc));
  return make_simulation(parse_scene_text(text, "two_layer.toml", {}));
}

bool has_blob(const std::vector<io::Blob>& blobs, const std::string& name) {
  return std::any_of(blobs.begin(), blobs.end(), [&](const io::Blob& b) { return b.name == name; });
}

TEST(HalfWidth, OneSpacingNeedsNoColumn) {
  auto sim = two_layer(2);
  ASSERT_TRUE(sim);
  const auto blobs = sim->save_state();
  EXPECT_TRUE(has_blob(blobs, "p.x0x"));  // the state holds the particle columns
  EXPECT_FALSE(has_blob(blobs, "p.lpx"));
  EXPECT_FALSE(has_blob(blobs, "p.lpy"));
}

// Two spacings: the columns exist, and the run stays finite and moves (the
// transfers read them; a half-width of 0 would divide by zero).
TEST(HalfWidth, TwoSpacingsKeepTheColumns) {
  auto sim = two_layer(3);
  ASSERT_TRUE(sim);
  const auto before = sim->save_state();
  EXPECT_TRUE(has_blob(before, "p.lpx"));
  EXPECT_TRUE(has_blob(before, "p.lpy"));
  for (int k = 0; k < 20; ++k) sim->step();
  const Energies e = sim->energies();
  EXPECT_TRUE(std::isfinite(e.kinetic) && std::isfinite(e.strain));
  EXPECT_GT(e.kinetic + e.strain, 0.0);
}

}  // namespace
