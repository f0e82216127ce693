// [simulation] particle_order: the particles are stored tile by tile, color
// by color ("color", the default: kernels/binning.hpp TileLayout) or in
// plain tile order ("tile"). Every colored pass visits the same tiles in
// the same order either way and a tile's particles keep their order, so
// every node receives the same sums in the same order: the particle fields
// (in seed order) must come out bitwise the same. Only sums over particles
// in storage order differ (energies, external work): to round-off,
// relative 1e-12 here.
//
// Also: the slot numbering itself (a bijection with the tiles, each color
// one contiguous run of slots in tile order) and the particle ranges the
// loops that are not colored give each thread.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "kernels/binning.hpp"
#include "scene/parse.hpp"
#include "solver/simulation.hpp"
#include "validation_util.hpp"

namespace {

using namespace mmpm;

template <int D>
void check_slots(const std::array<int, 3>& cells, int edge) {
  SCOPED_TRACE(::testing::Message() << D << "D, cells " << cells[0] << " x " << cells[1] << " x "
                                    << cells[2] << ", tile edge " << edge);
  TileLayout<D> color, tile;
  color.setup(edge, cells, true);
  tile.setup(edge, cells, false);
  std::vector<int> seen(color.tile_count, 0);
  int previous_color = 0;
  std::uint32_t previous_tile = 0;
  for (std::uint32_t s = 0; s < color.tile_count; ++s) {
    const std::uint32_t t = color.tile_of_slot(s);
    ASSERT_LT(t, color.tile_count) << "slot " << s;
    ++seen[t];
    EXPECT_EQ(color.slot_of_tile(t), s);
    // Colors in order, each one run of slots, its tiles in tile order.
    const int c = color.color(t);
    EXPECT_EQ(color.color_of_slot(s), c);
    EXPECT_GE(c, previous_color) << "slot " << s;
    if (s > 0 && c == previous_color) {
      EXPECT_GT(t, previous_tile) << "slot " << s;
    }
    EXPECT_GE(s, color.color_begin[std::size_t(c)]);
    EXPECT_LT(s, color.color_begin[std::size_t(c) + 1]);
    previous_color = c, previous_tile = t;
    // Tile order: the slot is the tile.
    EXPECT_EQ(tile.slot_of_tile(t), t);
    EXPECT_EQ(tile.tile_of_slot(t), t);
  }
  EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](int k) { return k == 1; }));
  // A cell's key names its tile through the slot, in both orders.
  for (int z = 0; z < (D == 3 ? cells[2] : 1); ++z)
    for (int y = 0; y < cells[1]; ++y)
      for (int x = 0; x < cells[0]; ++x) {
        const std::size_t t =
            color.tile_index(x >> color.shift, y >> color.shift, D == 3 ? z >> color.shift : 0);
        ASSERT_EQ(color.tile_of_key(color.key({x, y, z})), t);
        ASSERT_EQ(tile.tile_of_key(tile.key({x, y, z})), t);
      }
}

// Odd and even tile counts (a color of the odd index is one tile shorter),
// a single tile along a direction (its odd colors are empty), partial tiles.
TEST(ParticleOrder, SlotsNumberEveryTileOnceColorByColor) {
  check_slots<2>({64, 64, 1}, 8);
  check_slots<2>({37, 29, 1}, 4);
  check_slots<2>({5, 70, 1}, 8);
  check_slots<3>({16, 16, 16}, 4);
  check_slots<3>({28, 28, 26}, 8);
  check_slots<3>({9, 21, 4}, 4);
}

// thread_ranges: for 1-4 threads the ranges of all threads partition the
// particles; stored color by color, a thread's ranges are exactly the
// particles of its colored shares (so every pass gives it the same ones).
TEST(ParticleOrder, ThreadRangesAreTheColoredShares) {
  for (const bool color_major : {true, false}) {
    TileLayout<2> layout;
    layout.setup(4, {37, 29, 1}, color_major);
    std::vector<std::uint32_t> keys;
    for (int y = 0; y < 29; ++y)
      for (int x = 0; x < 37; ++x)
        for (int k = 0; k < 1 + (x * 7 + y * 3) % 5; ++k) keys.push_back(layout.key({x, y, 0}));
    std::sort(keys.begin(), keys.end());
    TileSchedule schedule;
    schedule.build(layout, keys.data(), keys.size());
    const std::size_t n = keys.size();
    for (std::size_t threads = 1; threads <= 4; ++threads) {
      std::vector<int> owner(n, -1);
      for (std::size_t i = 0; i < threads; ++i) {
        const TileSchedule::Ranges r = schedule.thread_ranges(threads, i);
        for (std::size_t k = 0; k < r.count; ++k)
          for (std::size_t p = r.range[k].first; p < r.range[k].second; ++p) {
            ASSERT_EQ(owner[p], -1) << "particle " << p << " in two ranges";
            owner[p] = int(i);
          }
      }
      for (std::size_t p = 0; p < n; ++p) ASSERT_NE(owner[p], -1) << "particle " << p;
      if (!color_major || threads < 2) continue;
      for (std::size_t c = 0; c < 4; ++c)
        for (std::size_t i = 0; i < threads; ++i) {
          const auto [first, last] = schedule.share(c, threads, i);
          for (std::size_t k = first; k < last; ++k) {
            const std::uint32_t s = schedule.tiles[c][k];
            for (std::size_t p = schedule.begin[s]; p < schedule.begin[s + 1]; ++p)
              ASSERT_EQ(owner[p], int(i)) << "color " << c << ", " << threads << " threads";
          }
        }
    }
  }
}

const std::string kInputs = std::string(MMPM_SOURCE_DIR) + "/inputs/";

Scene with_order(const std::string& file, std::vector<std::string> sets, const char* order) {
  sets.push_back(std::string("simulation.particle_order=\"") + order + "\"");
  return parse_scene_file(kInputs + file, sets);
}

void expect_same(const Simulation& a, const Simulation& b, const std::string& what) {
  for (const char* name : {"position", "velocity", "stress", "volume"})
    EXPECT_EQ(mmpm::testing::differing_values(a, b, name), 0u)
        << what << " " << name << ": values differing";
  const Energies e = a.energies(), g = b.energies();
  const double scale = std::abs(e.kinetic) + std::abs(e.strain) + std::abs(e.interface) +
                       std::abs(e.external_work) + 1e-300;
  EXPECT_NEAR(e.kinetic, g.kinetic, 1e-12 * scale) << what;
  EXPECT_NEAR(e.strain, g.strain, 1e-12 * scale) << what;
  EXPECT_EQ(e.interface, g.interface) << what;  // a sum over nodes
  EXPECT_NEAR(e.external_work, g.external_work, 1e-12 * scale) << what;
  const auto ra = a.reactions(), rb = b.reactions();
  ASSERT_EQ(ra.size(), rb.size()) << what;
  for (std::size_t r = 0; r < ra.size(); ++r)
    for (int d = 0; d < 3; ++d) EXPECT_EQ(ra[r].force[d], rb[r].force[d]) << what << " " << r;
}

// Steps both orders side by side, comparing every `check` steps.
void run_both(const std::string& file, const std::vector<std::string>& sets, int steps, int check) {
  auto color = make_simulation(with_order(file, sets, "color"));
  auto tile = make_simulation(with_order(file, sets, "tile"));
  for (int s = 1; s <= steps; ++s) {
    color->step();
    tile->step();
    if (s % check == 0 || s == steps) {
      expect_same(*color, *tile, file + " step " + std::to_string(s));
      if (::testing::Test::HasFailure()) return;
    }
  }
}

// Two blocks colliding with tiles of 4 cells: particles change tile, the
// columns are re-sorted (contact, two fields).
TEST(ParticleOrder, CollisionWithResortsSameParticles) {
  run_both("collision.toml", {"grid.tile=4"}, 120, 30);
}

// Imperfect interface, multimaterial fields scattered apart (the node box
// and reach-tile bookkeeping works on slots) and with the first P2G.
TEST(ParticleOrder, TwoLayerInterfaceSameParticles) {
  run_both("two_layer.toml", {}, 60, 20);
  run_both("two_layer.toml", {"simulation.mm_fields_share=0.0"}, 30, 30);
}

// USL (the G2P and constitutive passes that are not colored) with a
// traction ramp (update_tractions); rigid incline under gravity; 3D.
TEST(ParticleOrder, OtherPassesAndSchemesSameParticles) {
  run_both("series_bars.toml", {"simulation.scheme=\"USL\""}, 40, 20);
  run_both("series_bars.toml", {}, 40, 20);
  run_both("incline_block.toml", {}, 60, 30);
  run_both("sphere_in_cube.toml", {}, 20, 10);
}

}  // namespace
