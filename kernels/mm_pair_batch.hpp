// Two-material nodes of the multimaterial pass, a batch at a time (ALGORITHM
// §3, §4, §6 with K = 2; docs/multimaterial.md "Two-material nodes in
// batches"). Most multimaterial nodes hold exactly two deformable materials
// joined by one interaction. Node by node, each costs a chain of square
// roots and divisions (normal, tangent, h⊥, area, force limit) plus a dozen
// scattered grid loads; in lanes across nodes the work of different nodes
// overlaps (independent chains, one gather loop over the nodes), and the lane loops
// run in SIMD registers: GCC vectorises both passes for every law (but
// Coulomb friction in 3D pass A), checked in the solver binary by
// tools/check_vectorised.py. Pass A's loop is written for
// that: selects between Reals only, no run-time flag inside
// (docs/multimaterial.md "Pass A in SIMD lanes").
//
// The lane code does, per node, the operations of interact_pass_a /
// interact_pass_b_saved (kernels/multimaterial.hpp) for a deformable pair
// with explicit integration, written with selects instead of early returns.
// The compiler contracts multiply-adds differently in the two, so results
// agree to round-off, not bitwise; tests/test_mm_pair_batch.cpp compares
// them on every law, normal method, traction law and separation method.
// The lane loops carry `GCC ivdep`, not `omp simd`: with -fopenmp, GCC 12
// made the small std::array locals of an `omp simd` body per-lane arrays
// and vectorised nothing.
#pragma once

#include <cstddef>
#include <cstdint>

#include "kernels/grid_view.hpp"
#include "kernels/mm_common.hpp"
#include "kernels/mm_contact.hpp"
#include "kernels/mm_interface.hpp"
#include "kernels/mm_normals.hpp"

namespace mmpm::mm_detail {

// Up to kLanes two-material nodes of one pair (field_a < field_b): inputs
// gathered from the grid, outputs for the caller to apply in list order.
template <int D, class Real>
struct PairBatch {
  static constexpr int kLanes = 64;  // one chunk of the node list

  int count = 0;
  int field_a = -1, field_b = -1;
  const PairParams<Real>* params = nullptr;
  std::uint32_t node[kLanes];

  // Inputs: side 0 = field_a, side 1 = field_b.
  alignas(64) Real m[2][kLanes];
  alignas(64) Real vol[2][kLanes];
  alignas(64) Real p[2][D][kLanes];
  alignas(64) Real mx[2][D][kLanes];
  alignas(64) Real g[2][D][kLanes];
  alignas(64) Real f[2][D][kLanes];
  alignas(64) Real x[D][kLanes];  // node positions (radial normal)
  // Pass B input / pass A output: the saved geometry and stick flags.
  alignas(64) Real n[D][kLanes];
  alignas(64) Real dn[kLanes];
  alignas(64) unsigned char stick[kLanes];
  // Pass A's stick bits + 8 × limited count as a Real: the lane loop then
  // writes only Reals (see pass_a_lanes), and a scalar loop unpacks it.
  alignas(64) Real flags[kLanes];
  // Pass B's scratch (interface law): 1 where the stick flags stick the
  // tangential direction, else 0 (see pass_b_lanes).
  alignas(64) Real sticks_tangential[kLanes];
  // Pass A: in, 1 where the last step's pass B held the pair, 2 where it held
  // it stuck (USF only).
  // Pass B: in, 1 where the pair is held (kHeldInPassB, MUSL's strain pass
  // only); out, 1 where this pass held it (contact applied, one-sided
  // normal stuck), else 0.
  alignas(64) Real held[kLanes];
  // Pass B, out: 1 where this pass held the pair stuck (kStuckInPassB), else 0.
  alignas(64) Real stuck[kLanes];

  // Outputs for field_a (field_b gets the negatives).
  alignas(64) Real change[D][kLanes];
  alignas(64) Real force[D][kLanes];
  alignas(64) double energy[kLanes];
  alignas(64) int limited[kLanes];
};

// What pass B needs of pass A's batch in one chunk of the node list: which
// entries went into which lane, and the lanes' masses, normals,
// separations and stick flags (none of which change between the passes).
// Why: pass B then neither sorts the chunk's nodes again (a mass load and
// a branch per field and node) nor gathers the masses, and it copies the
// geometry as contiguous rows instead of picking it out of the per-node
// slots; in the 625 disks scene (20 000 multimaterial nodes) that sorting
// and copying were about half of a pass B (docs/multimaterial.md "Pass B
// from pass A's batches").
template <int D, class Real>
struct SavedBatch {
  static constexpr int kLanes = PairBatch<D, Real>::kLanes;
  int count = 0;  // 0: pass A batched nothing here; pass B sorts the chunk itself
  int field_a = -1, field_b = -1;
  const PairParams<Real>* params = nullptr;
  signed char lane_of[kLanes];  // per entry of the chunk; −1: by the per-node path
  std::uint32_t node[kLanes];
  alignas(64) Real m[2][kLanes];
  alignas(64) Real n[D][kLanes];
  alignas(64) Real dn[kLanes];
  alignas(64) unsigned char stick[kLanes];
};

// What a batch reads besides p.
struct BatchNeeds {
  bool mass = true, vol = true, geometry = true, gradient = false, position = false, force = false;
};

// The batch's rows node by node: each node's index is loaded once for all
// its rows. Why: row by row (an index load, a load and a store per row and
// node) pass A's 16 rows in 2D cost one index load per value, and the
// gather was more than half of pass A in the 625 disks' step; node by node
// pass A alone went 530 -> 429 us on one thread (docs/multimaterial.md
// "Pass B from pass A's batches"). The flags are loop invariants (GCC
// unswitches the loop or predicts them).
template <int D, class Real>
void gather_batch(const GridView<D, Real>& grid, const BatchNeeds& needs, PairBatch<D, Real>& B) {
  const std::size_t oa = grid.at(B.field_a, 0), ob = grid.at(B.field_b, 0);
  const int n = B.count;
  for (int i = 0; i < n; ++i) {
    const std::size_t a = oa + B.node[i], b = ob + B.node[i];
    if (needs.mass) B.m[0][i] = grid.m[a], B.m[1][i] = grid.m[b];
    if (needs.vol) B.vol[0][i] = grid.vol[a], B.vol[1][i] = grid.vol[b];
    for (int d = 0; d < D; ++d) {
      B.p[0][d][i] = grid.p[d][a];
      B.p[1][d][i] = grid.p[d][b];
      if (needs.geometry) B.mx[0][d][i] = grid.mx[d][a], B.mx[1][d][i] = grid.mx[d][b];
      if (needs.gradient) B.g[0][d][i] = grid.g[d][a], B.g[1][d][i] = grid.g[d][b];
      if (needs.force) B.f[0][d][i] = grid.f[d][a], B.f[1][d][i] = grid.f[d][b];
    }
  }
  if (needs.position)
    for (int i = 0; i < n; ++i) {
      const std::array<Real, 3> x = grid.position(B.node[i]);
      for (int d = 0; d < D; ++d) B.x[d][i] = x[d];
    }
}

// normalized_or_zero without the early return, for finite u (a non-finite
// u gives a non-finite result where normalized_or_zero gives zero; callers
// test the result with finite_nonzero). u times a selected scale, not a
// select of u / |u|: GCC 12 threaded the select's condition into the
// callers' tests of the result, as selects between booleans that its
// vectoriser rejects.
template <int D, class Real>
inline VecD<D, Real> unit_or_zero(const VecD<D, Real>& u) {
  const Real len = std::sqrt(dot<D, Real>(u, u));
  const bool ok = (len > 0) & std::isfinite(len);
  const Real scale = ok ? Real(1) / len : Real(0);
  VecD<D, Real> r;
  for (int d = 0; d < D; ++d) r[d] = u[d] * scale;
  return r;
}

// n is nonzero and finite (a usable unit_or_zero result).
template <int D, class Real>
inline bool finite_nonzero(const VecD<D, Real>& n) {
  const Real nn = dot<D, Real>(n, n);
  return (nn != Real(0)) & std::isfinite(nn);
}

// directional_stick_change with selects: the normal and/or tangential
// part of dp, as the directions stick.
template <int D, class Real>
inline VecD<D, Real> stick_change_lane(bool normal, bool tangential, const VecD<D, Real>& dp,
                                       const VecD<D, Real>& n) {
  const Real dn = dot<D, Real>(dp, n);
  VecD<D, Real> r;
  for (int d = 0; d < D; ++d) {
    const Real along = n[d] * dn;
    const Real across = dp[d] + -dn * n[d];  // add_scaled(dp, n, −dn)
    r[d] = normal & tangential ? dp[d] : normal ? along : tangential ? across : Real(0);
  }
  return r;
}

// contact_momentum_change for a law fixed at compile time, times "in contact";
// stuck: 1 where the pair is in contact and sticks (stick law, Coulomb not
// sliding), else 0.
template <Law L, int D, class Real>
inline VecD<D, Real> contact_change_lane(bool contact, Real friction, const VecD<D, Real>& dp,
                                         const VecD<D, Real>& n, Real& stuck) {
  const Real dn = dot<D, Real>(dp, n);
  VecD<D, Real> r;
  stuck = Real(0);
  if constexpr (L == Law::stick) {
    r = dp;
    stuck = contact ? Real(1) : Real(0);
  } else if constexpr (L == Law::frictionless) {
    for (int d = 0; d < D; ++d) r[d] = n[d] * dn;
  } else {  // Law::friction (P-16)
    VecD<D, Real> dp_t;
    for (int d = 0; d < D; ++d) dp_t[d] = dp[d] + -dn * n[d];
    const Real dt_len = std::sqrt(dot<D, Real>(dp_t, dp_t));
    const Real cap = std::max(Real(0), -friction * dn);  // 0 for a held pair parting
    const bool slide = dt_len > cap;
    const Real cap_over_len = cap / dt_len;
    for (int d = 0; d < D; ++d) {
      const Real along = n[d] * dn;
      r[d] = slide ? along + cap_over_len * dp_t[d] : dp[d];
    }
    stuck = contact & !slide ? Real(1) : Real(0);
  }
  for (int d = 0; d < D; ++d) r[d] = contact ? r[d] : Real(0);
  return r;
}

// Lane i of a D × kLanes array (v = its first row). A reference-to-array
// parameter here kept GCC 12 from vectorising the lane loops.
template <int D, class Real>
inline VecD<D, Real> lane(const Real* v, int i) {
  VecD<D, Real> r;
  for (int d = 0; d < D; ++d) r[d] = v[d * PairBatch<D, Real>::kLanes + i];
  return r;
}

// USF's pass A on the lanes the last step's pass B held (B.held: 1 held,
// 2 held stuck), after pass_a_lanes' loop decided every lane on approach:
// a held lane gets its contact change whatever the approach, and a Coulomb
// lane held stuck the whole of Δp_a (contact_result's held_already and
// stuck_already). A loop of its own: read in the lane loop, B.held left
// GCC 12's 3D stick and frictionless loops scalar. B.n is 0 where pass A
// found no usable normal, which it leaves alone.
template <Law L, int D, class Real>
void hold_carried_lanes(PairBatch<D, Real>& B) {
  const Real friction = B.params->friction;
  for (int i = 0; i < B.count; ++i) {
    if (B.held[i] == Real(0)) continue;
    const VecD<D, Real> n = lane<D, Real>(B.n[0], i);
    if (dot<D, Real>(n, n) == Real(0)) continue;
    const VecD<D, Real> dp = momentum_change_to_center_of_mass<D, Real>(
        B.m[0][i], lane<D, Real>(B.p[0][0], i), B.m[1][i], lane<D, Real>(B.p[1][0], i), false);
    Real stuck;
    VecD<D, Real> change = contact_change_lane<L, D, Real>(true, friction, dp, n, stuck);
    if (L == Law::friction && B.held[i] > Real(1)) change = dp;
    for (int d = 0; d < D; ++d) B.change[d][i] = change[d];
  }
}

// Pass A on the lanes of B: the normal by method M, the pair's law L
// (Law::interface: the imperfect interface with explicit integration),
// with Δf in the force limit when UseDf and the area by rule A (template
// parameters: a select on a run-time flag kept GCC from vectorising the loop).
//
// flatten: every helper called in the lane loop is inlined. A single call
// left out of line keeps the whole loop scalar, and GCC 12 left different
// ones out in different translation units of the solver (h_perp in 3D
// double, momentum_change_to_center_of_mass in 3D float), which the
// vectorised_loops test found in build/mmpm (docs/multimaterial.md "Pass A
// in SIMD lanes").
template <NormalMethod M, Law L, bool UseDf, ContactArea A, int D, class Real>
[[gnu::flatten]] void pass_a_lanes(PairBatch<D, Real>& B, Real sign, const std::array<Real, 3>& h,
                                   Real dt, Real thickness) {
  const PairParams<Real>& pp = *B.params;
  const Real omega_min = pp.omega_min, friction = pp.friction;
  const Real presence = pp.presence_min_volume;  // kContactPresentFraction or 0
  const bool presence_thin_along_normal = pp.presence_thin_along_normal;
  const bool position_method = pp.separation == Separation::position;
  const Real contact_offset = pp.contact_offset;
  const bool bilinear = pp.traction_law == TractionLaw::bilinear;
  const bool force_limit = pp.force_limit;
  const Real Dn = pp.Dn, Dn_compression = pp.Dn_compression, Dt_stiffness = pp.Dt;
  const Real s_out = Real(kDomainGradientOutward);
  // A copy in registers: with the gradient area h⊥ serves only the position
  // method's offset, GCC sank its loads under that condition, and masked loads
  // of the caller's array kept the loop scalar.
  const std::array<Real, 3> cell{h[0], h[1], h[2]};
  const int count = B.count;
#pragma GCC ivdep
  for (int i = 0; i < count; ++i) {
    const Real ma = B.m[0][i], mb = B.m[1][i], va = B.vol[0][i], vb = B.vol[1][i];
    const VecD<D, Real> pa = lane<D, Real>(B.p[0][0], i), pb = lane<D, Real>(B.p[1][0], i);
    // §5 normal a → b. The domain gradients also serve stick's presence test.
    constexpr bool kGradient = M != NormalMethod::specified && M != NormalMethod::radial;
    VecD<D, Real> ga{}, gb{};
    if constexpr (kGradient) ga = lane<D, Real>(B.g[0][0], i), gb = lane<D, Real>(B.g[1][0], i);
    VecD<D, Real> n;
    if constexpr (M == NormalMethod::avg) {
      VecD<D, Real> u;
      for (int d = 0; d < D; ++d) u[d] = s_out * (va * ga[d] - vb * gb[d]);
      n = unit_or_zero<D, Real>(u);
    } else if constexpr (M == NormalMethod::specified) {
      VecD<D, Real> u;
      for (int d = 0; d < D; ++d) u[d] = sign * pp.normal_vector[d];
      n = unit_or_zero<D, Real>(u);
    } else if constexpr (M == NormalMethod::radial) {
      const std::array<Real, 3> x{B.x[0][i], B.x[1][i], D == 3 ? B.x[D - 1][i] : Real(0)};
      n = unit_or_zero<D, Real>(
          radial_direction<D, Real>(x, pp.radial_center, pp.radial_axis, sign));
    } else {  // mvg (and rigid, which is mvg without a rigid partner)
      const bool use_a = dot<D, Real>(ga, ga) >= dot<D, Real>(gb, gb);
      VecD<D, Real> u;
      for (int d = 0; d < D; ++d) u[d] = use_a ? ga[d] * s_out : gb[d] * -s_out;
      n = unit_or_zero<D, Real>(u);
    }
    // & and | rather than && and || on lane conditions: short-circuits are
    // branches, which keep a loop from being if-converted and vectorised.
    const bool screened =
        (va + vb < omega_min) |
        partner_absent<D, Real>(va, vb, ga, gb, n, presence, presence_thin_along_normal);
    const bool valid = !screened & finite_nonzero<D, Real>(n);

    // (P-7, P-8), (P-11), (P-12), (P-15), (P-22), (P-14).
    const VecD<D, Real> dp = momentum_change_to_center_of_mass<D, Real>(ma, pa, mb, pb, false);
    const Real inv_ma = Real(1) / ma, inv_mb = Real(1) / mb;
    VecD<D, Real> delta;
    for (int d = 0; d < D; ++d) delta[d] = B.mx[1][d][i] * inv_mb - B.mx[0][d][i] * inv_ma;
    const Real delta_n = dot<D, Real>(delta, n);
    const VecD<D, Real> opening_t = add_scaled<D, Real>(delta, n, -delta_n);
    const Real delta_t = std::sqrt(
        resolved_opening_squared(dot<D, Real>(opening_t, opening_t), dot<D, Real>(delta, delta)));
    VecD<D, Real> t;
    {
      const Real inv_len = Real(1) / delta_t;
      VecD<D, Real> perpendicular;
      if constexpr (D == 2) {
        perpendicular = {-n[1], n[0]};
      } else {  // tangent_or_perpendicular's axis least aligned with n
        // Selects between Reals only (see the flags below).
        const Real a0 = std::abs(n[0]), a1 = std::abs(n[1]), a2 = std::abs(n[2]);
        const Real best01 = a1 < a0 ? a1 : a0;
        const Real e1 = a1 < a0 ? Real(1) : Real(0);
        const Real n_axis = a2 < best01 ? n[2] : a1 < a0 ? n[1] : n[0];
        VecD<D, Real> e;
        e[0] = a2 < best01 ? Real(0) : Real(1) - e1;
        e[1] = a2 < best01 ? Real(0) : e1;
        e[2] = a2 < best01 ? Real(1) : Real(0);
        perpendicular = unit_or_zero<D, Real>(add_scaled<D, Real>(e, n, -n_axis));
      }
      for (int d = 0; d < D; ++d) t[d] = delta_t > 0 ? opening_t[d] * inv_len : perpendicular[d];
    }
    const Real hp = h_perp<D, Real>(n, cell);
    const Real dn = position_method ? delta_n - contact_offset * hp : delta_n;
    for (int d = 0; d < D; ++d) B.n[d][i] = valid ? n[d] : Real(0);
    B.dn[i] = valid ? dn : Real(0);
    const Real dp_n = dot<D, Real>(dp, n);

    VecD<D, Real> change, force{};
    [[maybe_unused]] double energy = 0;
    [[maybe_unused]] Real flags = 0;
    if constexpr (L != Law::interface) {
      // in_contact (P-9, P-12, P-14), with & on the masks.
      // USF's held pairs: hold_carried_lanes, after this loop.
      [[maybe_unused]] Real stuck;
      change = contact_change_lane<L, D, Real>((dp_n < 0) & (dn < 0), friction, dp, n, stuck);
    } else {
      // §3.2 traction (linear or bilinear), (P-20) area, §4.4 force limit.
      const Real Dn_now = bilinear & (dn < 0) ? Dn_compression : Dn;
      Real Tn, kn, en, Tt, kt, et;
      bool perfect_n, perfect_t;
      linear_direction(Dn_now, dn, Tn, kn, en, perfect_n);
      linear_direction(Dt_stiffness, delta_t, Tt, kt, et, perfect_t);
      Real area;
      if constexpr (A == ContactArea::gradient) {  // docs/multimaterial.md §7.2
        area =
            gradient_contact_area<D, Real>(dot<D, Real>(lane<D, Real>(B.g[0][0], i), n),
                                           dot<D, Real>(lane<D, Real>(B.g[1][0], i), n), thickness);
      } else {
        ClosedDomains<Real> vol{va, vb};
        if constexpr (A == ContactArea::closed) {  // docs/multimaterial.md §7.1
          const Real half = Real(0.5) * dn;
          const Real u_an = dot<D, Real>(lane<D, Real>(B.mx[0][0], i), n) * inv_ma;
          const Real u_bn = dot<D, Real>(lane<D, Real>(B.mx[1][0], i), n) * inv_mb;
          vol = close_opening(va, vb, dot<D, Real>(lane<D, Real>(B.g[0][0], i), n),
                              dot<D, Real>(lane<D, Real>(B.g[1][0], i), n),
                              position_method ? -half : u_an, position_method ? half : u_bn);
        }
        area = contact_area<D, Real>(vol.a, vol.b, hp, thickness);
      }
      const Real m_red = reduced_mass(ma, mb, false);
      VecD<D, Real> df{};
      if constexpr (UseDf)
        df = force_difference<D, Real>(ma, lane<D, Real>(B.f[0][0], i), mb,
                                       lane<D, Real>(B.f[1][0], i), false);
      const Real fn = Tn * area, ft = Tt * area;
      const bool over_n =
          exceeds_force_limit(fn, force_limit_component(m_red, dt, dn, dp_n, dot<D, Real>(df, n)));
      const bool over_t = exceeds_force_limit(
          ft, force_limit_component(m_red, dt, delta_t, dot<D, Real>(dp, t), dot<D, Real>(df, t)));
      const bool stiff_n = spring_beyond_one_step(fn, m_red, dt, dn);
      const bool stiff_t = spring_beyond_one_step(ft, m_red, dt, delta_t);
      // The direction flags as 0/1 Reals: boolean algebra over these lane
      // conditions became selects between booleans in GCC 12, which its
      // vectoriser rejects; products and sums of Reals do not.
      const Real one = 1, none = 0, limiting = force_limit ? one : none;
      const Real pn = perfect_n ? one : none, pt = perfect_t ? one : none;
      const Real ln = (one - pn) * limiting * (over_n ? one : none) * (stiff_n ? one : none);
      const Real lt = (one - pt) * limiting * (over_t ? one : none) * (stiff_t ? one : none);
      const Real st = pt + lt;  // stick: perfect or limited (exclusive)
      // A perfect compression branch of the bilinear law is one-sided
      // (kOneSidedNormal, docs/multimaterial.md §4.1): it sticks only while the
      // pair approaches and, released, exerts no force.
      const Real one_sided = pn * (bilinear & (dn < 0) ? one : none);
      const Real approaching = dp_n < 0 ? one : B.held[i];  // or held (USF)
      const Real released = one_sided * (one - approaching);
      const Real sn = pn + ln - released;
      flags = sn * Real(kStickNormal) + st * Real(kStickTangential) + sn * st * Real(kStickBoth) +
              one_sided * Real(kOneSidedNormal) + Real(16) * (ln + lt);
      change = stick_change_lane<D, Real>(sn != none, st != none, dp, n);
      const Real on = sn != none ? Real(0) : fn,
                 ot = st != none ? Real(0) : ft;  // released: perfect, fn = 0
      for (int d = 0; d < D; ++d) force[d] = on * n[d] + ot * t[d];
      energy = double(sn != none ? Real(0) : en * area) + double(st != none ? Real(0) : et * area);
    }
    for (int d = 0; d < D; ++d) B.change[d][i] = valid ? change[d] : Real(0);
    if constexpr (L == Law::interface) {
      for (int d = 0; d < D; ++d) B.force[d][i] = valid ? force[d] : Real(0);
      B.energy[i] = valid ? energy : 0.0;
      B.flags[i] = valid ? flags : Real(0);
    }
  }
  if constexpr (L == Law::interface) {  // unpack the flags: stick bits + 16 × limited
    for (int i = 0; i < count; ++i) {
      const int code = int(B.flags[i]);
      B.stick[i] = (unsigned char)(code & 15);
      B.limited[i] = code >> 4;
    }
  } else {  // contact laws: no force, energy or flags
    for (int i = 0; i < count; ++i) {
      for (int d = 0; d < D; ++d) B.force[d][i] = Real(0);
      B.energy[i] = 0;
      B.stick[i] = 0;
      B.limited[i] = 0;
    }
    hold_carried_lanes<L>(B);
  }
}

// Pass B on the lanes of B from pass A's saved normal and separation (B.n,
// B.dn) and stick flags (B.stick): interact_pass_b_saved lane by lane.
// strain_pass: MUSL's repeat, which holds the pairs B.stick marks
// kHeldInPassB. B.held: which pairs this pass held.
// flatten: as pass_a_lanes.
template <Law L, int D, class Real>
[[gnu::flatten]] void pass_b_lanes(PairBatch<D, Real>& B, bool strain_pass) {
  const Real friction = B.params->friction;
  const int count = B.count;
  // Held (1), or held stuck under Coulomb (2: stuck_before), as a Real, for
  // the reason given for sticks_tangential below.
  for (int i = 0; i < count; ++i)
    B.held[i] = stuck_before(B.stick[i], strain_pass)  ? Real(2)
                : held_before(B.stick[i], strain_pass) ? Real(1)
                                                       : Real(0);
  if constexpr (L == Law::interface) {
    // The tangential stick flag as a 0/1 Real in memory, for the loop below
    // to select on. A select on a test of the byte needs the byte lanes'
    // mask converted to the double lanes', which GCC 12 for rocketlake
    // (AVX-512 masks, 256-bit vectors) cannot do ("conversion not supported
    // by target"; a Real made of the byte's bits in the same loop is folded
    // back into that test, and a table is a gather it will not emit): the
    // 2D and 3D double loops were scalar there (2026-12-01).
    static_assert(kStickNormal == 1 && kStickTangential == 2 && kStickBoth == 4 &&
                  kOneSidedNormal == 8);
    for (int i = 0; i < count; ++i) {
      const unsigned s = B.stick[i];
      B.sticks_tangential[i] = Real(((s >> 1) | (s >> 2)) & 1u);  // tangential or both
    }
  }
#pragma GCC ivdep
  for (int i = 0; i < count; ++i) {
    const VecD<D, Real> n = lane<D, Real>(B.n[0], i);
    const VecD<D, Real> dp = momentum_change_to_center_of_mass<D, Real>(
        B.m[0][i], lane<D, Real>(B.p[0][0], i), B.m[1][i], lane<D, Real>(B.p[1][0], i), false);
    const bool has_normal = dot<D, Real>(n, n) != Real(0);
    VecD<D, Real> change;
    if constexpr (L == Law::interface) {
      // resolve_one_sided on the updated momenta, its flags as 0/1 Reals: with
      // selects between booleans GCC 12 left the 3D float loop scalar (as in
      // pass_a_lanes). Values made of the byte's bits, not tests of the byte
      // (see the loop above for the tangential flag).
      const unsigned s = B.stick[i];
      const Real stuck = Real((s | (s >> 2)) & 1u);  // normal or both
      const Real one_sided = Real((s >> 3) & 1u);
      const Real approaching = dot<D, Real>(dp, n) < 0 ? Real(1) : B.held[i];
      const Real normal = stuck + one_sided * (approaching - stuck);
      const Real tangential = B.sticks_tangential[i];
      change = stick_change_lane<D, Real>(normal != Real(0), tangential != Real(0), dp, n);
      B.held[i] = one_sided * approaching;
      B.stuck[i] = Real(0);
    } else {
      const bool contact =
          ((dot<D, Real>(dp, n) < 0) & (B.dn[i] < 0)) | (B.held[i] != Real(0));  // in_contact
      change = contact_change_lane<L, D, Real>(contact, friction, dp, n, B.stuck[i]);
      if constexpr (L == Law::friction) {  // stuck in pass B: sticks again (stuck_before)
        const bool stuck_before_here = B.held[i] > Real(1);
        for (int d = 0; d < D; ++d) change[d] = stuck_before_here ? dp[d] : change[d];
        B.stuck[i] = stuck_before_here ? Real(1) : B.stuck[i];
      }
      B.held[i] = contact ? Real(1) : Real(0);
    }
    for (int d = 0; d < D; ++d) B.change[d][i] = has_normal ? change[d] : Real(0);
  }
}

template <NormalMethod M, ContactArea A, int D, class Real>
void pass_a_interface_lanes(PairBatch<D, Real>& B, Real sign, const std::array<Real, 3>& h, Real dt,
                            Real thickness, bool use_force_difference) {
  if (use_force_difference)
    return pass_a_lanes<M, Law::interface, true, A>(B, sign, h, dt, thickness);
  return pass_a_lanes<M, Law::interface, false, A>(B, sign, h, dt, thickness);
}

template <NormalMethod M, int D, class Real>
void pass_a_lanes_of_law(PairBatch<D, Real>& B, Real sign, const std::array<Real, 3>& h, Real dt,
                         Real thickness, bool use_force_difference) {
  constexpr ContactArea kPaper = ContactArea::paper;
  switch (B.params->law) {
    case Law::stick:
      return pass_a_lanes<M, Law::stick, false, kPaper>(B, sign, h, dt, thickness);
    case Law::frictionless:
      return pass_a_lanes<M, Law::frictionless, false, kPaper>(B, sign, h, dt, thickness);
    case Law::friction:
      return pass_a_lanes<M, Law::friction, false, kPaper>(B, sign, h, dt, thickness);
    default:
      // The area rule (docs/multimaterial.md §7) as a template parameter: an
      // if or a select on a run-time flag around the closed area's loads kept
      // GCC 12 from vectorising the loop, and computing it in every lane gated
      // by a product cost the paper's area 5 % of pass A.
      switch (B.params->area) {
        case ContactArea::closed:
          return pass_a_interface_lanes<M, ContactArea::closed>(B, sign, h, dt, thickness,
                                                                use_force_difference);
        case ContactArea::gradient:
          return pass_a_interface_lanes<M, ContactArea::gradient>(B, sign, h, dt, thickness,
                                                                  use_force_difference);
        default:
          return pass_a_interface_lanes<M, kPaper>(B, sign, h, dt, thickness, use_force_difference);
      }
  }
}

// Pass A on a gathered batch whose pair is batchable (batchable_pair).
template <int D, class Real>
void pass_a_batch(PairBatch<D, Real>& B, const std::array<Real, 3>& h, Real dt, Real thickness,
                  bool use_force_difference) {
  const Real sign = B.field_a == B.params->first_field ? Real(1) : Real(-1);
  switch (B.params->normal_method) {
    case NormalMethod::avg:
      return pass_a_lanes_of_law<NormalMethod::avg>(B, sign, h, dt, thickness,
                                                    use_force_difference);
    case NormalMethod::specified:
      return pass_a_lanes_of_law<NormalMethod::specified>(B, sign, h, dt, thickness,
                                                          use_force_difference);
    case NormalMethod::radial:
      return pass_a_lanes_of_law<NormalMethod::radial>(B, sign, h, dt, thickness,
                                                       use_force_difference);
    default:  // mvg; rigid without a rigid partner is mvg (§5)
      return pass_a_lanes_of_law<NormalMethod::mvg>(B, sign, h, dt, thickness,
                                                    use_force_difference);
  }
}

template <int D, class Real>
void pass_b_batch(PairBatch<D, Real>& B, bool strain_pass) {
  switch (B.params->law) {
    case Law::stick:
      return pass_b_lanes<Law::stick>(B, strain_pass);
    case Law::frictionless:
      return pass_b_lanes<Law::frictionless>(B, strain_pass);
    case Law::friction:
      return pass_b_lanes<Law::friction>(B, strain_pass);
    default:
      return pass_b_lanes<Law::interface>(B, strain_pass);
  }
}

// The pairs the batch handles: explicit integration in pass A (the exact
// spring's sines stay on the per-node path); any law in pass B from saved
// geometry. Both fields deformable is checked by the caller.
template <class Real>
inline bool batchable_pair(const PairParams<Real>& pp, bool pass_a) {
  return !pass_a || pp.integration == Integration::explicit_;
}

}  // namespace mmpm::mm_detail
