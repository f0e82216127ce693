// Interface normal at a multimaterial node (ALGORITHM §5, P-32, P-33).
// Every function returns a unit vector pointing from material a to material b,
// or the zero vector when the data define no direction (the caller then skips
// the interaction at that node).
//
// Sign of the domain gradient. (P-33) defines g_ij = Σ_p G_ip V_p with G_ip the
// gradient of the node's shape function at the particle, ∇S_i(x_p). Since
// Ω_ij(x_i) = Σ_p S(x_p − x_i) V_p, this is g_ij = −∇Ω_ij(x_i): g points OUT of
// material j (the paper's remark after P-33: "g = −∇Ω, so ‖n‖n = g"). ALGORITHM §5
// states the opposite orientation; see docs/multimaterial.md §5. The whole pass
// reads g through kDomainGradientOutward, the one place to change if P2G stores +∇Ω.
#pragma once

#include <limits>

#include "kernels/mm_common.hpp"

namespace mmpm {

// +1: grid.g of a field points out of that material (P-33 with G_ip = ∇S_i(x_p)).
// −1: grid.g points into the material (+∇Ω).
inline constexpr int kDomainGradientOutward = +1;

// MVG (maximum volume gradient): trust the material with the steeper domain gradient.
// a's outward normal runs a → b; b's outward normal runs b → a, so it is negated.
template <int D, class Real>
VecD<D, Real> normal_mvg(const VecD<D, Real>& g_a, const VecD<D, Real>& g_b) {
  using namespace mm_detail;
  const Real ga2 = dot<D, Real>(g_a, g_a);
  const Real gb2 = dot<D, Real>(g_b, g_b);
  const Real s = Real(kDomainGradientOutward);
  return ga2 >= gb2 ? normalized_or_zero<D, Real>(scaled<D, Real>(g_a, s))
                    : normalized_or_zero<D, Real>(scaled<D, Real>(g_b, -s));
}

// AVG (average volume gradient): domain-weighted average of the two outward
// estimates, n ∝ Ω_a out_a − Ω_b out_b (paper §2.5: (Ω_a g_a − Ω_b g_b)/(2Ω)).
template <int D, class Real>
VecD<D, Real> normal_avg(Real vol_a, const VecD<D, Real>& g_a, Real vol_b,
                         const VecD<D, Real>& g_b) {
  VecD<D, Real> n;
  const Real s = Real(kDomainGradientOutward);
  for (int d = 0; d < D; ++d) n[d] = s * (vol_a * g_a[d] - vol_b * g_b[d]);
  return mm_detail::normalized_or_zero<D, Real>(n);
}

// RMVG (rigid material volume gradient): the rigid material b's outward normal runs b → a.
template <int D, class Real>
VecD<D, Real> normal_rigid(const VecD<D, Real>& g_rigid_b) {
  return mm_detail::normalized_or_zero<D, Real>(
      mm_detail::scaled<D, Real>(g_rigid_b, -Real(kDomainGradientOutward)));
}

// SN: a given vector; `sign` = +1 when a is the field the vector points away from, else −1.
template <int D, class Real>
VecD<D, Real> normal_specified(const std::array<Real, 3>& vector, Real sign) {
  VecD<D, Real> n;
  for (int d = 0; d < D; ++d) n[d] = sign * vector[d];
  return mm_detail::normalized_or_zero<D, Real>(n);
}

// SN radial: n ∝ x_i − c (spherical inclusion, or a disk in 2D, `first_field` at c),
// or, with a unit `axis` (3D), n ∝ r − (r·a) a with r = x_i − c: a cylindrical
// inclusion (a fibre) along the line through c. A zero axis subtracts exactly 0.
template <int D, class Real>
VecD<D, Real> radial_direction(const std::array<Real, 3>& node_position,
                               const std::array<Real, 3>& center, const std::array<Real, 3>& axis,
                               Real sign) {
  VecD<D, Real> r;
  Real along = 0;
  for (int d = 0; d < D; ++d) {
    r[d] = sign * (node_position[d] - center[d]);
    along += r[d] * axis[d];
  }
  for (int d = 0; d < D; ++d) r[d] -= along * axis[d];
  return r;
}

template <int D, class Real>
VecD<D, Real> normal_radial(const std::array<Real, 3>& node_position,
                            const std::array<Real, 3>& center, const std::array<Real, 3>& axis,
                            Real sign) {
  return mm_detail::normalized_or_zero<D, Real>(
      radial_direction<D, Real>(node_position, center, axis, sign));
}

// The squared tangential opening |δ − (δ·n)n|² (P-15) when it is an opening, 0 when
// it is only the rounding left by the subtraction (δ along n to within 1024 ε |δ|).
// Such a remainder points anywhere, along n too; then t ∥ n, s = n × t vanishes
// and so does the 3D h⊥ (§4.2), and the contact area (P-20) divides by it. In
// sphere_in_cube (radial normal, radial opening) one node's area came out 2e14
// instead of 0.01: an interface force 16 orders too large, which made every
// force_limit = false run unstable within 23 steps, even at Dn = Dt = 1e-3, and
// turned the node to stick with the limit on (docs/multimaterial.md §4).
// Compared as squares: no square root for the test.
template <class Real>
inline Real resolved_opening_squared(Real opening_t2, Real delta2) {
  constexpr Real tol = Real(1024) * std::numeric_limits<Real>::epsilon();
  return opening_t2 > tol * tol * delta2 ? opening_t2 : Real(0);
}

// A unit tangent for the interface: along the tangential opening δ − (δ·n)n when it is
// not zero (P-15), otherwise a fixed perpendicular of n built from the coordinate axis
// least aligned with n (deterministic; depends on n only).
template <int D, class Real>
VecD<D, Real> tangent_or_perpendicular(const VecD<D, Real>& opening_t, Real opening_length,
                                       const VecD<D, Real>& n) {
  using namespace mm_detail;
  if (opening_length > 0) return scaled<D, Real>(opening_t, Real(1) / opening_length);
  if constexpr (D == 2) {
    return VecD<D, Real>{-n[1], n[0]};
  } else {
    int axis = 0;
    for (int d = 1; d < D; ++d)
      if (std::abs(n[d]) < std::abs(n[axis])) axis = d;
    VecD<D, Real> e{};
    e[axis] = 1;
    return normalized_or_zero<D, Real>(add_scaled<D, Real>(e, n, -n[axis]));
  }
}

}  // namespace mmpm
