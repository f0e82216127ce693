// XPIC's interpolation of a grid field to the particles (kernels/xpic.hpp):
// the windowed kernel the solver runs gives, particle by particle, the
// stencil's node-by-node sum to round-off, reads each particle's own
// field, and stops at the first particle whose stencil leaves the grid as
// the reference does. Every shape, 2D and 3D, double and float.
//
// Particles: seeded random positions over the grid (uGIMP half-widths per
// particle), two velocity fields, a smooth grid field that differs between
// the fields; one particle placed off the grid at a known index.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <random>
#include <type_traits>
#include <vector>

#include "kernels/xpic.hpp"
#include "tests/shape_configs.hpp"
#include "tests/window_test_grid.hpp"

namespace {

using namespace mmpm;

using mmpm_test::CfgNames;

template <class C>
class XpicInterpolation : public ::testing::Test {};

TYPED_TEST_SUITE(XpicInterpolation, mmpm_test::WindowConfigs, CfgNames);

using mmpm_test::kGridCells;
using mmpm_test::kGridH;
using mmpm_test::kGridOrigin;

TYPED_TEST(XpicInterpolation, WindowedEqualsTheStencilsSum) {
  constexpr int D = TypeParam::D;
  using Shape = typename TypeParam::Shape;
  using Real = typename TypeParam::Real;
  GridView<D, Real> G = mmpm_test::skewed_grid<D, Real>();
  G.fields = 2;
  ASSERT_TRUE((Window<D, Shape, Real>::fits(G)));

  // u: a smooth field per direction, another one on field 1.
  std::vector<Real> u_storage(std::size_t(D) * 2 * G.nodes);
  std::array<const Real*, D> u;
  for (int d = 0; d < D; ++d) {
    Real* ud = u_storage.data() + std::size_t(d) * 2 * G.nodes;
    u[d] = ud;
    for (std::size_t i = 0; i < G.nodes; ++i) {
      const auto x = G.position(i);
      ud[i] = Real(std::sin(1.3 * x[0] - 0.7 * x[1] + d) + 0.1 * x[2]);
      ud[G.nodes + i] = Real(std::cos(0.4 * x[0] + 1.1 * x[1] - d) - 0.2 * x[2]);
    }
  }

  // Particles three cells or more from every edge (every stencil fits), in
  // random order: the kernel does not rely on the solver's sorting.
  const std::size_t n = 500, off_grid = 333;
  std::vector<Real> x[D], lp[D];
  std::vector<std::uint8_t> field(n);
  ParticleView<D, Real> P;
  P.n = n;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> r(0.0, 1.0);
  for (int d = 0; d < D; ++d) {
    x[d].resize(n);
    lp[d].resize(n);
    for (std::size_t p = 0; p < n; ++p) {
      x[d][p] = Real(kGridOrigin[d] + (3.0 + (kGridCells[d] - 6.0) * r(rng)) * kGridH[d]);
      lp[d][p] = Real((0.15 + 0.1 * r(rng)) * kGridH[d]);
    }
    P.x[std::size_t(d)] = x[d].data();
    if (std::is_same_v<Shape, GimpShape>) P.lp[std::size_t(d)] = lp[d].data();
  }
  for (std::size_t p = 0; p < n; ++p) field[p] = std::uint8_t(r(rng) < 0.5 ? 0 : 1);
  P.field = field.data();

  auto run = [&](bool windowed, std::size_t end, std::vector<Real>& storage) {
    storage.assign(std::size_t(D) * n, Real(-7));
    std::array<Real*, D> out;
    for (int d = 0; d < D; ++d) out[d] = storage.data() + std::size_t(d) * n;
    return windowed ? interpolate_to_particles_windowed<D, Shape, Real>(P, G, u, into_arrays(out),
                                                                        0, end)
                    : interpolate_to_particles_pointwise<D, Shape, Real>(P, G, u, into_arrays(out),
                                                                         0, end);
  };
  std::vector<Real> win, ref;
  ASSERT_EQ(run(true, n, win), n);
  ASSERT_EQ(run(false, n, ref), n);
  // Round-off only. The two evaluate the weights differently (the window
  // from the distance to its base, the stencil from the node's own), so a
  // weight may differ by the rounding of the cell coordinate, up to
  // kGridCells[0] = 12 (eps each), times the weight's slope per cell (1 for the
  // B-splines and linear; 1 / (2 l / h) <= 3.4 for uGIMP, l >= 0.15 h), in
  // each of D factors; |u| < 1.4. Measured: 1-6 eps (linear, B-splines),
  // 21.5-22.5 (2D uGIMP), 35 (3D uGIMP), against bounds of 36-55 and
  // 124-186.
  // A wrong weight or node would differ by ~0.1.
  const double eps = double(std::numeric_limits<Real>::epsilon());
  const double slope = std::is_same_v<Shape, GimpShape> ? 1 / (2 * 0.15) : 1.0;
  const double bound = eps * (1 + kGridCells[0]) * slope * 1.4 * D;
  double worst = 0;
  for (std::size_t i = 0; i < win.size(); ++i) {
    ASSERT_TRUE(std::isfinite(double(win[i])));
    worst = std::max(worst, std::abs(double(win[i]) - double(ref[i])));
  }
  std::printf("[xpic interpolation] %dD %s %s: windowed vs stencil %.2f eps\n", D, Shape::name,
              sizeof(Real) == 8 ? "double" : "float", worst / eps);
  EXPECT_LT(worst, bound);
  // The field matters: the same particles on the other field read other values.
  for (std::size_t p = 0; p < n; ++p) field[p] = std::uint8_t(1 - field[p]);
  std::vector<Real> swapped;
  ASSERT_EQ(run(true, n, swapped), n);
  double moved = 0;
  for (std::size_t i = 0; i < win.size(); ++i)
    moved = std::max(moved, std::abs(double(swapped[i]) - double(win[i])));
  EXPECT_GT(moved, 0.1);

  // A particle off the grid: both stop there; the ones before it are written.
  x[0][off_grid] = Real(kGridOrigin[0] - 2 * kGridH[0]);
  EXPECT_EQ(run(true, n, win), off_grid);
  EXPECT_EQ(run(false, n, ref), off_grid);
  EXPECT_NE(win[off_grid - 1], Real(-7));
  EXPECT_EQ(win[off_grid], Real(-7));
}

}  // namespace
