// XPIC(m) particle velocities ([simulation] xpic_order; kernels/xpic.hpp,
// docs/validation.md §3.12): the series' first term is PIC, its terms
// converge on the projection that keeps every velocity field the grid can
// carry, and the filter keeps momentum.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "tests/test_util.hpp"
#include "tests/validation_util.hpp"

namespace mmpm {
namespace {

// A free block (no support, no load), 2 x 2 particles per cell, its edges
// off the grid lines.
std::string free_block(const std::string& shape) {
  mmpm_test::BoxScene2D s;
  s.shape = shape;
  s.scheme = "MUSL";
  s.cells_x = 20, s.cells_y = 20;
  s.b0_min[0] = 4.3, s.b0_min[1] = 3.7, s.b0_max[0] = 14.3, s.b0_max[1] = 15.7;
  return s.text();
}

// The particles' velocities after one step from v_p = a + B x_p, relative
// to it (root mean square). v_p lies in the range of S (S reproduces linear
// fields), so the exact projection keeps it; the stress is 0 in the first
// step, so the step's FLIP increment is 0 and v_p becomes S v*.
double linear_field_error(const std::string& shape, int order) {
  auto sim = testing::make_from_text(free_block(shape),
                                     {"simulation.xpic_order=" + std::to_string(order)});
  const std::vector<double> x = sim->particle_field("position").values;
  std::vector<double> v(x.size());
  for (std::size_t p = 0; p < x.size() / 2; ++p) {
    v[2 * p] = 1.0 + 0.3 * x[2 * p] - 0.5 * x[2 * p + 1];
    v[2 * p + 1] = -2.0 + 0.5 * x[2 * p] + 0.2 * x[2 * p + 1];
  }
  sim->set_particle_field("velocity", v);
  sim->step();
  const std::vector<double> after = sim->particle_field("velocity").values;
  double num = 0, den = 0;
  for (std::size_t i = 0; i < v.size(); ++i)
    num += (after[i] - v[i]) * (after[i] - v[i]), den += v[i] * v[i];
  return std::sqrt(num / den);
}

TEST(Xpic, SeriesConvergesOnAVelocityFieldTheGridCarries) {
  for (const char* shape : {"linear", "gimp", "bspline2"}) {
    std::vector<double> err;
    for (int m : {1, 2, 4, 8}) err.push_back(linear_field_error(shape, m));
    std::printf(
        "[xpic] %s: linear field kept within %.3e (m = 1, PIC), %.3e (2), %.3e (4), %.3e (8)\n",
        shape, err[0], err[1], err[2], err[3]);
    for (std::size_t k = 1; k < err.size(); ++k) EXPECT_LT(err[k], err[k - 1]) << shape;
    EXPECT_LT(err[3], 0.2 * err[0]) << shape;
  }
}

// m = 1: v_p = S v, then the FLIP increment S (v_L - v): PIC's S v_L up to
// round-off. The disks of inputs/colliding_disks.toml through their
// collision (t = 2.5), against flip = 0.
TEST(Xpic, OrderOneIsPic) {
  const std::string file = mmpm_test::source_dir() + "/inputs/colliding_disks.toml";
  auto run = [&](const std::string& key) {
    auto sim = make_simulation(parse_scene_file(file, {key}));
    testing::run_until(*sim, 2.5);
    return sim->particle_field("velocity").values;
  };
  const std::vector<double> xpic = run("simulation.xpic_order=1"), pic = run("simulation.flip=0.0");
  ASSERT_EQ(xpic.size(), pic.size());
  double worst = 0;
  for (std::size_t i = 0; i < pic.size(); ++i) worst = std::max(worst, std::abs(xpic[i] - pic[i]));
  std::printf("[xpic] order 1 against PIC: largest velocity difference %.2e (speed 0.14)\n", worst);
  EXPECT_LT(worst, 1e-12);
}

}  // namespace
}  // namespace mmpm
