// Contact laws at a multimaterial node: they change momentum, never add force
// (ALGORITHM §3, §3.1; P-7 … P-16).
#pragma once

#include "kernels/mm_common.hpp"

namespace mmpm {

// (P-7, P-8) momentum change of a to the center-of-mass velocity, with b the other
// (possibly lumped) material. Written as (m_a p_b − m_b p_a)/(m_a + m_b) so that the
// change of b computed the same way is exactly the negative (momentum conservation).
// Rigid b (P-28, P-29): v_c = v_b, Δp_a = m_a v_b − p_a.
template <int D, class Real>
VecD<D, Real> momentum_change_to_center_of_mass(Real m_a, const VecD<D, Real>& p_a, Real m_b,
                                                const VecD<D, Real>& p_b, bool b_is_rigid) {
  VecD<D, Real> dp;
  if (b_is_rigid) {
    const Real ratio = m_a / m_b;
    for (int d = 0; d < D; ++d) dp[d] = ratio * p_b[d] - p_a[d];
  } else {
    const Real inv_mc = Real(1) / (m_a + m_b);
    for (int d = 0; d < D; ++d) dp[d] = (m_a * p_b[d] - m_b * p_a[d]) * inv_mc;
  }
  return dp;
}

// Approaching: Δp_a·n < 0 (equivalent to Δv·n < 0, P-9). In contact: approaching and the
// (corrected) normal separation δ_n' < 0 (P-12, P-14).
template <class Real>
inline bool approaching(Real dp_dot_n) {
  return dp_dot_n < 0;
}
template <class Real>
inline bool in_contact(Real dp_dot_n, Real corrected_normal_separation) {
  return dp_dot_n < 0 && corrected_normal_separation < 0;
}

// δ_n' (P-14): the displacement method uses δ_n; the position method subtracts the
// contact offset δ_con = offset · h⊥ of two surfaces exactly in contact (the
// paper's offset: 0.8).
template <class Real>
inline Real corrected_normal_separation(Separation method, Real delta_n, Real h_perp, Real offset) {
  return method == Separation::position ? delta_n - offset * h_perp : delta_n;
}

// Momentum change of a for a pair in contact (ALGORITHM §3.1). `dp` is Δp_a, `n` the
// unit normal a → b. stick: Δp_a; frictionless: (Δp_a·n) n; Coulomb (P-16): with
// d_n = Δp_a·n < 0, d_t = |Δp_a − d_n n|, t the unit tangential part: slides when
// d_t > −μ d_n and then gets d_n n − μ d_n t (tangential change capped at μ|d_n|),
// otherwise sticks. A pair held while parting (d_n ≥ 0, kHeldInPassB) has no normal
// push to carry friction: the cap is 0 and only the normal part changes. Any other law
// changes nothing. *stuck (when given): whether the pair sticks (the stick law, or
// Coulomb not sliding).
template <int D, class Real>
VecD<D, Real> contact_momentum_change(Law law, Real friction, const VecD<D, Real>& dp,
                                      const VecD<D, Real>& n, bool* stuck = nullptr) {
  using namespace mm_detail;
  const Real dn = dot<D, Real>(dp, n);
  bool sticks = false;
  VecD<D, Real> change{};
  switch (law) {
    case Law::stick:
      sticks = true;
      change = dp;
      break;
    case Law::frictionless:
      change = scaled<D, Real>(n, dn);
      break;
    case Law::friction: {
      const VecD<D, Real> dp_t = add_scaled<D, Real>(dp, n, -dn);
      const Real dt_len = std::sqrt(dot<D, Real>(dp_t, dp_t));
      const Real cap = std::max(Real(0), -friction * dn);
      sticks = !(dt_len > cap);
      // Sliding: dt_len > 0 there since cap ≥ 0.
      change = sticks ? dp : add_scaled<D, Real>(scaled<D, Real>(n, dn), dp_t, cap / dt_len);
      break;
    }
    default:
      break;
  }
  if (stuck) *stuck = sticks;
  return change;
}

// Stick along chosen directions (perfect or force-limited interface directions, §3.2,
// §4.4): normal → (Δp_a·n) n; tangential → the whole tangential part Δp_a − (Δp_a·n) n
// (in 2D that is (Δp_a·t) t; in 3D it holds both tangents, so a perfect tangential
// interface cannot slide sideways either); both → Δp_a.
template <int D, class Real>
VecD<D, Real> directional_stick_change(unsigned char stick, const VecD<D, Real>& dp,
                                       const VecD<D, Real>& n) {
  using namespace mm_detail;
  const bool normal = (stick & (kStickNormal | kStickBoth)) != 0;
  const bool tangential = (stick & (kStickTangential | kStickBoth)) != 0;
  if (normal && tangential) return dp;
  const Real dn = dot<D, Real>(dp, n);
  if (normal) return scaled<D, Real>(n, dn);
  if (tangential) return add_scaled<D, Real>(dp, n, -dn);
  return VecD<D, Real>{};
}

}  // namespace mmpm
