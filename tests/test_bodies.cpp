// Particle generation from bodies: lattice filling, overlap replacement,
// rotation about a pivot, traction sharing on a face.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <sstream>

#include "model/bodies.hpp"
#include "scene/parse.hpp"

namespace mmpm {
namespace {

// The one material of every scene below.
const std::string kMaterialA = R"([[material]]
name = "a"
type = "isotropic"
density = 1.0
E = 100.0
nu = 0.3
)";

const std::string kBase = R"(
[simulation]
dimension = 2
end_time = 1.0
[grid]
origin = [-4.0, -4.0]
cell = [0.5, 0.5]
cells = [16, 16]
shape = "linear"
)" + kMaterialA;

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

// Overlap replacement against its definition, on many overlapping bodies:
// the particles are the lattice points of each body (every cell of the grid
// tried, in make_particles' loop order) that no later body contains, body
// after body. make_particles tests only the particles in the cells of a
// later body's bounding box (seeding was O(particles x bodies) before), so
// this also checks that the box holds every point the body contains:
// rotated boxes with and without a pivot, disks, polygons, clip boxes,
// spheres, cylinders, 1-3 particles per cell. Exact: same points, same
// order, same bodies.
// `replaced`: how many points a later body took over.
std::vector<std::pair<Vec3, int>> seeds_by_definition(const Scene& scene, std::size_t& replaced) {
  const int dim = scene.simulation.dimension;
  const GridSpec& g = scene.grid;
  std::vector<std::pair<Vec3, int>> kept;
  for (std::size_t b = 0; b < scene.bodies.size(); ++b) {
    const BodySpec& body = scene.bodies[b];
    replaced += std::erase_if(kept, [&](const auto& e) { return inside_body(body, e.first, dim); });
    const int ppc = body.particles_per_cell, sub_z = dim == 3 ? ppc : 1;
    for (int cz = 0; cz < (dim == 3 ? g.cells[2] : 1); ++cz)
      for (int cy = 0; cy < g.cells[1]; ++cy)
        for (int cx = 0; cx < g.cells[0]; ++cx)
          for (int kz = 0; kz < sub_z; ++kz)
            for (int ky = 0; ky < ppc; ++ky)
              for (int kx = 0; kx < ppc; ++kx) {
                Vec3 x{g.origin[0] + (cx + (kx + 0.5) / ppc) * g.cell[0],
                       g.origin[1] + (cy + (ky + 0.5) / ppc) * g.cell[1], 0.0};
                if (dim == 3) x[2] = g.origin[2] + (cz + (kz + 0.5) / ppc) * g.cell[2];
                if (inside_body(body, x, dim)) kept.emplace_back(x, int(b));
              }
  }
  return kept;
}

void expect_seeds_by_definition(const std::string& text, const char* label) {
  const Scene scene = parse_scene_text(text, label);
  const ParticleSeeds s = make_particles(scene);
  std::size_t replaced = 0;
  const auto want = seeds_by_definition(scene, replaced);
  ASSERT_EQ(s.x.size(), want.size());
  std::size_t differ = 0;
  for (std::size_t p = 0; p < want.size(); ++p)
    differ += s.x[p] != want[p].first || s.body[p] != want[p].second;
  EXPECT_EQ(differ, 0u);
  // The scene must exercise the replacement: many points taken over.
  EXPECT_GT(replaced, want.size() / 10);
}

struct Lcg {
  std::uint64_t state;
  double next(double lo, double hi) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return lo + (hi - lo) * double(state >> 11) / double(1ull << 53);
  }
};

TEST(Bodies, ManyOverlapsMatchTheDefinition2D) {
  // 16 x 16 mm grid of 0.5 mm cells; bodies inside [-3, 3]^2 so that every
  // shape keeps its margin from the grid edge.
  std::ostringstream t;
  t << kBase << "[[body]]\nmaterial = \"a\"\nshape = \"box\"\nmin = [-3.0, -3.0]\n"
    << "max = [3.0, 3.0]\nparticles_per_cell = 2\n";
  Lcg r{42};
  for (int b = 0; b < 36; ++b) {
    const double cx = r.next(-2.0, 2.0), cy = r.next(-2.0, 2.0), size = r.next(0.4, 1.0);
    const int ppc = 1 + b % 3;
    t << "[[body]]\nmaterial = \"a\"\nparticles_per_cell = " << ppc << "\n";
    switch (b % 4) {
      case 0:
        t << "shape = \"box\"\nmin = [" << cx - size << ", " << cy - 0.5 * size << "]\nmax = ["
          << cx + size << ", " << cy + 0.5 * size << "]\nrotate = " << r.next(-80, 80) << "\n";
        if (b % 8 == 0) t << "pivot = [" << cx + 0.3 << ", " << cy - 0.2 << "]\n";
        break;
      case 1:
        t << "shape = \"disk\"\ncenter = [" << cx << ", " << cy << "]\nradius = " << size << "\n";
        break;
      case 2:
        t << "shape = \"polygon\"\npoints = [[" << cx - size << ", " << cy - size << "], ["
          << cx + size << ", " << cy - 0.2 * size << "], [" << cx - 0.1 * size << ", " << cy + size
          << "]]\nrotate = " << r.next(-80, 80) << "\n";
        break;
      default:
        t << "shape = \"disk\"\ncenter = [" << cx << ", " << cy << "]\nradius = " << size
          << "\nclip = { min = [" << cx - size << ", " << cy - 0.4 * size << "], max = ["
          << cx + 0.5 * size << ", " << cy + size << "] }\n";
    }
  }
  expect_seeds_by_definition(t.str(), "overlaps2d.toml");
}

TEST(Bodies, ManyOverlapsMatchTheDefinition3D) {
  std::ostringstream t;
  t << "[simulation]\ndimension = 3\nend_time = 1.0\n[grid]\norigin = [-4.0, -4.0, -4.0]\n"
    << "cell = [0.5, 0.5, 0.5]\ncells = [16, 16, 16]\nshape = \"linear\"\n"
    << kMaterialA << "[[body]]\nmaterial = \"a\"\nshape = \"box\"\nmin = [-3.0, -3.0, -3.0]\n"
    << "max = [3.0, 3.0, 3.0]\n";
  Lcg r{7}, tilt{11};  // tilt: the cylinders' axes, drawn apart so the other bodies stay put
  for (int b = 0; b < 15; ++b) {
    const double c[3] = {r.next(-2, 2), r.next(-2, 2), r.next(-2, 1)};
    const double size = r.next(0.4, 1.0);
    t << "[[body]]\nmaterial = \"a\"\nparticles_per_cell = " << 1 + b % 3 << "\n";
    const std::string centre = "[" + std::to_string(c[0]) + ", " + std::to_string(c[1]) + ", " +
                               std::to_string(c[2]) + "]";
    switch (b % 3) {
      case 0:
        t << "shape = \"box\"\nmin = [" << c[0] - size << ", " << c[1] - size << ", " << c[2]
          << "]\nmax = [" << c[0] + 0.5 * size << ", " << c[1] + size << ", " << c[2] + size
          << "]\n";
        break;
      case 1:
        t << "shape = \"sphere\"\ncenter = " << centre << "\nradius = " << size << "\n";
        break;
      default:  // fibres along random directions: the bounds must cover the tilted body
        t << "shape = \"cylinder\"\ncenter = " << centre << "\nradius = " << size
          << "\nlength = " << 2 * size << "\naxis = [" << tilt.next(-1, 1) << ", "
          << tilt.next(-1, 1) << ", " << tilt.next(0.1, 1) << "]\n";
    }
  }
  expect_seeds_by_definition(t.str(), "overlaps3d.toml");
}

// A cylinder along (1, 2, 2) / 3: the seeded particles are exactly the grid's
// seed points within radius 0.8 of its axis and between its end planes,
// tested here with the definition written out, and their volume is pi r^2 L
// within 3 % (h = 0.25, 2 ppc: the staircase of a round body).
TEST(Bodies, CylinderAlongATiltedAxis) {
  const std::string text = R"([simulation]
dimension = 3
end_time = 1.0
[grid]
origin = [-1.0, -1.0, -1.0]
cell = [0.25, 0.25, 0.25]
cells = [24, 24, 24]
shape = "linear"
)" + kMaterialA + R"([[body]]
material = "a"
shape = "cylinder"
center = [0.5, 0.25, 0.25]
radius = 0.8
length = 3.0
axis = [1.0, 2.0, 2.0]
)";
  const Scene scene = parse_scene_text(text, "fibre.toml");
  const ParticleSeeds s = make_particles(scene);
  const double a[3] = {1.0 / 3, 2.0 / 3, 2.0 / 3}, c[3] = {0.5, 0.25, 0.25};
  auto inside = [&](const Vec3& x) {
    double along = 0, r2 = 0;
    for (int d = 0; d < 3; ++d) along += (x[d] - c[d]) * a[d];
    for (int d = 0; d < 3; ++d) r2 += std::pow(x[d] - c[d] - along * a[d], 2);
    return along >= 0 && along <= 3.0 && r2 <= 0.64;
  };
  std::size_t want = 0;
  for (int i = 0; i < 48; ++i)
    for (int j = 0; j < 48; ++j)
      for (int k = 0; k < 48; ++k)
        want +=
            inside({-1.0 + (i + 0.5) * 0.125, -1.0 + (j + 0.5) * 0.125, -1.0 + (k + 0.5) * 0.125});
  std::size_t outside = 0;
  for (const Vec3& x : s.x) outside += !inside(x);
  EXPECT_EQ(s.x.size(), want);
  EXPECT_EQ(outside, 0u);
  const double volume = double(s.x.size()) * 0.125 * 0.125 * 0.125;
  EXPECT_NEAR(volume / (std::numbers::pi * 0.64 * 3.0), 1.0, 0.03);
}

}  // namespace
}  // namespace mmpm
