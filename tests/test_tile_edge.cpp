// The default tile edge (Stepper::setup_grid): the largest of 64, 32, 16,
// 8, 4 in 2D (8, 4 in 3D) that leaves every one of the 2^D colors at least
// 32 tiles, 20 at edge 64 (docs/performance.md "Tile edge of the whole
// step", "Tile edge 64 from 513^2 cells"); `tile` in [grid] overrides it,
// rounded up to a power of two of at least 4.
// Exact integers, no tolerance.
#include <gtest/gtest.h>

#include <string>

#include "scene/parse.hpp"
#include "solver/simulation.hpp"

namespace {

using namespace mmpm;

// A small block in a grid of cells x cells (2D) or cells^3 (3D).
int tile_edge(int dim, int cells, const std::string& tile = "") {
  const std::string c = std::to_string(cells);
  const std::string text =
      "[simulation]\ndimension = " + std::to_string(dim) +
      "\nend_time = 1.0\ncfl = 0.4\n\n[grid]\norigin = [0.0, 0.0" + (dim == 3 ? ", 0.0" : "") +
      "]\ncell = [1.0, 1.0" + (dim == 3 ? ", 1.0" : "") + "]\ncells = [" + c + ", " + c +
      (dim == 3 ? ", " + c : "") + "]\nshape = \"linear\"\n" + tile +
      "\n[[material]]\nname = \"a\"\ntype = \"isotropic\"\ndensity = 1.0\nE = 1.0\nnu = 0.3\n\n"
      "[[body]]\nmaterial = \"a\"\nshape = \"box\"\nmin = [2.0, 2.0" +
      (dim == 3 ? ", 2.0" : "") + "]\nmax = [6.0, 6.0" + (dim == 3 ? ", 6.0" : "") +
      "]\nparticles_per_cell = 1\n";
  return make_simulation(parse_scene_text(text, "tile.toml"))->tile_edge();
}

TEST(TileEdge, DefaultKeepsThirtyTwoTilesPerColor2D) {
  // 4 colors x 32 = 128 tiles: ceil(cells / T) >= 12 (11^2 = 121) at T <= 32.
  EXPECT_EQ(tile_edge(2, 40), 4);    // 10^2 = 100 tiles at 4, the smallest edge
  EXPECT_EQ(tile_edge(2, 88), 4);    // 11^2 at 8
  EXPECT_EQ(tile_edge(2, 89), 8);    // 12^2 at 8
  EXPECT_EQ(tile_edge(2, 254), 16);  // the 250k bench scenes: 16^2 at 16, 8^2 at 32
  EXPECT_EQ(tile_edge(2, 352), 16);  // 11^2 at 32
  EXPECT_EQ(tile_edge(2, 353), 32);  // 12^2 at 32
  // Edge 64 with 20 tiles per color, 80 tiles: ceil(cells / 64) >= 9.
  EXPECT_EQ(tile_edge(2, 504), 32);   // the 10^6 bench block: 8^2 at 64
  EXPECT_EQ(tile_edge(2, 512), 32);   // 8^2 at 64
  EXPECT_EQ(tile_edge(2, 513), 64);   // 9^2 at 64
  EXPECT_EQ(tile_edge(2, 705), 64);   // 12^2 at 64
  EXPECT_EQ(tile_edge(2, 2000), 64);  // never beyond 64
}

TEST(TileEdge, DefaultKeepsThirtyTwoTilesPerColor3D) {
  // 8 colors x 32 = 256 tiles: ceil(cells / T) >= 7 (6^3 = 216).
  EXPECT_EQ(tile_edge(3, 48), 4);   // 6^3 at 8
  EXPECT_EQ(tile_edge(3, 49), 8);   // 7^3 at 8
  EXPECT_EQ(tile_edge(3, 120), 8);  // never beyond 8
}

TEST(TileEdge, SceneKeyOverridesRoundedUpToAPowerOfTwo) {
  EXPECT_EQ(tile_edge(2, 254, "tile = 64\n"), 64);
  EXPECT_EQ(tile_edge(2, 254, "tile = 24\n"), 32);
  EXPECT_EQ(tile_edge(2, 254, "tile = 3\n"), 4);
  EXPECT_EQ(tile_edge(3, 40, "tile = 16\n"), 16);
}

}  // namespace
