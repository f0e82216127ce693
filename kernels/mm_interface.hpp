// Imperfect interfaces at a multimaterial node (ALGORITHM §3.2, §4): traction laws,
// the effective cell thickness h⊥ (P-21, P-22), the contact area (P-20), the force
// limit for stiff interfaces (P-23 … P-27) and the exact integration of the
// interface spring (§4.5). Derivations: docs/multimaterial.md.
#pragma once

#include "kernels/mm_common.hpp"

namespace mmpm {

// ---------------------------------------------------------------- traction laws
// A traction law maps the openings (δ_n, δ_t ≥ 0) to tractions, the stiffness in use
// (for the exact integration) and the energy density per direction. A direction whose
// stiffness is +inf is "perfect": no traction, no energy, always stick (§3.2).
template <class Real>
struct Traction {
  Real normal = 0, tangential = 0;        // T_n, T_t (force per area)
  Real stiffness_n = 0, stiffness_t = 0;  // D in use this step
  Real energy_n = 0, energy_t = 0;        // energy per area: ∫T d[u] per direction
  bool perfect_n = false, perfect_t = false;
};

namespace mm_detail {
// One linear direction T = D δ, energy ½ D δ²; D = +inf → perfect.
template <class Real>
inline void linear_direction(Real stiffness, Real opening, Real& traction, Real& stiffness_out,
                             Real& energy, bool& perfect) {
  stiffness_out = stiffness;
  perfect = std::isinf(stiffness);
  traction = perfect ? Real(0) : stiffness * opening;
  energy = perfect ? Real(0) : Real(0.5) * stiffness * opening * opening;
}
}  // namespace mm_detail

// Linear law (P-3, P-4): T_n = D_n δ_n, T_t = D_t δ_t, φ = ½(D_n δ_n² + D_t δ_t²).
template <class Real>
Traction<Real> traction_linear(Real Dn, Real Dt, Real delta_n, Real delta_t) {
  Traction<Real> r;
  mm_detail::linear_direction(Dn, delta_n, r.normal, r.stiffness_n, r.energy_n, r.perfect_n);
  mm_detail::linear_direction(Dt, delta_t, r.tangential, r.stiffness_t, r.energy_t, r.perfect_t);
  return r;
}

// Bilinear in δ_n (paper §3 end, ALGORITHM §3.2): D_n in tension (δ_n ≥ 0), D_n^c in
// compression (δ_n < 0); energy ½ D δ_n² with the branch's D (elastic, kink at 0).
template <class Real>
Traction<Real> traction_bilinear(Real Dn_tension, Real Dn_compression, Real Dt, Real delta_n,
                                 Real delta_t) {
  return traction_linear(delta_n < 0 ? Dn_compression : Dn_tension, Dt, delta_n, delta_t);
}

template <class Real>
Traction<Real> evaluate_traction(const PairParams<Real>& pp, Real delta_n, Real delta_t) {
  switch (pp.traction_law) {
    case TractionLaw::bilinear:
      return traction_bilinear(pp.Dn, pp.Dn_compression, pp.Dt, delta_n, delta_t);
    case TractionLaw::linear:
    default:
      return traction_linear(pp.Dn, pp.Dt, delta_n, delta_t);
  }
}

// ---------------------------------------------------------------- h⊥ and area
// h⊥ (P-21, P-22 method 1): V_cell / (h1 h2) with h1, h2 the radii of the ellipsoid
// Σ x_k²/Δx_k² = 1 along two tangents of the plane ⟂ n. Taken along the principal axes
// of that section (an ellipse of area π h1 h2 = π V_cell / |diag(Δx) n|), this is
//   h⊥ = sqrt(Σ_k n_k² Δx_k²),
// the paper's 2D formula in any dimension: V_cell = h⊥ A_c holds exactly for the
// section, and h⊥ depends on n alone. The paper's 3D form with t along the tangential
// opening gives a larger h⊥ for any other t (up to 25 % for Δy = 2Δx), so the interface
// area, force and energy would change with the slip direction (docs/multimaterial.md §6).
// Equals Δx on a regular mesh.
template <int D, class Real>
Real h_perp(const VecD<D, Real>& n, const std::array<Real, 3>& h) {
  Real sum = 0;
  for (int k = 0; k < D; ++k) sum += n[k] * n[k] * h[k] * h[k];
  return std::sqrt(sum);
}

// Contact area (P-20): A_i = t sqrt(2 Ω_i min(Ω_a, Ω_b)) / h⊥ in 2D (t = `thickness`),
// without t in 3D. Ω_i = Ω_a + Ω_b.
template <int D, class Real>
Real contact_area(Real vol_a, Real vol_b, Real h_perp_value, Real thickness) {
  const Real total = vol_a + vol_b;
  const Real smaller = vol_a < vol_b ? vol_a : vol_b;
  const Real area = std::sqrt(Real(2) * total * smaller) / h_perp_value;
  if constexpr (D == 2) return thickness * area;
  return area;
}

// The interface's share of a node read from the domain gradients (area =
// "gradient", docs/multimaterial.md §7.2): A_i = ∫_Γ S_i dΓ, which is what the
// weak form of a traction on Γ puts on node i (f_i = ∫_Γ S_i T dΓ). By the
// divergence theorem ∫_{Ω_a} ∇S_i dΩ = ∮_{∂Ω_a} S_i n_out dΓ, and g_a (P-33) is the
// particle quadrature of the left side; along n (a → b) the interface is the
// part of ∂Ω_a the projection keeps, so n·g_a = ∫_Γ S_i dΓ, and −n·g_b reads the
// same over b's face. The two sides are averaged, and the sign dropped: a
// specified normal may point b → a on some of an interface's faces (the central
// lap of a double lap shear has its partner on both sides), and its area is
// the same. (P-20) assumes one row of interface nodes and gives each row a full
// share; a B-spline puts the interface in two or three rows, and (P-20) counted
// it 1.35 (bspline2) to 1.54 (bspline3) times. `gn_a`, `gn_b` = n·g as stored;
// 2D multiplies by the thickness, as (P-20).
template <int D, class Real>
Real gradient_contact_area(Real gn_a, Real gn_b, Real thickness) {
  const Real area = Real(0.5) * std::abs(gn_a - gn_b);
  if constexpr (D == 2) return thickness * area;
  return area;
}

template <class Real>
struct ClosedDomains {
  Real a, b;  // Ω_a', Ω_b'
};

// The nodal domains with the interface's opening closed (area = "closed",
// docs/multimaterial.md §7.1). On the current domains (P-20) loses area as the
// interface opens, 1.5 δ_n/h⊥ of it at a grid-line interface: the side that
// moved away takes its domain from the node. Moving material j's particles by
// s n changes Ω_j by s (n · g_j) (g = Σ ∇S_i(x_p) V_p, outward, P-33), so each
// side is moved back along n by its normal displacement u_jn less a common c.
// c is the value between u_an and u_bn nearest 0: where the reference
// configuration lies within the opening (small motion: either side or both
// moved) both sides return to it, which is exact to first order; under a large
// common motion only the side that moved the farther returns, by the opening
// and never more, so the Taylor step stays within the gap. Callers without
// displacements (the position method) pass −dn/2 and dn/2: half the opening
// each. A domain cannot go below 0.
template <class Real>
[[nodiscard]] inline ClosedDomains<Real> close_opening(Real vol_a, Real vol_b, Real gn_a, Real gn_b,
                                                       Real u_an, Real u_bn) {
  const Real lo = u_an < u_bn ? u_an : u_bn, hi = u_an < u_bn ? u_bn : u_an;
  const Real c = lo > Real(0) ? lo : (hi < Real(0) ? hi : Real(0));
  const Real closed_a = vol_a - (u_an - c) * gn_a, closed_b = vol_b - (u_bn - c) * gn_b;
  return {closed_a > Real(0) ? closed_a : Real(0), closed_b > Real(0) ? closed_b : Real(0)};
}

// ---------------------------------------------------------------- force limit
// Component along a direction of the largest meaningful interface force on a (P-26):
// the force that brings a and b to the center-of-mass displacement in one step under
// the midpoint rule (P-23 … P-25):
//   f_lim = (2 m_red / Δt²)(u_b − u_a) + (2/Δt) Δp_a + Δf_i,  m_red = m_a m_b/(m_a + m_b)
// `separation` = (u_b − u_a)·d, `momentum_change` = Δp_a·d, `force_difference` = Δf_i·d.
template <class Real>
Real force_limit_component(Real m_red, Real dt, Real separation, Real momentum_change,
                           Real force_difference = 0) {
  return Real(2) * m_red / (dt * dt) * separation + Real(2) / dt * momentum_change +
         force_difference;
}

// The direction becomes stick when the interface force exceeds the limit in magnitude.
template <class Real>
inline bool exceeds_force_limit(Real force, Real limit) {
  return std::abs(force) > std::abs(limit);
}

// Whether the limit applies at all: the force also exceeds the limit's
// separation term alone, (2 m_red / Δt²)(u_b − u_a), i.e. for the linear law
// D A Δt² > 2 m_red, ω Δt > √2 (docs/multimaterial.md §8.1). Why: f_lim
// passes through zero where the pair will reach its centre-of-mass
// displacement within the step, so the paper's test alone also fires for a
// soft spring (ω Δt ≪ 1) at a zero crossing of a vibration, where the
// spring is far inside the explicit bound and sticking it for one step
// adds or removes energy (two bars at Dn = 100, ω Δt = 0.16: 8 firings in
// 3 ms, each +5 to +14 % of the energy; docs/interface_validation.md
// Finding 14). At rest the momentum term is zero and the two tests agree,
// so static results are the paper's.
template <class Real>
inline bool spring_beyond_one_step(Real force, Real m_red, Real dt, Real separation) {
  return exceeds_force_limit(force, force_limit_component(m_red, dt, separation, Real(0)));
}

// Reduced mass of the pair; a rigid b has infinite mass, so m_red = m_a (P-28 … P-31).
template <class Real>
inline Real reduced_mass(Real m_a, Real m_b, bool b_is_rigid) {
  return b_is_rigid ? m_a : m_a * m_b / (m_a + m_b);
}

// Δf_i of (P-27) = (m_a f_b − m_b f_a)/(m_a + m_b) = m_red (f_b/m_b − f_a/m_a); for a
// rigid b (prescribed velocity, no acceleration within the step) it is −f_a.
template <int D, class Real>
VecD<D, Real> force_difference(Real m_a, const VecD<D, Real>& f_a, Real m_b,
                               const VecD<D, Real>& f_b, bool b_is_rigid) {
  VecD<D, Real> r;
  if (b_is_rigid) {
    for (int d = 0; d < D; ++d) r[d] = -f_a[d];
  } else {
    const Real inv = Real(1) / (m_a + m_b);
    for (int d = 0; d < D; ++d) r[d] = (m_a * f_b[d] - m_b * f_a[d]) * inv;
  }
  return r;
}

// ---------------------------------------------------------------- exact integration
// §4.5: along one direction the relative coordinate s = u_b − u_a obeys
//   m_red s'' = −k s + Δf,  k = D A_i,  ω² = k / m_red,  θ = ωΔt,  s* = Δf/k,
// whose solution, sampled once a step, satisfies
//   s_{n+1} − 2 cos θ s_n + s_{n−1} = 2 (1 − cos θ) s*.
// MPM advances the pair as velocity first, then position with the new velocity
// (w_{n+1} = w_n + Δt (Δf − F_n)/m_red, s_{n+1} = s_n + Δt w_{n+1}), i.e.
//   s_{n+1} − 2 s_n + s_{n−1} = (Δt²/m_red)(Δf − F_n).
// The two agree for every n when
//   F = k C(θ) (s0 − s*) + Δf = k s0 C(θ) + Δf (1 − C(θ)),  C(θ) = 2(1 − cos θ)/θ²,
// so the sampled positions are the exact oscillator's at any θ < π and the map keeps
// the oscillator's energy (eigenvalues e^{±iθ}). The particles' velocity is the step's
// mean, not the start-of-step velocity, so the relative velocity w0 plays no part: a
// force that also landed (s0, w0) on s(Δt), as if w0 were that instant's velocity (the
// earlier form, with (2/Δt) Δp_a·d (1 − sin θ/θ)), is a dashpot of k Δt/3 that took an
// undamped vibration to 0.000 E0 in 1.5 ms (docs/interface_validation.md Finding 15).
// C → 1 as θ → 0 (the explicit force k s0). When θ > 1.5 the direction is effectively
// perfect and becomes stick (ALGORITHM §4.5). Derivation: docs/multimaterial.md §11.
inline constexpr double kExactStickOmegaDt = 1.5;

template <class Real>
struct SpringStep {
  Real force = 0;      // interface force on a along the direction
  bool stick = false;  // θ > kExactStickOmegaDt: treat the direction as stick
  Real omega_dt = 0;   // θ
};

namespace mm_detail {
// C(θ) = 2(1 − cos θ)/θ², without cancellation.
template <class Real>
inline Real oscillator_cos_term(Real theta) {
  const Real half = Real(0.5) * theta;
  if (half < Real(1e-4)) return Real(1) - theta * theta / Real(12);
  const Real sinc = std::sin(half) / half;
  return sinc * sinc;
}
}  // namespace mm_detail

template <class Real>
SpringStep<Real> exact_spring_force(Real stiffness, Real m_red, Real dt, Real separation,
                                    Real force_difference = 0, Real stick_dt = 0) {
  SpringStep<Real> r;
  const Real omega = std::sqrt(stiffness / m_red);
  r.omega_dt = dt * omega;
  // stick_dt: the step the stick decision is made for (MMConfig::limit_dt).
  if ((stick_dt > 0 ? stick_dt : dt) * omega > Real(kExactStickOmegaDt)) {
    r.stick = true;
    return r;
  }
  const Real c = mm_detail::oscillator_cos_term(r.omega_dt);
  r.force = stiffness * separation * c + force_difference * (Real(1) - c);
  return r;
}

}  // namespace mmpm
