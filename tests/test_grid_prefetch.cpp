// [simulation] prefetch_grid (default true): the 2D transfers request the
// grid lines their windows reach next (kernels/grid_prefetch.hpp). A request
// is a hint, so runs with and without it must agree bit for bit, on one and
// two threads, for every 2D kernel that requests: the packed linear P2G and
// G2P (one and two fields, double and float), the windowed uGIMP transfers
// with the multimaterial arrays, and the grouped scatter of cubic B-splines.
// The solver requests only on grids of kPrefetchMinGridBytes and more, so
// the scenes here run on grids enlarged past the bodies (the same
// particles). The key is written back by format_scene only when off, so a
// scene resolved before it existed (a checkpoint's) re-resolves to the same
// text.
#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "kernels/grid_prefetch.hpp"
#include "kernels/shape.hpp"
#include "kernels/window.hpp"
#include "scene/format.hpp"
#include "scene/parse.hpp"
#include "solver/simulation.hpp"
#include "solver/stepper.hpp"
#include "switch_checks.hpp"

namespace {

using namespace mmpm;

const std::string kInputs = std::string(MMPM_SOURCE_DIR) + "/inputs/";

std::unique_ptr<Simulation> make(const std::string& file, std::vector<std::string> sets, bool on) {
  sets.push_back(std::string("simulation.prefetch_grid=") + (on ? "true" : "false"));
  return make_simulation(parse_scene_file(kInputs + file, sets));
}

void expect_same_with_and_without(const std::string& file, const std::vector<std::string>& sets,
                                  int steps) {
  mmpm_test::expect_switch_changes_nothing(
      file + " " + ::testing::PrintToString(sets), steps, [&](const std::string&) {
        return mmpm_test::SimulationPair(make(file, sets, true), make(file, sets, false));
      });
}

TEST(GridPrefetch, TwoLayerInterfaceBitwise) {
  // uGIMP windows, two fields, mx and Omega scattered with the forces.
  expect_same_with_and_without("two_layer.toml", {"grid.cells=[120, 120]"}, 40);
}

TEST(GridPrefetch, PackedLinearBitwise) {
  // The packed 2D linear kernels (MUSL's three passes), two fields in contact.
  const std::string big = "grid.cells=[150, 150]";
  expect_same_with_and_without("shear_blocks.toml", {big, "grid.shape=\"linear\""}, 40);
  expect_same_with_and_without(
      "shear_blocks.toml", {big, "grid.shape=\"linear\"", "simulation.precision=\"float\""}, 40);
  expect_same_with_and_without("shear_blocks.toml",
                               {big, "grid.shape=\"linear\"", "simulation.scheme=\"USL\""}, 40);
}

TEST(GridPrefetch, CubicBsplinesBitwise) {
  // The widest 2D window (4 x 4 nodes).
  expect_same_with_and_without("collision.toml",
                               {"grid.cells=[200, 100]", "grid.shape=\"bspline3\""}, 30);
}

TEST(GridPrefetch, OnlyOnGridsPastTheL2) {
  auto on = [](std::vector<std::string> sets) {
    auto sim = make_simulation(parse_scene_file(kInputs + "two_layer.toml", sets));
    auto* stepper = dynamic_cast<Stepper<2, GimpShape, double>*>(sim.get());
    EXPECT_NE(stepper, nullptr);
    return stepper && stepper->prefetch_grid();
  };
  // 41 x 89 nodes, 2 fields, 9 arrays of doubles: 0.50 MiB.
  EXPECT_FALSE(on({}));
  // 121 x 121 nodes: 2.0 MiB.
  EXPECT_TRUE(on({"grid.cells=[120, 120]"}));
  EXPECT_FALSE(on({"grid.cells=[120, 120]", "simulation.prefetch_grid=false"}));
}

TEST(GridPrefetch, WrittenBackOnlyWhenOff) {
  mmpm_test::expect_written_back_only_when_off(kInputs + "two_layer.toml", "prefetch_grid",
                                               &SimulationSpec::prefetch_grid);
}

TEST(GridPrefetch, OnlyIn2D) {
  using W2 = Window<2, LinearShape, double>;
  using W3 = Window<3, LinearShape, double>;
  EXPECT_TRUE(GridLinesAhead<W2>(true, typename W2::Offsets{}).on());
  EXPECT_FALSE(GridLinesAhead<W2>(false, typename W2::Offsets{}).on());
  EXPECT_FALSE(GridLinesAhead<W3>(true, typename W3::Offsets{}).on());
}

TEST(GridPrefetch, ArrayCountsAndMissingArrays) {
  // The counts are template arguments (kernels/grid_prefetch.hpp): a
  // request reads every address of its count. A pass missing one of its
  // arrays requests the others (the missing one takes another's address);
  // a pass missing all of them requests nothing.
  using W = Window<2, LinearShape, double>;
  static_assert(scatter_array_count<kMassMomentum | kForce, 2>() == 5);
  static_assert(scatter_array_count<kMomentumOnly, 2>() == 2);
  static_assert(scatter_array_count<kMultimaterial | kDomainGradient, 2>() == 5);
  static_assert(gather_read_count<kUpdateMotion, 2>() == 4);                      // vel, dvel
  static_assert(gather_read_count<0, 3>() == 3);                                  // vel alone
  static_assert(gather_write_count<kUpdateMotion | kScatterMomentum, 3>() == 3);  // MUSL's p
  static_assert(gather_write_count<kUpdateMotion, 2>() == 0);
  std::vector<double> storage(16 * 64);
  double* next = storage.data();
  auto array = [&] { return (next += 64) - 64; };
  GridView<2, double> G;
  G.m = array();
  G.vol = array();
  for (int d = 0; d < 2; ++d) G.p[d] = array(), G.f[d] = array(), G.mx[d] = array();
  GridVelocity<2, double> V;
  for (int d = 0; d < 2; ++d) V.vel[d] = array(), V.dvel[d] = array();
  const W::Offsets rows{0, 8};

  auto scatter = [&](bool on) {
    auto ahead = scatter_lines_ahead<kMassMomentum | kForce, W>(on, rows, G);
    ahead.window(3);  // a hint: never faults, never writes
    return ahead.on();
  };
  EXPECT_TRUE(scatter(true));
  EXPECT_FALSE(scatter(false));
  G.f[1] = nullptr;
  EXPECT_TRUE(scatter(true));
  G.m = G.p[0] = G.p[1] = G.f[0] = nullptr;
  EXPECT_FALSE(scatter(true));
  // The multimaterial arrays, g missing (this grid has none): on.
  EXPECT_TRUE((scatter_lines_ahead<kMultimaterial | kDomainGradient, W>(true, rows, G).on()));

  constexpr unsigned kMusl = kUpdateMotion | kScatterMomentum;
  EXPECT_TRUE((gather_lines_ahead<kMusl, W>(true, rows, G, V).on()));  // p missing
  V.vel = {};
  V.dvel = {};
  EXPECT_FALSE((gather_lines_ahead<kUpdateMotion, W>(true, rows, G, V).on()));
}

}  // namespace
