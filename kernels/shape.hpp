// Shape functions in one dimension; the D-dimensional weight is the tensor
// product (ALGORITHM §1 uses S_ip and G_ip). Coordinates are in cell units:
// xi = (x - origin) / h. Two forms:
//  - eval(): the S weights of the nodes base .. base + S - 1 and their
//    derivatives d/dxi (the caller divides by h); the pointwise kernels.
//  - lanes(): weight and derivative of one node at distance d = xi - node,
//    elementwise on a vector of distances (kernels/lanes.hpp), zero beyond
//    the function's reach; the window kernels (kernels/window.hpp) evaluate
//    all window nodes of all directions in one call.
#pragma once

#include <array>
#include <cmath>

#include "kernels/lanes.hpp"

namespace mmpm {

// Linear hat functions: two nodes per direction.
struct LinearShape {
  static constexpr int S = 2;
  static constexpr int W = 2;          // window nodes per direction (kernels/window.hpp)
  static constexpr int window_lo = 0;  // window starts at cell - window_lo
  static constexpr bool nearest_node_stencil = false;  // binned_by_nearest_node below
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
  // hat(d) = 1 - |d|; a window node is never farther than one cell.
  template <class V>
  static void lanes(const V& d, const V& /*half_width*/, V& w, V& dw) {
    using R = LaneReal<V>;
    w = R(1) - lanes_abs(d);
    dw = d < R(0) ? R(1) + V{} : R(-1) + V{};
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
  // The window covers every stencil of a particle of one key cell: nodes
  // key-1 .. key+2. node() is zero beyond the particle's reach, so the
  // window weights need no padding logic.
  static constexpr int W = 4;
  static constexpr int window_lo = 1;
  // The stencil is the nodes k-1 .. k+1 around the nearest node k
  // (binned_by_nearest_node below).
  static constexpr bool nearest_node_stencil = true;
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
  // lanes() reads the half-widths l (uses_half_width below).
  static constexpr bool half_width_lanes = true;
  // node() lane by lane.
  template <class V>
  static void lanes(const V& d, const V& l, V& w, V& dw) {
    using R = LaneReal<V>;
    const V one = 1 + V{}, minus_one = -1 + V{};
    const V inv2l = R(0.5) / l;
    const V a = lanes_clamp(d + l, minus_one, one), b = lanes_clamp(d - l, minus_one, one);
    const V aa = lanes_abs(a), ab = lanes_abs(b);
    w = ((a - R(0.5) * a * aa) - (b - R(0.5) * b * ab)) * inv2l;
    dw = (ab - aa) * inv2l;
  }
};

// Quadratic B-spline: three nodes.
struct BSpline2Shape {
  static constexpr int S = 3;
  static constexpr int W = 4;  // as uGIMP: nodes cell-1 .. cell+2
  static constexpr int window_lo = 1;
  static constexpr bool nearest_node_stencil = true;  // as uGIMP
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
  // N(d) = 3/4 - d^2 for |d| < 1/2, (3/2 - |d|)^2 / 2 for |d| < 3/2, else 0;
  // written with selects so the four window nodes vectorise.
  template <class V>
  static void lanes(const V& d, const V& /*half_width*/, V& w, V& dw) {
    using R = LaneReal<V>;
    const V a = lanes_abs(d);
    const V t = lanes_max(R(1.5) - a, V{});
    const auto inner = a < R(0.5);
    w = inner ? R(0.75) - d * d : R(0.5) * t * t;
    dw = inner ? R(-2) * d : (d < R(0) ? t : -t);
  }
};

// Cubic B-spline: four nodes. With r = xi - base in [1, 2) the distances
// to the nodes are r, r-1, r-2, r-3: the first and last always fall in the
// outer piece (1 <= |d| < 2), the middle two in the inner piece, so the
// weights need no branches.
struct BSpline3Shape {
  static constexpr int S = 4;
  static constexpr int W = 4;  // the stencil itself: nodes cell-1 .. cell+2
  static constexpr int window_lo = 1;
  static constexpr bool nearest_node_stencil = false;
  static constexpr const char* name = "bspline3";
  template <class Real>
  static int eval(Real xi, Real /*half_width*/, Real* w, Real* dw) {
    const Real fb = std::floor(xi) - Real(1);
    weights(xi - fb, w, dw);
    return int(fb);
  }
  // N(d) = 2/3 - d^2 + |d|^3/2 for |d| < 1, (2 - |d|)^3/6 for |d| < 2.
  template <class V>
  static void lanes(const V& d, const V& /*half_width*/, V& w, V& dw) {
    using R = LaneReal<V>;
    const V a = lanes_abs(d);
    const V t = lanes_max(R(2) - a, V{});
    const auto inner = a < R(1);
    const auto neg = d < R(0);
    w = inner ? R(2) / R(3) - d * d + R(0.5) * a * a * a : t * t * t * (R(1) / R(6));
    const V douter = R(0.5) * t * t;
    dw = inner ? R(-2) * d + R(1.5) * d * a : (neg ? douter : -douter);
  }
  template <class Real>
  static void weights(Real r, Real* w, Real* dw) {  // r in [1, 2)
    const Real q0 = Real(2) - r;                    // outer piece, d = r
    const Real a1 = r - Real(1);                    // inner piece, d = r - 1 >= 0
    const Real a2 = Real(2) - r;                    // inner piece, d = r - 2 < 0, |d| = 2 - r
    const Real q3 = r - Real(1);                    // outer piece, d = r - 3, 2 - |d| = r - 1
    w[0] = q0 * q0 * q0 / Real(6);
    dw[0] = Real(-0.5) * q0 * q0;
    w[1] = Real(2) / Real(3) - a1 * a1 + Real(0.5) * a1 * a1 * a1;
    dw[1] = Real(-2) * a1 + Real(1.5) * a1 * a1;
    w[2] = Real(2) / Real(3) - a2 * a2 + Real(0.5) * a2 * a2 * a2;
    dw[2] = Real(2) * a2 - Real(1.5) * a2 * a2;
    w[3] = q3 * q3 * q3 / Real(6);
    dw[3] = Real(0.5) * q3 * q3;
  }
};

// Does Shape::lanes read the particles' half-widths (uGIMP)?
template <class Shape>
inline constexpr bool uses_half_width = requires {
  requires Shape::half_width_lanes;
};

// Whether particles are binned by their nearest node k instead of their
// cell: then every particle of a bin has the stencil k-1 .. k+1, and the
// window needs 3 rows per y and z direction instead of 4
// (kernels/window.hpp). In double, 2D and 3D: 3D saves 28 of 64 window
// nodes (P2G -16..-22 %, G2P -12 %); 2D's three rows of 4 doubles are
// three half-register units in the gathers, which run two particles per
// register (G2PGather::gather_pair), and two padded full-register units in
// the scatters (2D uGIMP steps 4-10 % faster). In 2D float with AVX-512
// too: the scatters keep one register per sum (4 rows of 4 floats, the
// fourth a padding row that is neither loaded nor stored) and the gathers
// run pairs in 256-bit vectors (the 2D uGIMP float MUSL step 1.20x
// faster). Not in 3D float (9 rows of 16 bytes) nor in float on narrower
// targets, where the 3 one-row gather units would replace 2 full ones
// (docs/performance.md "Windows centred on the nearest node", "The same
// in 2D double", "The same in 2D float").
template <int D, class Shape, class Real>
inline constexpr bool binned_by_nearest_node =
    (D == 2 || D == 3) &&
    (sizeof(Real) == 8 || (D == 2 && kRegisterVectorBytes == 64)) && Shape::nearest_node_stencil;

// The origin particles are binned from: the grid's, or half a cell below it
// when binned by the nearest node, so that cell_of(x, key_origin, 1/h)
// (kernels/binning.hpp) is that node. The window builder (kernels/window.hpp)
// measures from the same origin, so a particle's window and its key agree
// to the last bit.
template <int D, class Shape, class Real>
inline Real key_origin(Real origin, Real h) {
  return binned_by_nearest_node<D, Shape, Real> ? origin - Real(0.5) * h : origin;
}
template <int D, class Shape, class Real>
inline std::array<Real, 3> key_origins(const std::array<Real, 3>& origin,
                                       const std::array<Real, 3>& h) {
  return {key_origin<D, Shape>(origin[0], h[0]), key_origin<D, Shape>(origin[1], h[1]),
          key_origin<D, Shape>(origin[2], h[2])};
}

}  // namespace mmpm
