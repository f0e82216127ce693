// Particle generation from bodies: lattice filling, overlap replacement,
// rotation about a pivot, traction sharing on a face.
#include <gtest/gtest.h>

#include <algorithm>

#include "model/bodies.hpp"
#include "scene/parse.hpp"

namespace mmpm {
namespace {

const char* kBase = R"(
[simulation]
dimension = 2
end_time = 1.0
[grid]
origin = [-4.0, -4.0]
cell = [0.5, 0.5]
cells = [16, 16]
shape = "linear"
[[material]]
name = "a"
type = "isotropic"
density = 1.0
E = 100.0
nu = 0.3
)";

std::pair<Vec3, Vec3> extent(const ParticleSeeds& s) {
  Vec3 lo{1e9, 1e9, 0}, hi{-1e9, -1e9, 0};
  for (const auto& x : s.x)
    for (int d = 0; d < 2; ++d) lo[d] = std::min(lo[d], x[d]), hi[d] = std::max(hi[d], x[d]);
  return {lo, hi};
}

// A 2 x 1 box turned 90 degrees about the pivot (0, 0) occupies [-1, 0] x [0, 2]:
// particles (2x2 per 0.5 mm cell) from -0.875 to -0.125 in x and 0.125 to 1.875 in y.
TEST(Bodies, RotationAboutPivot) {
  const std::string text =
      std::string(kBase) +
      "[[body]]\nmaterial = \"a\"\nshape = \"box\"\nmin = [0.0, 0.0]\nmax = [2.0, 1.0]\n"
      "rotate = 90.0\npivot = [0.0, 0.0]\n";
  const ParticleSeeds s = make_particles(parse_scene_text(text, "pivot.toml"));
  EXPECT_EQ(s.x.size(), 32u);  // 2 mm^2 at 16 particles per mm^2
  const auto [lo, hi] = extent(s);
  EXPECT_NEAR(lo[0], -0.875, 1e-12);
  EXPECT_NEAR(hi[0], -0.125, 1e-12);
  EXPECT_NEAR(lo[1], 0.125, 1e-12);
  EXPECT_NEAR(hi[1], 1.875, 1e-12);
}

// Without a pivot the box turns about its own centre (1, 0.5): [0.5, 1.5] x [-0.5, 1.5].
TEST(Bodies, RotationAboutOwnCentre) {
  const std::string text =
      std::string(kBase) +
      "[[body]]\nmaterial = \"a\"\nshape = \"box\"\nmin = [0.0, 0.0]\nmax = [2.0, 1.0]\n"
      "rotate = 90.0\n";
  const ParticleSeeds s = make_particles(parse_scene_text(text, "centre.toml"));
  const auto [lo, hi] = extent(s);
  EXPECT_NEAR(lo[0], 0.625, 1e-12);
  EXPECT_NEAR(hi[0], 1.375, 1e-12);
  EXPECT_NEAR(lo[1], -0.375, 1e-12);
  EXPECT_NEAR(hi[1], 1.375, 1e-12);
}

// The later body replaces the earlier one's particles; the traction force on
// a face sums to traction x face length x thickness.
TEST(Bodies, OverlapReplacementAndTractionTotal) {
  const std::string text =
      std::string(kBase) +
      "[[material]]\nname = \"b\"\ntype = \"isotropic\"\ndensity = 1.0\nE = 100.0\nnu = 0.3\n"
      "[[body]]\nname = \"matrix\"\nmaterial = \"a\"\nshape = \"box\"\nmin = [0.0, 0.0]\nmax = "
      "[2.0, 2.0]\n"
      "[[body]]\nmaterial = \"b\"\nshape = \"box\"\nmin = [0.5, 0.5]\nmax = [1.5, 1.5]\n"
      "[[load]]\nkind = \"traction\"\nwhere = { body = \"matrix\", face = \"y_max\" }\n"
      "traction = [0.0, 3.0]\n";
  const ParticleSeeds s = make_particles(parse_scene_text(text, "overlap.toml"));
  EXPECT_EQ(s.x.size(), 64u);
  EXPECT_EQ(std::count(s.material.begin(), s.material.end(), 1), 16);
  double fy = 0;
  for (const auto& f : s.traction_force) fy += f[1];
  EXPECT_NEAR(fy, 3.0 * 2.0 * 1.0, 1e-12);
}

}  // namespace
}  // namespace mmpm
