// USL's light nodes at a stuck pair (kernels/mm_left_out.hpp): the left-out
// force moves where pass B sticks a pair, the particles' total momentum
// change is kept, and a stuck pair ends with one left-out velocity.
#include <gtest/gtest.h>

#include <array>
#include <cmath>

#include "kernels/light_nodes.hpp"
#include "kernels/mm_left_out.hpp"
#include "tests/mm_test_grid.hpp"

namespace mmpm {
namespace {

constexpr double kDt = 0.01;

// One node, two fields, as grid_update leaves it for pass B under USL: p
// holds the kept force, dvel the left-out velocity (and -v_old, here 0).
struct LightNode {
  test::TestGrid<2, double> grid{{1, 1, 1}, 2};
  std::array<std::vector<double>, 2> dvel{std::vector<double>(2, 0.0), std::vector<double>(2, 0.0)};
  std::array<double*, 2> dvel_ptr{dvel[0].data(), dvel[1].data()};
  std::array<double, 3> gravity{0.0, -3.0, 0.0};
  std::array<double, 2> light{};

  LightNode(double ma, double mb, double light_a, double light_b) : light{light_a, light_b} {
    grid.set(0, 0, ma, {0.5, -0.25, 0}, {0, 0, 0}, 1);
    grid.set(1, 0, mb, {0.5, -0.25, 0}, {0, 0, 0}, 1);
    const double f[2][2] = {{3.0, -1.0}, {-2.5, 4.0}}, fi[2][2] = {{0.5, 0.25}, {-0.5, -0.25}};
    for (int x = 0; x < 2; ++x)
      for (int d = 0; d < 2; ++d) {
        grid.f[d][std::size_t(x)] = f[x][d];
        grid.fi[d][std::size_t(x)] = fi[x][d];
        dvel[d][std::size_t(x)] =
            light_left_out<2, double>(grid.view, std::size_t(x), d, grid.m[std::size_t(x)],
                                      light[std::size_t(x)], gravity[std::size_t(d)], kDt);
      }
  }
  // Momentum of the grid plus what dvel carries to the particles beyond it.
  double momentum(int d) const {
    double sum = 0;
    for (std::size_t x = 0; x < 2; ++x) sum += grid.p[d][x] + grid.m[x] * dvel[d][x];
    return sum;
  }
  double force(int x, int d) const {  // f + m g + f_interface
    const std::size_t i = std::size_t(x);
    return grid.f[d][i] + grid.m[i] * gravity[std::size_t(d)] + grid.fi[d][i];
  }
  VecD<2, double> exchange(unsigned char directions, VecD<2, double> n, bool b_rigid = false,
                           unsigned char fixed = 0) {
    return exchange_left_out<2, double>(grid.view, light.data(), dvel_ptr, gravity, kDt, 0, 0, 1,
                                        b_rigid, directions, n, fixed);
  }
};

TEST(LightNodeExchange, LeftOutVelocityIsTheUpdatesShareOfTheWholeForce) {
  LightNode node(0.1, 2.0, 0.5, 0.5);
  for (int d = 0; d < 2; ++d) {
    EXPECT_NEAR(node.dvel[d][0], kDt * node.force(0, d) * (1 - 0.1 / 0.5) / 0.1, 1e-15);
    EXPECT_EQ(node.dvel[d][1], 0.0) << "a node heavier than m_L leaves nothing out";
  }
}

// b heavier than m_L: the pair is one node heavier than m_L along the stuck
// directions, so a's whole left-out impulse goes into the momenta.
TEST(LightNodeExchange, HeavyPartnerTakesTheLightFieldsWholeForce) {
  LightNode node(0.1, 2.0, 0.5, 0.5);
  const double before[2] = {node.momentum(0), node.momentum(1)};
  const double lo_a[2] = {node.dvel[0][0], node.dvel[1][0]};
  const double relative[2] = {node.grid.velocity(0, 0, 0) - node.grid.velocity(1, 0, 0),
                              node.grid.velocity(0, 0, 1) - node.grid.velocity(1, 0, 1)};
  node.exchange(kStickBoth, {1.0, 0.0});
  for (int d = 0; d < 2; ++d) {
    EXPECT_NEAR(node.momentum(d), before[d], 1e-14);
    EXPECT_NEAR(node.dvel[d][0], 0.0, 1e-14) << "nothing left out along a stuck direction";
    EXPECT_NEAR(node.dvel[d][1], 0.0, 1e-14);
    // The pair's velocities move together: a stuck pair stays stuck.
    EXPECT_NEAR(node.grid.velocity(0, 0, d) - node.grid.velocity(1, 0, d), relative[d], 1e-13);
    EXPECT_NEAR(node.grid.p[d][0] + node.grid.p[d][1],
                2.1 * (0.5 * (d == 0) - 0.25 * (d == 1)) + 0.1 * lo_a[d], 1e-14);
  }
}

// Both lighter than m_L with M = m_a + m_b < m_L: the pair keeps M / m_L of
// the pair's force, the combined node's rule, and both fields' dvel carry
// one left-out velocity.
TEST(LightNodeExchange, TwoLightFieldsKeepTheCombinedNodesShare) {
  const double ma = 0.1, mb = 0.2, light = 0.5;
  LightNode node(ma, mb, light, light);
  const double before[2] = {node.momentum(0), node.momentum(1)};
  double p_before[2];
  for (int d = 0; d < 2; ++d) p_before[d] = node.grid.p[d][0] + node.grid.p[d][1];
  node.exchange(kStickBoth, {0.6, 0.8});
  const double M = ma + mb;
  for (int d = 0; d < 2; ++d) {
    EXPECT_NEAR(node.momentum(d), before[d], 1e-14);
    EXPECT_NEAR(node.dvel[d][0], node.dvel[d][1], 1e-14);
    // Kept before: (m_x / m_L) F_x dt each; now (M / m_L) (F_a + F_b) dt.
    const double added = kDt * ((M / light - ma / light) * node.force(0, d) +
                                (M / light - mb / light) * node.force(1, d));
    EXPECT_NEAR(node.grid.p[d][0] + node.grid.p[d][1] - p_before[d], added, 1e-14);
  }
}

// Stuck along the normal only: the tangential part of each field's left-out
// velocity stays where the update put it.
TEST(LightNodeExchange, OnlyTheStuckDirectionMoves) {
  LightNode node(0.1, 2.0, 0.5, 0.5);
  const VecD<2, double> n{0.6, 0.8}, t{-0.8, 0.6};
  auto along = [&](int x, const VecD<2, double>& u) {
    return node.dvel[0][std::size_t(x)] * u[0] + node.dvel[1][std::size_t(x)] * u[1];
  };
  const double tangential_a = along(0, t), tangential_b = along(1, t);
  const double before[2] = {node.momentum(0), node.momentum(1)};
  node.exchange(kStickNormal, n);
  EXPECT_NEAR(along(0, t), tangential_a, 1e-14);
  EXPECT_NEAR(along(1, t), tangential_b, 1e-14);
  EXPECT_NEAR(along(0, n), 0.0, 1e-14);
  for (int d = 0; d < 2; ++d) EXPECT_NEAR(node.momentum(d), before[d], 1e-14);
  // No stuck direction, or no normal: nothing moves.
  LightNode other(0.1, 2.0, 0.5, 0.5);
  const double untouched = other.dvel[0][0];
  other.exchange(0, n);
  other.exchange(kStickBoth, {0.0, 0.0});
  EXPECT_EQ(other.dvel[0][0], untouched);
}

// A rigid partner holds a's velocity along the stuck directions: a's
// left-out impulse there is its reaction's, not the particles'.
TEST(LightNodeExchange, RigidPartnerAbsorbsTheLeftOutImpulse) {
  LightNode node(0.1, 2.0, 0.5, 0.5);
  const double lo_a[2] = {node.dvel[0][0], node.dvel[1][0]};
  const VecD<2, double> absorbed = node.exchange(kStickBoth, {1.0, 0.0}, true);
  for (int d = 0; d < 2; ++d) {
    EXPECT_NEAR(node.dvel[d][0], 0.0, 1e-14);
    EXPECT_NEAR(absorbed[d], -0.1 * lo_a[d], 1e-15);
  }
}

// A support fixing an axis takes each field's own left-out velocity there
// (apply_supports): the exchange leaves that component alone.
TEST(LightNodeExchange, FixedAxisIsLeftToTheSupport) {
  LightNode node(0.1, 2.0, 0.5, 0.5);
  const double x_before = node.dvel[0][0], p_before = node.grid.p[0][0];
  node.exchange(kStickBoth, {1.0, 0.0}, false, 1u);  // x fixed
  EXPECT_EQ(node.dvel[0][0], x_before);
  EXPECT_EQ(node.grid.p[0][0], p_before);
  EXPECT_NEAR(node.dvel[1][0], 0.0, 1e-14) << "the free axis is exchanged";
}

TEST(LightNodeExchange, StuckDirectionsFollowTheLawAndPassB) {
  EXPECT_EQ(stuck_directions(Law::interface, kStickNormal, false, false), kStickNormal);
  EXPECT_EQ(stuck_directions(Law::interface, kStickTangential, false, false), kStickTangential);
  EXPECT_EQ(stuck_directions(Law::interface, kStickNormal | kStickTangential, false, false),
            kStickBoth);
  // A one-sided normal sticks only where pass B held it.
  const unsigned char one_sided = kOneSidedNormal | kStickNormal | kStickTangential | kStickBoth;
  EXPECT_EQ(stuck_directions(Law::interface, one_sided, true, false), kStickBoth);
  EXPECT_EQ(stuck_directions(Law::interface, one_sided, false, false), kStickTangential);
  EXPECT_EQ(stuck_directions(Law::frictionless, 0, true, false), kStickNormal);
  // A sliding Coulomb pair: its friction reads pass B's normal impulse.
  EXPECT_EQ(stuck_directions(Law::friction, 0, true, false), 0) << "sliding";
  EXPECT_EQ(stuck_directions(Law::friction, 0, true, true), kStickBoth);
  EXPECT_EQ(stuck_directions(Law::stick, 0, true, true), kStickBoth);
  EXPECT_EQ(stuck_directions(Law::stick, 0, false, false), 0);
}

}  // namespace
}  // namespace mmpm
