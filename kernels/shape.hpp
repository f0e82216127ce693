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
// (cell units, l = 1/(2 ppc) <= 1/2). Three nodes suffice: the node
// base - 1 or base + 2 can only be reached when l > 1/2.
// The weight is the hat function averaged over the particle domain,
// S(d) = (H(d + l) - H(d - l)) / (2l) with H the hat's antiderivative, and
// dS/dd = (hat(d + l) - hat(d - l)) / (2l). With c = clamp(s, -1, 1),
// H(s) = 1/2 + c - c|c|/2 and hat(s) = 1 - |c|: no branches, so the
// stencil evaluation does not mispredict as particles move.
struct GimpShape {
  static constexpr int S = 3;
  static constexpr const char* name = "gimp";
  template <class Real>
  static Real clamp1(Real s) {
    return s < Real(-1) ? Real(-1) : (s > Real(1) ? Real(1) : s);
  }
  template <class Real>
  static void node(Real d, Real l, Real& w, Real& dw) {
    const Real inv2l = Real(0.5) / l;
    const Real a = clamp1(d + l), b = clamp1(d - l);
    const Real Ha = Real(0.5) + a - Real(0.5) * a * std::abs(a);
    const Real Hb = Real(0.5) + b - Real(0.5) * b * std::abs(b);
    w = (Ha - Hb) * inv2l;
    dw = (std::abs(b) - std::abs(a)) * inv2l;  // hat(d + l) - hat(d - l), over 2l
  }
  template <class Real>
  static int eval(Real xi, Real l, Real* w, Real* dw) {
    const Real fb = std::floor(xi - Real(0.5));
    const Real r = xi - fb;
    for (int k = 0; k < 3; ++k) node(r - Real(k), l, w[k], dw[k]);
    return int(fb);
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

// Cubic B-spline: four nodes. With r = xi - base in [1, 2) the distances
// to the nodes are r, r-1, r-2, r-3: the first and last always fall in the
// outer piece (1 <= |d| < 2), the middle two in the inner piece, so the
// weights need no branches.
struct BSpline3Shape {
  static constexpr int S = 4;
  static constexpr const char* name = "bspline3";
  template <class Real>
  static int eval(Real xi, Real /*half_width*/, Real* w, Real* dw) {
    const Real fb = std::floor(xi) - Real(1);
    const Real r = xi - fb;                   // in [1, 2)
    const Real q0 = Real(2) - r;              // outer piece, d = r
    const Real a1 = r - Real(1);              // inner piece, d = r - 1 >= 0
    const Real a2 = Real(2) - r;              // inner piece, d = r - 2 < 0, |d| = 2 - r
    const Real q3 = r - Real(1);              // outer piece, d = r - 3, 2 - |d| = r - 1
    w[0] = q0 * q0 * q0 / Real(6);
    dw[0] = Real(-0.5) * q0 * q0;
    w[1] = Real(2) / Real(3) - a1 * a1 + Real(0.5) * a1 * a1 * a1;
    dw[1] = Real(-2) * a1 + Real(1.5) * a1 * a1;
    w[2] = Real(2) / Real(3) - a2 * a2 + Real(0.5) * a2 * a2 * a2;
    dw[2] = Real(2) * a2 - Real(1.5) * a2 * a2;
    w[3] = q3 * q3 * q3 / Real(6);
    dw[3] = Real(0.5) * q3 * q3;
    return int(fb);
  }
};

}  // namespace mmpm
