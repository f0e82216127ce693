// normal = "geometry": a material's outward normal from its bodies' shapes
// (model/shape_surface.hpp), the motion that carries them, and the
// gradients it turns before pass A (solver/geometry_normals.hpp). Exact
// geometry, so 1e-12.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>
#include <string>
#include <vector>

#include "model/material.hpp"
#include "model/shape_surface.hpp"
#include "scene/parse.hpp"
#include "solver/field_plan.hpp"
#include "solver/geometry_normals.hpp"
#include "solver/simulation.hpp"
#include "test_util.hpp"

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

ShapeSurface wall_surface(const Scene& scene) {
  return ShapeSurface(scene, {std::size_t(scene.material_index("wall"))});
}

void expect_normal(const ShapeSurface& s, Vec3 x, Vec3 n, const char* where) {
  const Vec3 got = s.distance(x).gradient;
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(got[d], n[d], kTol) << where << " component " << d;
}

// A 20-degree slab, its top face through the pivot (0, 0): along the face,
// just inside and just outside, the normal is the face's (-sin, cos); at
// its lower end the end face's (cos, sin) inside, and past the end's
// corner the direction from the corner.
TEST(ShapeSurface, RotatedBoxGivesItsFacesNormals) {
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
  const ShapeSurface s = wall_surface(scene);
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
TEST(ShapeSurface, PolygonNormalsDoNotDependOnItsWinding) {
  for (const char* points :
       {"[[-4.0, -4.0], [4.0, -4.0], [4.0, 0.0]]", "[[4.0, 0.0], [4.0, -4.0], [-4.0, -4.0]]"}) {
    const Scene scene = parse_scene_text(
        scene_2d(std::string(kBlock) + "[[body]]\nmaterial = \"wall\"\nshape = \"polygon\"\n" +
                 "points = " + points + "\n"),
        "wedge.toml");
    const ShapeSurface s = wall_surface(scene);
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
TEST(ShapeSurface, ClipBoxesAndLaterBodiesCutTheSurface) {
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
  const ShapeSurface s = wall_surface(scene);
  expect_normal(s, {0.0, 3.1, 0}, {0, -1, 0}, "the clip's face");
  expect_normal(s, {1.2, 5.6, 0}, {0.6, 0.8, 0}, "the disk");
  expect_normal(s, {0.0, -0.9, 0}, {0, 1, 0}, "the notch's floor, inside the wall");
  expect_normal(s, {0.0, -1.2, 0}, {0, 1, 0}, "the notch's floor, below it");
  expect_normal(s, {0.9, -0.5, 0}, {-1, 0, 0}, "the notch's side");
  expect_normal(s, {4.0, -0.1, 0}, {0, 1, 0}, "the box's top beside the notch");
}

// A cylinder along a tilted axis (3D): radial on its side, the axis past its end.
TEST(ShapeSurface, CylinderSideAndEnd) {
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
TEST(ShapeSurface, RigidDisplacementIntegratesTheVelocityTable) {
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

// A body turned by 30 degrees about (1, 2) and moved by (0.5, -0.25): the
// moments of its particles give back that motion, in 2D (closed form) and
// in 3D (Kabsch, about a tilted axis), and the shape's normals turn with it.
TEST(ShapeSurface, BodyMomentsGiveBackARigidMotion) {
  const double a = 30.0 * std::numbers::pi / 180.0;
  BodyMoments m2;
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 3; ++j) {
      const Vec3 X{0.3 * i, 0.7 * j - 0.4, 0};
      const double dx = X[0] - 1.0, dy = X[1] - 2.0;
      const Vec3 x{1.5 + std::cos(a) * dx - std::sin(a) * dy,
                   1.75 + std::sin(a) * dx + std::cos(a) * dy, 0};
      m2.add(0.1 + 0.01 * i, X, x);
    }
  const BodyMotion f = m2.motion(2);
  EXPECT_NEAR(f.R[0], std::cos(a), kTol);
  EXPECT_NEAR(f.R[1], -std::sin(a), kTol);
  EXPECT_NEAR(f.R[3], std::sin(a), kTol);
  const Vec3 X = f.to_reference({1.5, 1.75, 0});  // where (1, 2) went
  EXPECT_NEAR(X[0], 1.0, kTol);
  EXPECT_NEAR(X[1], 2.0, kTol);

  // 3D: 40 degrees about the unit axis (1, 2, 2) / 3 (Rodrigues), moved by (1, -2, 3).
  const double k[3] = {1.0 / 3, 2.0 / 3, 2.0 / 3}, b = 40.0 * std::numbers::pi / 180.0;
  double R[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      R[i][j] = (i == j ? std::cos(b) : 0.0) + (1 - std::cos(b)) * k[i] * k[j] +
                std::sin(b) * (i == j ? 0.0 : ((i + 1) % 3 == j ? -k[3 - i - j] : k[3 - i - j]));
  BodyMoments m3;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int l = 0; l < 2; ++l) {
        const Vec3 Y{0.5 * i, 0.4 * j, 0.9 * l};
        Vec3 y{1.0, -2.0, 3.0};
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) y[r] += R[r][c] * Y[c];
        m3.add(1.0, Y, y);
      }
  const BodyMotion g = m3.motion(3);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(g.R[3 * i + j], R[i][j], 1e-10) << i << j;
}

// Before pass A each geometry field's gradient at the listed nodes turns to
// the normal of its moved shape and keeps its length: the rigid wall's
// disk moved by its velocity, the block by the motion fitted to it; a
// node where a field has no gradient keeps its zero.
TEST(ShapeSurface, OrientGradientsFollowsTheMovingShapes) {
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
  std::vector<GeometryNormalField> fields = geometry_normal_fields(scene, plan);
  ASSERT_EQ(fields.size(), 2u);  // the block (deformable) and the wall (rigid)
  const std::size_t w = fields[0].rigid_material >= 0 ? 0 : 1;
  const int wall = fields[w].field, block = fields[1 - w].field;
  move_rigid_shapes(fields, scene, 0.5);          // the disk's centre is at (1.5, -0.5)
  BodyMotion& slid = fields[1 - w].motion.at(0);  // the block [-7, -6] x [5, 6] moved by (8, -7)
  slid.C0 = {-6.5, 5.5, 0};
  slid.c = {1.5, -1.5, 0};

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

  orient_gradients(grid, nodes, fields, {}, 0.5);  // no pair: each field its own normal
  for (std::uint32_t i : nodes) {
    const auto x = grid.position(i);
    const double rx = x[0] - 1.5, ry = x[1] + 0.5, r = std::hypot(rx, ry);
    const std::size_t at = grid.at(wall, i);
    if (i == 44) {
      EXPECT_EQ(gx[at], 0.0);
      EXPECT_EQ(gy[at], 0.0);
    } else {
      EXPECT_NEAR(gx[at], 0.5 * rx / r, kTol) << "node " << i;  // |g| = 0.5 kept
      EXPECT_NEAR(gy[at], 0.5 * ry / r, kTol) << "node " << i;
    }
  }
  // The block, now [1, 2] x [-2, -1]: node 10 at (0.5, -3.5) lies below
  // its bottom-left corner (1, -2), node 40 at (2, -2) on its corner.
  const double c = 0.5 / std::hypot(0.5, 1.5);
  EXPECT_NEAR(gx[grid.at(block, 10)], -0.5 * c, kTol);
  EXPECT_NEAR(gy[grid.at(block, 10)], -0.5 * 3 * c, kTol);
  EXPECT_NEAR(gx[grid.at(block, 70)], 0.5 * 1.5 / std::hypot(1.5, 0.5), kTol);
}

// The shapes belong to the simulation, not to the scene it was made from:
// moving the caller's boxes by 10 mm after make_simulation changes nothing
// (inputs/rotated_incline.toml, 300 steps, velocities bit for bit). The
// shapes once pointed into the caller's scene, and a simulation made from
// a temporary one read freed memory.
TEST(ShapeSurface, TheSimulationKeepsItsOwnShapes) {
  const std::string file = mmpm_test::source_dir() + "/inputs/rotated_incline.toml";
  Scene kept = parse_scene_file(file, {});
  Scene changed = parse_scene_file(file, {});
  auto a = make_simulation(kept);
  auto b = make_simulation(changed);
  for (BodySpec& body : changed.bodies) body.min[0] += 10.0, body.max[0] += 10.0;
  for (int k = 0; k < 300; ++k) a->step(), b->step();
  const auto va = a->particle_field("velocity").values, vb = b->particle_field("velocity").values;
  ASSERT_EQ(va.size(), vb.size());
  std::size_t differ = 0;
  for (std::size_t i = 0; i < va.size(); ++i)
    differ += std::memcmp(&va[i], &vb[i], sizeof va[i]) != 0;
  EXPECT_EQ(differ, 0u);
  double speed = 0;
  for (double v : va) speed = std::max(speed, std::abs(v));
  EXPECT_GT(speed, 0.1) << "the block must be sliding";
}

}  // namespace
}  // namespace mmpm
