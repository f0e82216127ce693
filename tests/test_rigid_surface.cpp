// normal = "geometry": a rigid material's outward normal from its bodies'
// shapes (model/rigid_surface.hpp) and the gradients it turns before pass A
// (solver/rigid_normals.hpp). Exact geometry, so 1e-12.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "model/material.hpp"
#include "model/rigid_surface.hpp"
#include "scene/parse.hpp"
#include "solver/field_plan.hpp"
#include "solver/rigid_normals.hpp"

namespace mmpm {
namespace {

constexpr double kTol = 1e-12;

std::string scene_2d(const std::string& bodies, const std::string& rigid_velocity = "[0.0, 0.0]") {
  return R"(
[simulation]
dimension = 2
end_time = 1.0
[grid]
origin = [-8.0, -8.0]
cell = [0.5, 0.5]
cells = [32, 32]
shape = "linear"
[[material]]
name = "block"
type = "isotropic"
density = 1.0
E = 100.0
nu = 0.3
[[material]]
name = "wall"
type = "rigid"
density = 1.0
velocity = )" +
         rigid_velocity + "\n" + bodies + R"(
[[interaction]]
materials = ["block", "wall"]
law = "frictionless"
normal = "geometry"
)";
}

const char* kBlock = R"(
[[body]]
material = "block"
shape = "box"
min = [-7.0, 5.0]
max = [-6.0, 6.0]
)";

RigidSurface wall_surface(const Scene& scene) {
  return RigidSurface(scene, {std::size_t(scene.material_index("wall"))});
}

void expect_normal(const RigidSurface& s, Vec3 x, Vec3 n, const char* where) {
  const Vec3 got = s.outward_normal(x);
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(got[d], n[d], kTol) << where << " component " << d;
}

// A 20-degree slab, its top face through the pivot (0, 0): along the face,
// just inside and just outside, the normal is the face's (-sin, cos); at
// its lower end the end face's (cos, sin) inside, and past the end's
// corner the direction from the corner.
TEST(RigidSurface, RotatedBoxGivesItsFacesNormals) {
  const Scene scene = parse_scene_text(scene_2d(std::string(kBlock) + R"(
[[body]]
material = "wall"
shape = "box"
min = [-5.0, -2.0]
max = [5.0, 0.0]
rotate = 20.0
pivot = [0.0, 0.0]
)"),
                                       "slab.toml");
  const RigidSurface s = wall_surface(scene);
  const double th = 20.0 * std::numbers::pi / 180.0;
  const Vec3 t{std::cos(th), std::sin(th), 0}, n{-std::sin(th), std::cos(th), 0};
  for (double along : {-4.0, -1.3, 0.0, 2.7, 4.5})
    for (double off : {-0.3, -0.05, 0.05, 0.4}) {
      const Vec3 x{along * t[0] + off * n[0], along * t[1] + off * n[1], 0};
      expect_normal(s, x, n, "top face");
      EXPECT_NEAR(s.distance(x).distance, off, kTol);
    }
  // Near the end face x' = 5 (body frame), 1 mm below the top: inside.
  expect_normal(s, {4.9 * t[0] - 1.0 * n[0], 4.9 * t[1] - 1.0 * n[1], 0}, t, "end face");
  // Past the top-right corner (5, 0) by (0.3, 0.4) in the body frame.
  const Vec3 corner{5.0 * t[0], 5.0 * t[1], 0};
  const Vec3 x{corner[0] + 0.3 * t[0] + 0.4 * n[0], corner[1] + 0.3 * t[1] + 0.4 * n[1], 0};
  expect_normal(s, x, {0.6 * t[0] + 0.8 * n[0], 0.6 * t[1] + 0.8 * n[1], 0}, "corner");
  EXPECT_NEAR(s.distance(x).distance, 0.5, kTol);
}

// A wedge given clockwise and counter-clockwise: the same outward normals.
TEST(RigidSurface, PolygonNormalsDoNotDependOnItsWinding) {
  for (const char* points :
       {"[[-4.0, -4.0], [4.0, -4.0], [4.0, 0.0]]", "[[4.0, 0.0], [4.0, -4.0], [-4.0, -4.0]]"}) {
    const Scene scene = parse_scene_text(
        scene_2d(std::string(kBlock) + "[[body]]\nmaterial = \"wall\"\nshape = \"polygon\"\n" +
                 "points = " + points + "\n"),
        "wedge.toml");
    const RigidSurface s = wall_surface(scene);
    const double l = std::hypot(8.0, 4.0);
    const Vec3 slope{-4.0 / l, 8.0 / l, 0};  // the hypotenuse, facing up and left
    expect_normal(s, {0.0, -2.0 + 0.1, 0}, slope, points);
    expect_normal(s, {0.0, -2.0 - 0.1, 0}, slope, points);
    expect_normal(s, {3.9, -2.5, 0}, {1, 0, 0}, points);
    expect_normal(s, {1.0, -3.9, 0}, {0, -1, 0}, points);
  }
}

// The clip box cuts the disk; a later block of another material takes a
// notch out of the wall's box, whose floor then faces up into the notch.
TEST(RigidSurface, ClipBoxesAndLaterBodiesCutTheSurface) {
  const Scene scene = parse_scene_text(scene_2d(R"(
[[body]]
material = "wall"
shape = "disk"
center = [0.0, 4.0]
radius = 2.0
clip = { min = [-3.0, 3.0], max = [3.0, 7.0] }
[[body]]
material = "wall"
shape = "box"
min = [-6.0, -6.0]
max = [6.0, 0.0]
[[body]]
material = "block"
shape = "box"
min = [-1.0, -1.0]
max = [1.0, 2.0]
)"),
                                       "cut.toml");
  const RigidSurface s = wall_surface(scene);
  expect_normal(s, {0.0, 3.1, 0}, {0, -1, 0}, "the clip's face");
  expect_normal(s, {1.2, 5.6, 0}, {0.6, 0.8, 0}, "the disk");
  expect_normal(s, {0.0, -0.9, 0}, {0, 1, 0}, "the notch's floor, inside the wall");
  expect_normal(s, {0.0, -1.2, 0}, {0, 1, 0}, "the notch's floor, below it");
  expect_normal(s, {0.9, -0.5, 0}, {-1, 0, 0}, "the notch's side");
  expect_normal(s, {4.0, -0.1, 0}, {0, 1, 0}, "the box's top beside the notch");
}

// A cylinder along a tilted axis (3D): radial on its side, the axis past its end.
TEST(RigidSurface, CylinderSideAndEnd) {
  BodySpec b;
  b.shape = BodyShape::cylinder;
  b.center = {1.0, 2.0, 3.0};
  b.radius = 0.5;
  b.length = 4.0;
  const double c = 1.0 / std::sqrt(2.0);
  b.axis = {c, 0.0, c};
  const Vec3 side = {1.0 + 2.0 * c, 2.0 + 0.6, 3.0 + 2.0 * c};  // 0.6 from the axis along y
  const SurfaceDistance s = body_distance(b, side, 3);
  EXPECT_NEAR(s.distance, 0.1, kTol);
  EXPECT_NEAR(s.gradient[0], 0.0, kTol);
  EXPECT_NEAR(s.gradient[1], 1.0, kTol);
  EXPECT_NEAR(s.gradient[2], 0.0, kTol);
  const Vec3 end = {1.0 + 4.2 * c, 2.1, 3.0 + 4.2 * c};  // 0.2 past the far end, 0.1 off axis
  const SurfaceDistance e = body_distance(b, end, 3);
  EXPECT_NEAR(e.distance, 0.2, kTol);
  EXPECT_NEAR(e.gradient[0], c, kTol);
  EXPECT_NEAR(e.gradient[1], 0.0, kTol);
  EXPECT_NEAR(e.gradient[2], c, kTol);
}

// The displacement of a rigid table: the exact integral, against a fine
// midpoint sum of rigid_velocity.
TEST(RigidSurface, RigidDisplacementIntegratesTheVelocityTable) {
  MaterialSpec m;
  m.velocity.time = {0.5, 1.0, 3.0};
  m.velocity.velocity = {{1.0, 0.0, 0.0}, {-2.0, 4.0, 0.0}, {0.0, 1.0, 0.0}};
  for (double t : {0.2, 0.5, 0.8, 2.0, 4.5}) {
    const int n = 200000;
    Vec3 sum{0, 0, 0};
    for (int k = 0; k < n; ++k) {
      const Vec3 v = rigid_velocity(m, (k + 0.5) * t / n);
      for (int d = 0; d < 3; ++d) sum[d] += v[d] * t / n;
    }
    const Vec3 u = rigid_displacement(m, t);
    for (int d = 0; d < 3; ++d) EXPECT_NEAR(u[d], sum[d], 1e-8) << "t = " << t;
  }
}

// Before pass A the wall's gradient at each listed node turns to the
// normal of its moved shape and keeps its length; the block's field, and
// a node where the wall has no gradient, keep theirs.
TEST(RigidSurface, OrientRigidGradientsFollowsTheMovingShape) {
  const Scene scene = parse_scene_text(scene_2d(std::string(kBlock) + R"(
[[body]]
material = "wall"
shape = "disk"
center = [0.0, 0.0]
radius = 2.0
)",
                                                "[3.0, -1.0]"),
                                       "moving.toml");
  const FieldPlan plan = plan_fields(scene);
  const std::vector<RigidSurfaceField> surfaces = rigid_surface_fields(scene, plan);
  ASSERT_EQ(surfaces.size(), 1u);
  const int wall = surfaces[0].field, block = 1 - wall;

  GridView<2, double> grid;
  grid.nodes_per_dim = {9, 9, 1};
  grid.h = {0.5, 0.5, 1};
  grid.origin = {0.0, -4.0, 0};
  grid.nodes = 81;
  grid.fields = 2;
  std::vector<double> gx(162, 0.0), gy(162, 0.0);
  grid.g = {gx.data(), gy.data()};
  const std::vector<std::uint32_t> nodes = {10, 40, 44, 70};
  for (std::uint32_t i : nodes)
    for (int f = 0; f < 2; ++f) gx[grid.at(f, i)] = 0.3, gy[grid.at(f, i)] = 0.4;
  gx[grid.at(wall, 44)] = gy[grid.at(wall, 44)] = 0.0;

  const double t = 0.5;  // the disk's centre is at (1.5, -0.5)
  orient_rigid_gradients(grid, nodes, surfaces, scene, t);
  for (std::uint32_t i : nodes) {
    const auto x = grid.position(i);
    const double rx = x[0] - 1.5, ry = x[1] + 0.5, r = std::hypot(rx, ry);
    const std::size_t w = grid.at(wall, i), b = grid.at(block, i);
    if (i == 44) {
      EXPECT_EQ(gx[w], 0.0);
      EXPECT_EQ(gy[w], 0.0);
    } else {
      EXPECT_NEAR(gx[w], 0.5 * rx / r, kTol) << "node " << i;  // |g| = 0.5 kept
      EXPECT_NEAR(gy[w], 0.5 * ry / r, kTol) << "node " << i;
    }
    EXPECT_EQ(gx[b], 0.3);
    EXPECT_EQ(gy[b], 0.4);
  }
}

}  // namespace
}  // namespace mmpm
