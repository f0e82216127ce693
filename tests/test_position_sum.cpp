// Float positions keep their rounding error (kernels/position_sum.hpp):
// moves smaller than half an ulp of x still add up.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "kernels/g2p_particle.hpp"

namespace mmpm {
namespace {

// One float particle at x = 10 moved 100 000 times by 1e-7 (ulp of 10f is
// 9.5e-7, so each move is about 0.1 ulp). The exact end is 10 + 1e5 m,
// with m the float nearest 1e-7. Without xlo every sum rounds back to 10:
// the particle never moves (the failure the compensation is for). With xlo,
// x + xlo is the exact sum within the bound of compensated summation: each
// step rounds only move + lo (|lo| <= ulp(x) / 2), so the error is at most
// the sum over steps of eps (|move| + ulp(x)) = 1.25e-8, against the 0.01
// the uncompensated particle misses (measured: 2.5e-10).
// Both through detail::move_particle, what every G2P path calls, in place
// and into x_next (MUSL).
TEST(PositionSum, FloatMovesBelowHalfAnUlpAddUp) {
  const float move = 1e-7f;
  const int steps = 100000;
  const double exact = 10.0 + steps * double(move);
  for (bool into_next : {false, true}) {
    SCOPED_TRACE(into_next ? "into x_next" : "in place");
    for (bool compensated : {false, true}) {
      std::array<float, 2> x{10.0f, -3.0f}, lo{0.0f, 0.0f}, next{0.0f, 0.0f};
      ParticleView<2, float> P;
      P.n = 1;
      P.x = {&x[0], &x[1]};
      if (compensated) P.xlo = {&lo[0], &lo[1]};
      if (into_next) P.x_next = {&next[0], &next[1]};
      for (int k = 0; k < steps; ++k) {
        detail::move_particle(P, 0, 0, 1.0f, move);
        if (into_next) x[0] = next[0];  // the commit of the gradient pass
      }
      const double end = double(x[0]) + double(lo[0]);
      const double eps = double(std::numeric_limits<float>::epsilon());
      const double ulp = double(std::nextafter(10.01f, 20.0f)) - double(10.01f);
      const double bound = steps * eps * (double(move) + ulp);
      ASSERT_LT(bound, 1.3e-8);
      if (compensated)
        EXPECT_NEAR(end, exact, bound) << "x " << x[0] << " lo " << lo[0];
      else
        EXPECT_EQ(x[0], 10.0f) << "float rounds each 0.1-ulp move away";
      EXPECT_EQ(x[1], -3.0f) << "the other axis did not move";
    }
  }
}

// Moves of many ulps: the low part stays within half an ulp of x (it is
// the exact error of the rounded sum), and a walk of 1000 random moves of
// up to 1e-3 and back returns to its start within the bound of
// compensated summation, sum over steps of eps (|move| + ulp(x)) (each
// step rounds only move + lo): 1.2e-7 over the 2000 steps here, where a
// plain float sum may lose up to half an ulp of x (4.8e-7) in every step.
TEST(PositionSum, FloatWalkReturnsToItsStart) {
  std::array<float, 2> x{12.5f, 0.0f}, lo{0.0f, 0.0f};
  ParticleView<2, float> P;
  P.n = 1;
  P.x = {&x[0], &x[1]};
  P.xlo = {&lo[0], &lo[1]};
  std::vector<float> moves;
  unsigned s = 12345u;
  for (int k = 0; k < 1000; ++k) {
    s = s * 1664525u + 1013904223u;
    moves.push_back(float(double(s) / 4294967296.0 - 0.5) * 2e-3f);
  }
  const double eps = double(std::numeric_limits<float>::epsilon());
  double bound = 0;
  auto step = [&](float m) {
    detail::move_particle(P, 0, 0, 1.0f, m);
    const double ulp = double(std::nextafter(std::abs(x[0]), 1e30f)) - double(std::abs(x[0]));
    EXPECT_LE(std::abs(double(lo[0])), 0.5 * ulp);
    bound += eps * (std::abs(double(m)) + ulp);
  };
  for (float m : moves) step(m);
  for (auto it = moves.rbegin(); it != moves.rend(); ++it) step(-*it);
  EXPECT_NEAR(double(x[0]) + double(lo[0]), 12.5, bound);
  EXPECT_LT(bound, 2e-7);
}

}  // namespace
}  // namespace mmpm
