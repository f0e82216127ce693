// Shape functions in one dimension; the D-dimensional weight is the tensor
// product (ALGORITHM §1 uses S_ip and G_ip). Coordinates are in cell units:
// xi = (x - origin) / h. Every function fills the S weights of the nodes
// base .. base + S - 1 and their derivatives d/dxi (the caller divides by h).
#pragma once

#include <cmath>

namespace mmpm {

// Linear hat functions: two nodes per direction.
struct LinearShape {
  static constexpr int S = 2;
  static constexpr const char* name = "linear";
  template <class Real>
  static int eval(Real xi, Real /*half_width*/, Real* w, Real* dw) {
    const Real fb = std::floor(xi);
    const Real r = xi - fb;
    w[0] = Real(1) - r;
    w[1] = r;
    dw[0] = Real(-1);
    dw[1] = Real(1);
    return int(fb);
  }
};

// uGIMP (Bardenhagen & Kober 2004) with a constant particle half-width l
// (cell units, l = 1/(2 ppc) ≤ 1/2). Three nodes suffice: the node
// base - 1 or base + 2 can only be reached when l > 1/2.
struct GimpShape {
  static constexpr int S = 3;
  static constexpr const char* name = "gimp";
  template <class Real>
  static void node(Real d, Real l, Real& w, Real& dw) {
    const Real a = std::abs(d);
    const Real sgn = d < 0 ? Real(-1) : Real(1);
    if (a < l) {
      w = Real(1) - (d * d + l * l) / (Real(2) * l);
      dw = -d / l;
    } else if (a < Real(1) - l) {
      w = Real(1) - a;
      dw = -sgn;
    } else if (a < Real(1) + l) {
      const Real q = Real(1) + l - a;
      w = q * q / (Real(4) * l);
      dw = -sgn * q / (Real(2) * l);
    } else {
      w = Real(0);
      dw = Real(0);
    }
  }
  template <class Real>
  static int eval(Real xi, Real l, Real* w, Real* dw) {
    const int base = int(std::floor(xi - Real(0.5)));
    for (int k = 0; k < 3; ++k) node(xi - Real(base + k), l, w[k], dw[k]);
    return base;
  }
};

// Quadratic B-spline: three nodes.
struct BSpline2Shape {
  static constexpr int S = 3;
  static constexpr const char* name = "bspline2";
  template <class Real>
  static int eval(Real xi, Real /*half_width*/, Real* w, Real* dw) {
    const Real fb = std::floor(xi - Real(0.5));
    const Real r = xi - fb;  // in [0.5, 1.5)
    const Real a = Real(1.5) - r, b = r - Real(1), c = r - Real(0.5);
    w[0] = Real(0.5) * a * a;
    w[1] = Real(0.75) - b * b;
    w[2] = Real(0.5) * c * c;
    dw[0] = -a;
    dw[1] = Real(-2) * b;
    dw[2] = c;
    return int(fb);
  }
};

// Cubic B-spline: four nodes.
struct BSpline3Shape {
  static constexpr int S = 4;
  static constexpr const char* name = "bspline3";
  template <class Real>
  static int eval(Real xi, Real /*half_width*/, Real* w, Real* dw) {
    const Real fb = std::floor(xi) - Real(1);
    const Real r = xi - fb;  // in [1, 2): distances r, r-1, r-2, r-3
    for (int k = 0; k < 4; ++k) {
      const Real d = r - Real(k);
      const Real a = std::abs(d);
      const Real sgn = d < 0 ? Real(-1) : Real(1);
      if (a < Real(1)) {
        w[k] = Real(2) / Real(3) - a * a + Real(0.5) * a * a * a;
        dw[k] = sgn * (Real(-2) * a + Real(1.5) * a * a);
      } else {
        const Real q = Real(2) - a;
        w[k] = q * q * q / Real(6);
        dw[k] = -sgn * Real(0.5) * q * q;
      }
    }
    return int(fb);
  }
};

}  // namespace mmpm
