// MUSL's separation shift advanced inside the gradient pass (G2PWhat
// kSeparationShift, detail::advance_shift; the packed 2D linear gather's
// update_group) against its own pass (kernels/separation_shift.hpp
// advance_separation_shift, the reference: XPIC's interpolation of v*,
// with the same one-particle update detail::advance_shift, so what is
// compared is the gathered S v*, the packed lanes' update and the
// dispatch):
//  - the shift: c + dt S v* - (x_next - x) of the reference to round-off,
//    |difference| <= 1e-12 (double) / 2e-5 (float) of the largest
//    |dt S v*| (the two sum S v* in different orders);
//  - a rigid field's particles keep their shift bit for bit;
//  - L and the committed x are bitwise those of the same pass without the
//    shift: the shift reads the pass's sums and changes nothing else.
// Every shape, 2D and 3D, double and float (the solver's dispatch:
// g2p_range picks the packed, windowed or pointwise gather). Particles:
// runs of 1-5 near one node in one field (so runs share windows, as the
// packed and paired gathers need), x_next = x + a random move, field 1
// rigid for half the seeds.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <vector>

#include "kernels/g2p.hpp"
#include "kernels/separation_shift.hpp"
#include "tests/shape_configs.hpp"
#include "tests/window_test_grid.hpp"

namespace {

using namespace mmpm;

using mmpm_test::CfgNames;
using mmpm_test::kGridCells;

template <class C>
class SeparationShift : public ::testing::Test {};

TYPED_TEST_SUITE(SeparationShift, mmpm_test::WindowConfigs, CfgNames);

struct NoKeys {
  bool any_moved(const std::uint32_t*, std::size_t, std::size_t) const { return false; }
};

template <class Real>
using Columns = std::vector<std::vector<Real>>;

// One particle set's columns: x, x_next, lp, sep_shift (D each), L (D*D).
template <int D, class Real>
struct Set {
  Columns<Real> x, x_next, lp, shift, L;
  std::vector<std::uint8_t> field;
  std::vector<std::uint32_t> key;
  ParticleView<D, Real> view(bool gimp, bool with_shift) {
    ParticleView<D, Real> P;
    P.n = field.size();
    for (int d = 0; d < D; ++d) {
      P.x[d] = x[d].data();
      P.x_next[d] = x_next[d].data();
      P.lp[d] = gimp ? lp[d].data() : nullptr;
      P.sep_shift[d] = with_shift ? shift[d].data() : nullptr;
    }
    for (int c = 0; c < D * D; ++c) P.L[c] = L[c].data();
    P.field = field.data();
    P.key = key.data();
    return P;
  }
};

template <int D, class Real>
Set<D, Real> node_runs(const GridView<D, Real>& G, std::size_t n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  Set<D, Real> s;
  s.x.assign(D, std::vector<Real>(n));
  s.x_next = s.lp = s.shift = s.x;
  s.L.assign(D * D, std::vector<Real>(n, Real(0)));
  s.field.resize(n);
  s.key.assign(n, 0);
  int field = 0;
  for (std::size_t i = 0; i < n;) {
    const std::size_t run = std::min<std::size_t>(n - i, 1 + std::size_t(U(rng) * 5));
    double centre[D];
    for (int d = 0; d < D; ++d) {
      const int node = 3 + int(U(rng) * (kGridCells[d] - 6));
      centre[d] = double(G.origin[d]) + (node + 0.6 * (U(rng) - 0.5)) * double(G.h[d]);
    }
    for (std::size_t k = 0; k < run; ++k, ++i) {
      for (int d = 0; d < D; ++d) {
        const double h = double(G.h[d]);
        s.x[d][i] = Real(centre[d] + 0.24 * (U(rng) - 0.5) * h);
        s.x_next[d][i] = Real(double(s.x[d][i]) + 0.05 * (U(rng) - 0.5) * h);
        s.lp[d][i] = Real((0.1 + 0.4 * U(rng)) * h);
        s.shift[d][i] = Real(0.01 * (U(rng) - 0.5) * h);
      }
      s.field[i] = std::uint8_t(field);
    }
    field ^= 1;
  }
  return s;
}

template <class Real>
bool bitwise_equal(const std::vector<Real>& a, const std::vector<Real>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(Real)) == 0;
}

template <int D, class Shape, class Real>
void check_fused_shift(unsigned seed, bool rigid_field) {
  const bool gimp = std::string(Shape::name) == "gimp";
  GridView<D, Real> G = mmpm_test::skewed_grid<D, Real>();
  G.fields = 2;
  // v* and dv on both fields, random.
  std::mt19937_64 rng(seed + 11);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  const std::size_t total = 2 * G.nodes;
  Columns<Real> vel(D, std::vector<Real>(total)), dvel = vel;
  GridVelocity<D, Real> V;
  std::array<const Real*, D> vstar;
  for (int d = 0; d < D; ++d) {
    for (std::size_t i = 0; i < total; ++i) vel[d][i] = Real(U(rng)), dvel[d][i] = Real(U(rng));
    V.vel[d] = vel[d].data();
    V.dvel[d] = dvel[d].data();
    vstar[std::size_t(d)] = vel[d].data();
  }
  const std::size_t n = 700;
  Set<D, Real> fused = node_runs<D, Real>(G, n, seed), plain = fused, ref = fused;
  const Set<D, Real> start = fused;
  const unsigned char rigid[2] = {0, static_cast<unsigned char>(rigid_field ? 1 : 0)};
  const double rigid_velocity[2][3] = {{0, 0, 0}, {0.5, -0.25, 0.125}};
  G2PParams q;
  q.dt = 0.01;
  q.flip = 0.9;
  q.rigid = rigid;
  q.rigid_velocity = rigid_velocity;
  const Real dt = Real(q.dt);

  // The reference: its own pass, before the commit (it reads x and x_next).
  const ParticleView<D, Real> Pr = ref.view(gimp, true);
  ASSERT_EQ((advance_separation_shift<D, Shape, Real>(Pr, G, vstar, rigid, dt, 0, n)), n);

  constexpr unsigned kGradient = kVelocityGradient | kCommitPosition;
  const auto rf = g2p_range<D, Shape, Real, kGradient | kSeparationShift, true, false, false>(
      fused.view(gimp, true), G, V, q, NoKeys{}, 0, n);
  const auto rp = g2p_range<D, Shape, Real, kGradient, true, false, false>(plain.view(gimp, false),
                                                                           G, V, q, NoKeys{}, 0, n);
  ASSERT_EQ(rf.bad, SIZE_MAX);
  ASSERT_EQ(rp.bad, SIZE_MAX);

  for (int c = 0; c < D * D; ++c) EXPECT_TRUE(bitwise_equal(fused.L[c], plain.L[c])) << "L " << c;
  for (int d = 0; d < D; ++d) {
    EXPECT_TRUE(bitwise_equal(fused.x[d], plain.x[d])) << "x " << d;
    EXPECT_TRUE(bitwise_equal(fused.x[d], start.x_next[d])) << "x committed " << d;
    EXPECT_TRUE(bitwise_equal(plain.shift[d], start.shift[d])) << "no shift pass, no change";
  }
  // The largest |dt S v*|, from the reference's change and the moves.
  double scale = 0;
  std::size_t changed = 0, kept = 0;
  for (int d = 0; d < D; ++d)
    for (std::size_t p = 0; p < n; ++p) {
      const double moved = double(start.x_next[d][p]) - double(start.x[d][p]);
      scale =
          std::max(scale, std::abs(double(ref.shift[d][p]) - double(start.shift[d][p]) + moved));
    }
  ASSERT_GT(scale, 0.0);
  const double tol = sizeof(Real) == 8 ? 1e-12 : 2e-5;
  for (int d = 0; d < D; ++d)
    for (std::size_t p = 0; p < n; ++p) {
      if (rigid[fused.field[p]]) {
        ASSERT_EQ(std::memcmp(&fused.shift[d][p], &start.shift[d][p], sizeof(Real)), 0)
            << "rigid particle " << p << " kept its shift";
        ++kept;
        continue;
      }
      ASSERT_LE(std::abs(double(fused.shift[d][p]) - double(ref.shift[d][p])), tol * scale)
          << "particle " << p << " axis " << d;
      changed += fused.shift[d][p] != start.shift[d][p];
    }
  EXPECT_GT(changed, std::size_t(n / 4)) << "the shift moved";
  if (rigid_field) {
    EXPECT_GT(kept, std::size_t(n / 4)) << "field 1 is rigid";
  }
}

TYPED_TEST(SeparationShift, InTheGradientPassAsInItsOwnPass) {
  constexpr int D = TypeParam::D;
  using Shape = typename TypeParam::Shape;
  using Real = typename TypeParam::Real;
  check_fused_shift<D, Shape, Real>(4101, false);
  check_fused_shift<D, Shape, Real>(4102, true);
}

}  // namespace
