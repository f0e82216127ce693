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
                                        b_rigid, PassBHold<double>{directions, false, 0.0}, n,
                                        fixed);
  }
  // pass B held the pair sliding under Coulomb friction mu.
  VecD<2, double> slide(double mu, VecD<2, double> n, bool b_rigid = false) {
    return exchange_left_out<2, double>(grid.view, light.data(), dvel_ptr, gravity, kDt, 0, 0, 1,
                                        b_rigid, PassBHold<double>{kStickNormal, true, mu}, n, 0);
  }
  // Field x's velocity as its particles receive it: p / m plus dvel.
  double total_velocity(int x, int d) const {
    const std::size_t i = std::size_t(x);
    return grid.p[d][i] / grid.m[i] + dvel[d][i];
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

// A sliding Coulomb pair against a rigid floor below it (n = a -> b = -y):
// a's left-out velocity presses it into the floor, so the floor takes that
// normal part, and with it the friction mu m_a (v'_a . n) against a's
// sliding (kept +x 1.5 plus left-out), in dvel; the reaction counts both.
TEST(LightNodeExchange, SlidingPairTakesTheNormalPartAndItsFriction) {
  const double mu = 0.5, ma = 0.1;
  LightNode node(ma, 2.0, 0.5, 0.5);
  node.grid.p[0][0] = ma * 2.0;  // a slides along +x at 1.5 relative to the floor
  const double lo[2] = {node.dvel[0][0], node.dvel[1][0]};
  ASSERT_LT(lo[1], 0.0) << "the left-out part must press a into the floor";
  const double p_before[2] = {node.grid.p[0][0], node.grid.p[1][0]};
  const VecD<2, double> absorbed = node.slide(mu, {0.0, -1.0}, true);
  EXPECT_NEAR(node.dvel[1][0], 0.0, 1e-15) << "the floor holds the normal part";
  EXPECT_NEAR(node.dvel[0][0], lo[0] - mu * (-lo[1]), 1e-15) << "friction mu |v'_n|";
  for (int d = 0; d < 2; ++d) {
    EXPECT_EQ(node.grid.p[d][0], p_before[d]) << "the momentum (strain, positions) is not touched";
    EXPECT_NEAR(absorbed[d], ma * (node.dvel[d][0] - lo[d]), 1e-16);
  }
  // A large mu stops the sliding, kept and left-out together, and no more.
  LightNode stuck(ma, 2.0, 0.5, 0.5);
  stuck.grid.p[0][0] = ma * 2.0;
  stuck.slide(100.0, {0.0, -1.0}, true);
  EXPECT_NEAR(stuck.total_velocity(0, 0), stuck.grid.velocity(1, 0, 0), 1e-14);
  // A left-out part that pulls a off the floor is not held (contact does not
  // pull), and carries no friction.
  LightNode parting(ma, 2.0, 0.5, 0.5);
  const double before[2] = {parting.dvel[0][0], parting.dvel[1][0]};
  const VecD<2, double> none = parting.slide(mu, {0.0, 1.0}, true);
  for (int d = 0; d < 2; ++d) {
    EXPECT_EQ(parting.dvel[d][0], before[d]);
    EXPECT_EQ(none[d], 0.0);
  }
}

// Two light deformable fields sliding on each other: the pair is one node
// along the normal (as a frictionless held pair), the exchanged normal
// impulse J = m_r (v'_a - v'_b) . n carries the friction mu J, a gets it and
// b its negative: the momentum is kept, the normal left-out velocities end
// equal, and the relative sliding drops by mu J (1 / m_a + 1 / m_b).
TEST(LightNodeExchange, SlidingDeformablePairExchangesTheNormalAndItsFriction) {
  const double mu = 0.3, ma = 0.1, mb = 0.2;
  LightNode node(ma, mb, 0.5, 0.5);
  node.grid.p[0][0] = ma * 2.0;  // a slides along +x at 1.5 relative to b
  const VecD<2, double> n{0.0, -1.0};
  const double approach = -(node.dvel[1][0] - node.dvel[1][1]);
  ASSERT_GT(approach, 0.0);
  const double before[2] = {node.momentum(0), node.momentum(1)};
  const double slide_before = node.total_velocity(0, 0) - node.total_velocity(1, 0);
  const double normal_kept = node.grid.velocity(0, 0, 1) - node.grid.velocity(1, 0, 1);
  node.slide(mu, n);
  for (int d = 0; d < 2; ++d) EXPECT_NEAR(node.momentum(d), before[d], 1e-14);
  EXPECT_NEAR(node.total_velocity(0, 1) - node.total_velocity(1, 1), normal_kept, 1e-14);
  const double J = ma * mb / (ma + mb) * approach;
  EXPECT_NEAR(node.total_velocity(0, 0) - node.total_velocity(1, 0),
              slide_before - mu * J * (1 / ma + 1 / mb), 1e-14);
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
  // A sliding Coulomb pair is held along the normal (with its friction).
  EXPECT_EQ(stuck_directions(Law::friction, 0, true, false), kStickNormal) << "sliding";
  EXPECT_TRUE((pass_b_hold<double>(Law::friction, 0.3, 0, true, false).sliding));
  EXPECT_FALSE((pass_b_hold<double>(Law::friction, 0.3, 0, true, true).sliding));
  EXPECT_FALSE((pass_b_hold<double>(Law::frictionless, 0.0, 0, true, false).sliding));
  EXPECT_EQ(stuck_directions(Law::friction, 0, true, true), kStickBoth);
  EXPECT_EQ(stuck_directions(Law::stick, 0, true, true), kStickBoth);
  EXPECT_EQ(stuck_directions(Law::stick, 0, false, false), 0);
}

}  // namespace
}  // namespace mmpm
