// Shape functions (kernels/shape.hpp) and their tensor products
// (kernels/weights.hpp Stencil): partition of unity, zero gradient sum,
// linear reproduction, derivative = finite difference of the weight, and the
// uGIMP weight = the analytic average of the hat function over the particle.
//
// Tolerances: sums in double to 1e-12 (absolute; the weights are O(1), the
// gradients O(1/h) with h >= 0.3, coordinates O(10) for the reproduction
// checks, hence 1e-11 there); float to 2e-6 (~16 ulp). Finite differences:
// central, step 1e-7 cells, compared to 1e-6 (truncation <= |f''| e / 4 with
// |f''| <= 1/l = 8, rounding ~1e-9); for the C0 linear hat the points within
// 1e-5 of a node are skipped. Random points: 2000 per shape in 1D, 300 per
// shape in 2D and 3D, xi in [3, 30) cells.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstddef>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "kernels/grid_view.hpp"
#include "kernels/particle_view.hpp"
#include "kernels/shape.hpp"
#include "kernels/weights.hpp"

namespace {

using namespace mmpm;

template <class S, int InvL = 0>
struct Case {
  using Shape = S;
  // uGIMP half-width (cell units): 1 / InvL; 0 for the shapes without one.
  static double l() { return InvL ? 1.0 / InvL : 0.0; }
};

using LinearCase = Case<LinearShape>;
using Gimp4Case = Case<GimpShape, 4>;  // l = 0.25  (2 particles per cell)
using Gimp8Case = Case<GimpShape, 8>;  // l = 0.125 (4 particles per cell)
using Gimp2Case = Case<GimpShape, 2>;  // l = 0.5   (1 particle per cell)
using BSpline2Case = Case<BSpline2Shape>;
using BSpline3Case = Case<BSpline3Shape>;

template <class C>
class ShapeFunctions : public ::testing::Test {};

using AllShapes =
    ::testing::Types<LinearCase, Gimp4Case, Gimp8Case, Gimp2Case, BSpline2Case, BSpline3Case>;

struct CaseNames {
  template <class C>
  static std::string GetName(int) {
    using S = typename C::Shape;
    std::string n = S::name;
    if (C::l() > 0) n += "_l" + std::to_string(int(std::lround(1.0 / C::l())));
    return n;
  }
};
TYPED_TEST_SUITE(ShapeFunctions, AllShapes, CaseNames);

// Weight of absolute node j at xi (0 when j is outside the returned stencil).
template <class Shape, class Real>
Real weight_of_node(Real xi, Real l, int j) {
  Real w[Shape::S], dw[Shape::S];
  const int base = Shape::eval(xi, l, w, dw);
  return j >= base && j < base + Shape::S ? w[j - base] : Real(0);
}

bool near_integer(double x, double tol) {
  return std::abs(x - std::round(x)) < tol;
}

template <class Shape, class Real>
void check_1d(double l, double tol, int points, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(3.0, 30.0);
  for (int n = 0; n < points; ++n) {
    const Real xi = Real(U(rng));
    Real w[Shape::S], dw[Shape::S];
    const int base = Shape::eval(xi, Real(l), w, dw);
    double sw = 0, sdw = 0, sx = 0, sdx = 0;
    for (int k = 0; k < Shape::S; ++k) {
      EXPECT_GE(w[k], Real(0)) << "xi=" << xi << " k=" << k;
      sw += double(w[k]);
      sdw += double(dw[k]);
      sx += double(w[k]) * double(base + k);
      sdx += double(dw[k]) * double(base + k);
    }
    ASSERT_NEAR(sw, 1.0, tol) << "partition of unity, xi=" << xi;
    ASSERT_LT(std::abs(sdw), tol) << "gradient sum, xi=" << xi;
    // Linear fields are reproduced exactly (every shape here is complete to first order).
    ASSERT_NEAR(sx, double(xi), 30 * tol) << "linear reproduction, xi=" << xi;
    ASSERT_NEAR(sdx, 1.0, 30 * tol) << "gradient of x, xi=" << xi;
  }
}

TYPED_TEST(ShapeFunctions, OneDimensionalSumsDouble) {
  using S = typename TypeParam::Shape;
  check_1d<S, double>(TypeParam::l(), 1e-12, 2000, 11);
}

TYPED_TEST(ShapeFunctions, OneDimensionalSumsFloat) {
  using S = typename TypeParam::Shape;
  check_1d<S, float>(TypeParam::l(), 2e-6, 2000, 12);
}

// The stencil is wide enough: the nodes just outside it carry no weight
// (checked with the exact per-node uGIMP function; for the others the
// partition of unity of the returned weights already implies it).
TEST(ShapeFunctions, GimpStencilCoversTheSupport) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> U(3.0, 30.0);
  for (double l : {0.125, 0.25, 0.5}) {
    for (int n = 0; n < 2000; ++n) {
      const double xi = U(rng);
      double w[3], dw[3];
      const int base = GimpShape::eval(xi, l, w, dw);
      for (int j : {base - 1, base + 3}) {
        double wj, dwj;
        GimpShape::node(xi - double(j), l, wj, dwj);
        ASSERT_EQ(wj, 0.0) << "l=" << l << " xi=" << xi << " node " << j;
        ASSERT_EQ(dwj, 0.0);
      }
    }
  }
}

TYPED_TEST(ShapeFunctions, DerivativeIsFiniteDifferenceOfWeight) {
  using S = typename TypeParam::Shape;
  const double l = TypeParam::l();
  const bool c0 = std::string(S::name) == "linear";  // kinks at the nodes
  std::mt19937_64 rng(21);
  std::uniform_real_distribution<double> U(3.0, 30.0);
  const double e = 1e-7;
  int checked = 0;
  for (int n = 0; n < 2000; ++n) {
    const double xi = U(rng);
    if (c0 && near_integer(xi, 1e-5)) continue;
    double w[S::S], dw[S::S];
    const int base = S::eval(xi, l, w, dw);
    for (int k = 0; k < S::S; ++k) {
      const double fd =
          (weight_of_node<S>(xi + e, l, base + k) - weight_of_node<S>(xi - e, l, base + k)) /
          (2 * e);
      ASSERT_NEAR(dw[k], fd, 1e-6) << "xi=" << xi << " node " << base + k;
      // The weight itself is continuous across the stencil switch.
      ASSERT_NEAR(weight_of_node<S>(xi + e, l, base + k), w[k], 1e-6);
      ++checked;
    }
  }
  EXPECT_GT(checked, 1000 * S::S);
}

// ----------------------------------------------- uGIMP = averaged hat --

// Antiderivative of the hat N(x) = max(0, 1 - |x|).
double hat_integral(double x) {
  if (x <= -1) return 0;
  if (x <= 0) return 0.5 * (x + 1) * (x + 1);
  if (x <= 1) return 1 - 0.5 * (1 - x) * (1 - x);
  return 1;
}
double hat(double x) {
  return std::max(0.0, 1 - std::abs(x));
}

// uGIMP weight of a node at distance d (cell units) from a particle of half-width l:
// (1/2l) * integral of N over [d - l, d + l]; its derivative in d by Leibniz' rule.
double ugimp_weight(double d, double l) {
  return (hat_integral(d + l) - hat_integral(d - l)) / (2 * l);
}
double ugimp_derivative(double d, double l) {
  return (hat(d + l) - hat(d - l)) / (2 * l);
}

TEST(ShapeFunctions, GimpWeightEqualsAnalyticIntegralHandValues) {
  struct Hand {
    double d, l, w;
  };
  // Worked by hand from the integral (comments: which branch of GimpShape::node).
  const Hand hand[] = {
      {0.0, 0.25, 0.875},     // |d| < l
      {0.1, 0.25, 0.855},     // |d| < l
      {-0.1, 0.25, 0.855},    // symmetric
      {0.5, 0.25, 0.5},       // l <= |d| < 1 - l: plain hat
      {1.0, 0.25, 0.0625},    // 1 - l <= |d| < 1 + l
      {1.25, 0.25, 0.0},      // outside the support
      {0.3, 0.5, 0.66},       // l = 1/2
      {1.2, 0.5, 0.045},      // l = 1/2, outer branch
      {0.9, 0.125, 0.10125},  // l = 1/8, outer branch
      {-0.9, 0.125, 0.10125},
  };
  for (const Hand& h : hand) {
    double w, dw;
    GimpShape::node(h.d, h.l, w, dw);
    EXPECT_NEAR(w, h.w, 1e-15) << "d=" << h.d << " l=" << h.l;
    EXPECT_NEAR(ugimp_weight(h.d, h.l), h.w, 1e-15) << "the reference itself, d=" << h.d;
  }
}

TEST(ShapeFunctions, GimpWeightAndDerivativeEqualAnalyticIntegralRandom) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> D(-1.6, 1.6), L(0.05, 0.5);
  for (int n = 0; n < 5000; ++n) {
    const double d = D(rng), l = L(rng);
    double w, dw;
    GimpShape::node(d, l, w, dw);
    ASSERT_NEAR(w, ugimp_weight(d, l), 1e-13) << "d=" << d << " l=" << l;
    ASSERT_NEAR(dw, ugimp_derivative(d, l), 1e-13) << "d=" << d << " l=" << l;
  }
}

// ------------------------------------------------- 2D and 3D via Stencil --

template <int D, class Shape, class Real>
struct StencilFixture {
  // A grid of 40 nodes per direction with unequal cell sizes and an offset origin.
  GridView<D, Real> G;
  std::array<std::vector<Real>, D> x, lp;
  ParticleView<D, Real> P;
  std::array<Real, 3> inv_h{};

  explicit StencilFixture(double l) {
    const double h[3] = {0.3, 0.7, 0.45}, o[3] = {-1.2, 0.5, 2.0};
    G.nodes = 1;
    for (int d = 0; d < D; ++d) {
      G.nodes_per_dim[d] = 40;
      G.h[d] = Real(h[d]);
      G.origin[d] = Real(o[d]);
      G.nodes *= 40;
    }
    for (int d = 0; d < 3; ++d) inv_h[d] = Real(1) / G.h[d];
    P.n = 1;
    for (int d = 0; d < D; ++d) {
      x[d].assign(1, Real(0));
      P.x[d] = x[d].data();
      if (l > 0) {
        // Different half-widths per direction are allowed (rectangular particles).
        lp[d].assign(1, Real(d == 1 ? l * 0.5 : l));
        P.lp[d] = lp[d].data();
      }
    }
  }
  // Weights by absolute node index.
  std::map<std::size_t, Real> weights() const {
    Stencil<D, Shape, Real> st{};
    EXPECT_TRUE(st.build(P, G, inv_h, 0));
    std::map<std::size_t, Real> m;
    for (int k = 0; k < st.count; ++k) m[st.base + st.node[k]] = st.w[k];
    return m;
  }
};

template <int D, class Shape, class Real>
void check_stencil(double l, double tol, unsigned seed) {
  StencilFixture<D, Shape, Real> f(l);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(3.0, 30.0);
  const bool c0 = std::string(Shape::name) == "linear";
  for (int n = 0; n < 300; ++n) {
    double xi[D];
    for (int d = 0; d < D; ++d) {
      do xi[d] = U(rng);
      while (c0 && near_integer(xi[d], 1e-4));
      f.x[d][0] = Real(double(f.G.origin[d]) + xi[d] * double(f.G.h[d]));
    }
    Stencil<D, Shape, Real> st{};
    ASSERT_TRUE(st.build(f.P, f.G, f.inv_h, 0));
    double sw = 0, sg[D] = {}, sx[D] = {}, sgx[D][D] = {};
    for (int k = 0; k < st.count; ++k) {
      const auto xn = f.G.position(st.base + st.node[k]);
      sw += double(st.w[k]);
      for (int d = 0; d < D; ++d) {
        sg[d] += double(st.g[k][d]);
        sx[d] += double(st.w[k]) * double(xn[d]);
        for (int e = 0; e < D; ++e) sgx[d][e] += double(st.g[k][e]) * double(xn[d]);
      }
    }
    ASSERT_NEAR(sw, 1.0, tol) << D << "D partition of unity";
    for (int d = 0; d < D; ++d) {
      ASSERT_LT(std::abs(sg[d]), tol) << D << "D gradient sum, direction " << d;
      ASSERT_NEAR(sx[d], double(f.x[d][0]), 10 * tol) << "reproduces x_" << d;
      for (int e = 0; e < D; ++e)
        ASSERT_NEAR(sgx[d][e], d == e ? 1.0 : 0.0, 10 * tol) << "grad x_" << d << " along " << e;
    }
    // Gradient = central finite difference of the tensor-product weight (double only).
    if constexpr (sizeof(Real) == 8) {
      for (int d = 0; d < D; ++d) {
        const Real x0 = f.x[d][0], e = Real(1e-7) * f.G.h[d];
        f.x[d][0] = x0 + e;
        const auto wp = f.weights();
        f.x[d][0] = x0 - e;
        const auto wm = f.weights();
        f.x[d][0] = x0;
        for (int k = 0; k < st.count; ++k) {
          const std::size_t node = st.base + st.node[k];
          const double a = wp.count(node) ? wp.at(node) : 0.0,
                       b = wm.count(node) ? wm.at(node) : 0.0;
          ASSERT_NEAR(double(st.g[k][d]), (a - b) / (2 * e), 1e-6 * double(f.inv_h[d]))
              << D << "D gradient component " << d << " at node " << node;
        }
      }
    }
  }
}

TYPED_TEST(ShapeFunctions, TwoDimensionalStencilDouble) {
  check_stencil<2, typename TypeParam::Shape, double>(TypeParam::l(), 1e-12, 31);
}
TYPED_TEST(ShapeFunctions, ThreeDimensionalStencilDouble) {
  check_stencil<3, typename TypeParam::Shape, double>(TypeParam::l(), 1e-12, 32);
}
TYPED_TEST(ShapeFunctions, TwoDimensionalStencilFloat) {
  check_stencil<2, typename TypeParam::Shape, float>(TypeParam::l(), 2e-6 * 4, 33);
}
TYPED_TEST(ShapeFunctions, ThreeDimensionalStencilFloat) {
  check_stencil<3, typename TypeParam::Shape, float>(TypeParam::l(), 2e-6 * 4, 34);
}

}  // namespace
