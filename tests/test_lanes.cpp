// lanes_sum8 (kernels/lanes.hpp), the 2D windowed gather's reduction of its
// eight dot products, against the per-direction reduction it replaced
// (lanes_fold4 of each vector, then lanes_sum4 of four): every sum bitwise
// equal, for 8- and 16-lane vectors in double and float. The inputs span
// 12 orders of magnitude and both signs, so a different order of the adds
// would round differently (the check that it does: a serial sum of the
// same lanes differs from the tree in at least one case).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "kernels/lanes.hpp"

namespace {

using namespace mmpm;

template <class Real, int n>
void check_sum8_bits(unsigned seed) {
  using V = Lanes<Real, n>;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> mantissa(-1.0, 1.0);
  std::uniform_int_distribution<int> exponent(-6, 6);
  int serial_differs = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    V v[8];
    for (auto& x : v)
      for (int l = 0; l < n; ++l) x[l] = Real(mantissa(rng) * std::pow(10.0, exponent(rng)));
    const Lanes<Real, 8> got = lanes_sum8<Real, n>(v);
    Real want[8];
    for (int h = 0; h < 2; ++h) {
      const Lanes<Real, 4> s =
          lanes_sum4(lanes_fold4<Real, n>(v[4 * h]), lanes_fold4<Real, n>(v[4 * h + 1]),
                     lanes_fold4<Real, n>(v[4 * h + 2]), lanes_fold4<Real, n>(v[4 * h + 3]));
      for (int k = 0; k < 4; ++k) want[4 * h + k] = s[k];
    }
    for (int k = 0; k < 8; ++k) {
      const Real g = got[k];
      ASSERT_EQ(std::memcmp(&g, &want[k], sizeof(Real)), 0)
          << "trial " << trial << " sum " << k << ": " << g << " vs " << want[k];
      const Real serial = lanes_sum<Real, n>(v[k]);
      serial_differs += std::memcmp(&serial, &want[k], sizeof(Real)) != 0;
    }
  }
  EXPECT_GT(serial_differs, 0) << "the inputs do not tell one order of sums from another";
}

TEST(Lanes, Sum8IsTheFoldAndSum4BitwiseDouble8) {
  check_sum8_bits<double, 8>(11);
}
TEST(Lanes, Sum8IsTheFoldAndSum4BitwiseDouble16) {
  check_sum8_bits<double, 16>(12);
}
TEST(Lanes, Sum8IsTheFoldAndSum4BitwiseFloat8) {
  check_sum8_bits<float, 8>(13);
}
TEST(Lanes, Sum8IsTheFoldAndSum4BitwiseFloat16) {
  check_sum8_bits<float, 16>(14);
}

}  // namespace
