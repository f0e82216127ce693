// WindowBuilder::build_batch (kernels/window.hpp) gives, particle by
// particle, bitwise the window of WindowBuilder::build and the same on-grid
// verdict: it computes the window bases and distances of a whole batch in a
// loop vectorised across particles, and must not change any transfer's
// result.
//
// Particles: seeded random positions over the grid and one cell beyond it
// on every side, plus positions exactly on each direction's limits (the
// lowest allowed xi, which is in, and n - margin, which is out), NaN, +-inf
// and 1e30 (a wild position must be rejected, not converted to int). uGIMP
// half-widths vary per particle. Every shape, 2D and 3D, double and float;
// batch sizes 1, 7 and 32 (kWeightBatch) from varying first particles.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "kernels/shape.hpp"
#include "kernels/window.hpp"
#include "tests/shape_configs.hpp"
#include "tests/window_test_grid.hpp"

namespace {

using namespace mmpm;

using mmpm_test::CfgNames;

template <class C>
class WindowBatch : public ::testing::Test {};

TYPED_TEST_SUITE(WindowBatch, mmpm_test::WindowConfigs, CfgNames);

// The grid of these tests: cells, spacing and origin differ per direction.
constexpr const int (&cells)[3] = mmpm_test::kGridCells;
constexpr const double (&h)[3] = mmpm_test::kGridH;
constexpr const double (&origin)[3] = mmpm_test::kGridOrigin;
template <int D, class Real>
GridView<D, Real> test_grid() {
  return mmpm_test::skewed_grid<D, Real>();
}

TYPED_TEST(WindowBatch, SameWindowsAndVerdictsAsOneByOne) {
  constexpr int D = TypeParam::D;
  using Shape = typename TypeParam::Shape;
  using Real = typename TypeParam::Real;
  using Builder = WindowBuilder<D, Shape, Real>;
  using Win = Window<D, Shape, Real>;

  const GridView<D, Real> G = test_grid<D, Real>();

  // Positions: random, then the special ones in direction 0 (mid-grid in the
  // others).
  const std::size_t n_random = 600;
  std::vector<double> special_xi = {Builder::kLoXi,
                                    double(cells[0] + 1) - Builder::kHiMargin,
                                    std::nextafter(double(Builder::kLoXi), -1.0),
                                    0.0,
                                    double(cells[0]),
                                    std::numeric_limits<double>::quiet_NaN(),
                                    std::numeric_limits<double>::infinity(),
                                    -std::numeric_limits<double>::infinity(),
                                    1e30,
                                    -1e30};
  const std::size_t n = n_random + special_xi.size();
  std::vector<Real> x[D], lp[D];
  ParticleView<D, Real> P;
  P.n = n;
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int d = 0; d < D; ++d) {
    x[d].resize(n);
    lp[d].resize(n);
    for (std::size_t p = 0; p < n; ++p) {
      const double xi = -1.0 + (cells[d] + 2.0) * u(rng);  // one cell beyond each side
      x[d][p] = Real(origin[d] + xi * h[d]);
      lp[d][p] = Real(0.1 + 0.15 * u(rng));
    }
    P.x[std::size_t(d)] = x[d].data();
    if (std::is_same_v<Shape, GimpShape>) P.lp[std::size_t(d)] = lp[d].data();
  }
  for (std::size_t k = 0; k < special_xi.size(); ++k) {
    x[0][n_random + k] = Real(origin[0] + special_xi[k] * h[0]);
    for (int d = 1; d < D; ++d) x[d][n_random + k] = Real(origin[d] + 0.5 * cells[d] * h[d]);
  }

  const Builder builder(G);
  std::vector<Win> one(n);
  std::vector<char> one_ok(n);
  std::size_t inside = 0;
  for (std::size_t p = 0; p < n; ++p) {
    one_ok[p] = builder.build(P, p, one[p]);
    inside += one_ok[p] != 0;
  }
  // Both verdicts occur, and the lowest allowed xi is on the grid.
  EXPECT_GT(inside, n / 5);
  EXPECT_LT(inside, n);
  EXPECT_TRUE(one_ok[n_random]);
  EXPECT_FALSE(one_ok[n_random + 1]);

  for (std::size_t batch : {std::size_t(1), std::size_t(7), kWeightBatch}) {
    for (std::size_t first = 0; first < n; first += batch) {
      const std::size_t count = std::min(batch, n - first);
      Win w[kWeightBatch];
      bool ok[kWeightBatch];
      builder.build_batch(P, first, count, w, ok);
      for (std::size_t i = 0; i < count; ++i) {
        const std::size_t p = first + i;
        ASSERT_EQ(ok[i], one_ok[p] != 0) << "particle " << p << ", batch " << batch;
        if (!ok[i]) continue;
        ASSERT_EQ(w[i].base, one[p].base) << "particle " << p;
        ASSERT_EQ(std::memcmp(&w[i].wa, &one[p].wa, sizeof(w[i].wa)), 0) << "particle " << p;
        ASSERT_EQ(std::memcmp(&w[i].dwa, &one[p].dwa, sizeof(w[i].dwa)), 0) << "particle " << p;
      }
    }
  }
}

// A view without half-width columns (every particle has P.lp_all, as the
// Stepper builds it when all bodies share one particle spacing) gives
// bitwise the windows of columns that hold those values everywhere: the
// batch's shared lanes are built once, the column's per particle. Also with
// a column in one direction only (the Stepper's choice when the spacings
// differ in that direction alone).
TYPED_TEST(WindowBatch, SharedHalfWidthGivesTheColumnsWindows) {
  constexpr int D = TypeParam::D;
  using Shape = typename TypeParam::Shape;
  using Real = typename TypeParam::Real;
  using Builder = WindowBuilder<D, Shape, Real>;
  using Win = Window<D, Shape, Real>;

  const GridView<D, Real> G = test_grid<D, Real>();
  const Real shared_l[3] = {Real(0.3), Real(0.2), Real(0.35)};
  const std::size_t n = 300;
  std::vector<Real> x[D], lp[D];
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  ParticleView<D, Real> columns, shared, mixed;
  for (auto* P : {&columns, &shared, &mixed}) P->n = n;
  for (int d = 0; d < D; ++d) {
    x[d].resize(n);
    lp[d].assign(n, shared_l[d]);
    for (std::size_t p = 0; p < n; ++p)
      x[d][p] = Real(origin[d] + (0.6 + (cells[d] - 1.2) * u(rng)) * h[d]);
    for (auto* P : {&columns, &shared, &mixed}) P->x[std::size_t(d)] = x[d].data();
    columns.lp[std::size_t(d)] = lp[d].data();
    shared.lp_all[std::size_t(d)] = shared_l[d];
    mixed.lp_all[std::size_t(d)] = shared_l[d];
  }
  mixed.lp[0] = lp[0].data();

  const Builder builder(G);
  std::size_t compared = 0;
  for (std::size_t first = 0; first < n; first += kWeightBatch) {
    const std::size_t count = std::min(kWeightBatch, n - first);
    Win wc[kWeightBatch], ws[kWeightBatch], wm[kWeightBatch];
    bool okc[kWeightBatch], oks[kWeightBatch], okm[kWeightBatch];
    builder.build_batch(columns, first, count, wc, okc);
    builder.build_batch(shared, first, count, ws, oks);
    builder.build_batch(mixed, first, count, wm, okm);
    for (std::size_t i = 0; i < count; ++i) {
      const std::size_t p = first + i;
      ASSERT_EQ(okc[i], oks[i]) << "particle " << p;
      ASSERT_EQ(okc[i], okm[i]) << "particle " << p;
      if (!okc[i]) continue;
      Win one;
      ASSERT_TRUE(builder.build(shared, p, one));
      for (const Win* w : {&ws[i], &wm[i], &one}) {
        ASSERT_EQ(w->base, wc[i].base) << "particle " << p;
        ASSERT_EQ(std::memcmp(&w->wa, &wc[i].wa, sizeof(w->wa)), 0) << "particle " << p;
        ASSERT_EQ(std::memcmp(&w->dwa, &wc[i].dwa, sizeof(w->dwa)), 0) << "particle " << p;
      }
      ++compared;
    }
  }
  EXPECT_GT(compared, n / 2);
  // The half-width matters to uGIMP: another shared value changes its windows.
  if constexpr (std::is_same_v<Shape, GimpShape>) {
    ParticleView<D, Real> other = shared;
    other.lp_all[0] = Real(0.1);
    Win a[kWeightBatch], b[kWeightBatch];
    bool oka[kWeightBatch], okb[kWeightBatch];
    builder.build_batch(shared, 0, kWeightBatch, a, oka);
    builder.build_batch(other, 0, kWeightBatch, b, okb);
    bool differ = false;
    for (std::size_t i = 0; i < kWeightBatch; ++i)
      differ = differ || (oka[i] && std::memcmp(&a[i].wa, &b[i].wa, sizeof(a[i].wa)) != 0);
    EXPECT_TRUE(differ);
  }
}

}  // namespace
