// USL's light nodes at a pair that pass B holds (docs/validation.md §3.5,
// "The whole force, and where it is held" and "Sliding pairs").
//
// Under USL a field lighter than m_L at a node takes only f m / m_L of its
// force into the momentum (update_deformable, kernels/grid_update.hpp); the
// rest, dt f (1 / m − 1 / m_L), goes to the particles through dvel alone.
// That bounds the light field's own velocity, which is what USL's strain
// reads. But where pass B sticks the pair, the velocity along the stuck
// directions is the pair's, over the mass m_a + m_b, and is bounded without
// the rule; left in place, the left-out part missed the exchange: the
// pair's momentum balanced only the kept share of the light field's force
// (a static interface's equilibrium moved, sphere in cube U +3.2 % at
// cfl 0.5), and the rest reached one field's particles every step, a
// velocity mode the other field's particles did not share.
//
// Here, along the stuck directions only, the pair is one node of mass
// M = m_a + m_b, and the light-node rule is applied to it: field x keeps
// min(1, M / m_Lx) of its force in the momentum, so of its left-out impulse
// J_x = dt f_x (1 − m_x / m_Lx) the share ρ_x = min(1, (M − m_x) / (m_Lx − m_x))
// moves into the momenta (split by mass, so the pair stays stuck), and the
// rest goes to both fields' dvel as one velocity over M. A rigid partner
// absorbs the light field's left-out impulse along the stuck directions (its
// reaction takes it). The particles' total momentum change is unchanged.
// A pair pass B lets slide (Coulomb) is held along its normal only, with
// the friction that normal impulse carries (exchange_left_out below).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>

#include "kernels/grid_view.hpp"
#include "kernels/light_nodes.hpp"
#include "kernels/mm_common.hpp"
#include "kernels/mm_contact.hpp"

namespace mmpm {

// The directions a pass B result stuck the pair in, as the kStick* bits
// directional_stick_change reads: from the pair's law, pass A's flags for
// it, and pass B's held / stuck (InteractionResult, or the batch's lanes).
inline unsigned char stuck_directions(Law law, unsigned char pass_a_flags, bool held, bool stuck) {
  if (law == Law::interface) {
    // A one-sided normal sticks where pass B held it (resolve_one_sided).
    const bool normal = (pass_a_flags & kOneSidedNormal) != 0
                            ? held
                            : (pass_a_flags & (kStickNormal | kStickBoth)) != 0;
    const bool tangential = (pass_a_flags & (kStickTangential | kStickBoth)) != 0;
    if (normal && tangential) return kStickBoth;
    return (unsigned char)((normal ? kStickNormal : 0) | (tangential ? kStickTangential : 0));
  }
  // Contact: held sticks the normal; stuck (stick, Coulomb inside its cone)
  // the tangential too. A sliding Coulomb pair is held along the normal only
  // (exchange_left_out adds the friction that the exchanged normal impulse
  // carries).
  if (!held) return 0;
  return stuck ? kStickBoth : kStickNormal;
}

// How pass B held a pair, for exchange_left_out: the stuck directions, and
// for a sliding Coulomb pair its friction coefficient.
template <class Real>
struct PassBHold {
  unsigned char directions = 0;  // kStick* bits (stuck_directions)
  bool sliding = false;          // Coulomb, held but not stuck
  Real friction = 0;             // its mu
};

template <class Real>
PassBHold<Real> pass_b_hold(Law law, Real friction, unsigned char pass_a_flags, bool held,
                            bool stuck) {
  PassBHold<Real> hold;
  hold.directions = stuck_directions(law, pass_a_flags, held, stuck);
  hold.sliding = law == Law::friction && held && !stuck;
  hold.friction = hold.sliding ? friction : Real(0);
  return hold;
}

template <int D, class Real>
VecD<D, Real> left_out_velocity(const GridView<D, Real>& grid, std::size_t i, Real m, Real light,
                                const std::array<Real, 3>& gravity, Real dt) {
  VecD<D, Real> v{};
  for (int d = 0; d < D; ++d) v[d] = light_left_out<D, Real>(grid, i, d, m, light, gravity[d], dt);
  return v;
}

// The exchange above at `node` for the pair (fa, fb) that pass B held as
// `hold` says (pass_b_hold) about the unit normal n. Writes grid.p and
// dvel; returns the momentum change a rigid fb takes from a (for its
// reaction; zero for a deformable fb). `fixed` (bit d: a support fixes axis
// d at the node) leaves those components alone: the support then takes
// each field's own left-out velocity there (apply_supports), and with this
// exchange too it took it twice (a particle-velocity mode where the
// two-layer interface meets its fixed bottom).
//
// A sliding Coulomb pair (docs/validation.md §3.5, "Sliding pairs") is
// exchanged along the normal only, and only where the left-out velocities
// press the pair together (contact does not pull): that adds the normal
// impulse J = m_r ((v'_a − v'_b)·n), m_r = m_a m_b / M (m_a for a rigid b),
// to the one pass B applied, and with it the friction μ J, against the
// pair's tangential sliding (kept, read from the momenta after pass B's
// change, plus left-out), capped where that sliding would stop. The
// friction goes to dvel, where the left-out part lives: applied to a light
// field's momentum it would move the velocity its strain reads. Left
// without it, the normal impulse held the block on incline_block.toml with
// no friction for it (a +0.17 % at cfl 0.5); left out altogether, the
// block on rotated_incline.toml slid with too little friction (K +25 % at
// cfl 0.65).
template <int D, class Real>
VecD<D, Real> exchange_left_out(GridView<D, Real>& grid, const Real* light_mass,
                                const std::array<Real*, D>& dvel,
                                const std::array<Real, 3>& gravity, Real dt, std::size_t node,
                                int fa, int fb, bool b_rigid, const PassBHold<Real>& hold,
                                const VecD<D, Real>& n, unsigned char fixed) {
  using namespace mm_detail;
  VecD<D, Real> absorbed{};
  // No normal: pass B left the pair alone.
  if (hold.directions == 0 || dot<D, Real>(n, n) == Real(0)) return absorbed;
  const std::size_t ia = grid.at(fa, node), ib = grid.at(fb, node);
  const Real ma = grid.m[ia], mb = grid.m[ib];
  const Real la = light_mass[fa], lb = b_rigid ? Real(0) : light_mass[fb];
  const bool a_light = ma <= la, b_light = !b_rigid && mb <= lb;
  if (!a_light && !b_light) return absorbed;
  const VecD<D, Real> full_a = left_out_velocity<D, Real>(grid, ia, ma, la, gravity, dt);
  const VecD<D, Real> full_b =
      b_rigid ? VecD<D, Real>{} : left_out_velocity<D, Real>(grid, ib, mb, lb, gravity, dt);
  VecD<D, Real> friction{};  // the sliding pair's friction impulse on a
  if (hold.sliding) {
    const VecD<D, Real> relative = add_scaled<D, Real>(full_a, full_b, Real(-1));
    const Real approach = dot<D, Real>(relative, n);
    if (!(approach > Real(0))) return absorbed;
    const Real m_r = b_rigid ? ma : ma * mb / (ma + mb);
    VecD<D, Real> slide;  // a's tangential velocity relative to b, kept plus left-out
    for (int d = 0; d < D; ++d) slide[d] = grid.p[d][ia] / ma - grid.p[d][ib] / mb + relative[d];
    slide = add_scaled<D, Real>(slide, n, -dot<D, Real>(slide, n));
    const Real speed = std::sqrt(dot<D, Real>(slide, slide));
    if (speed > Real(0))
      friction =
          scaled<D, Real>(slide, -std::min(hold.friction * m_r * approach, m_r * speed) / speed);
  }
  auto along = [&](const VecD<D, Real>& v) {
    return directional_stick_change<D, Real>(hold.directions, v, n);
  };
  const VecD<D, Real> lo_a = along(full_a);
  if (b_rigid) {
    for (int d = 0; d < D; ++d) {
      if ((fixed >> d) & 1u) continue;
      dvel[d][ia] += friction[d] / ma - lo_a[d];
      absorbed[d] = friction[d] - ma * lo_a[d];
    }
    return absorbed;
  }
  const VecD<D, Real> lo_b = along(full_b);
  const Real total = ma + mb;
  const Real rho_a = a_light && ma < la ? std::min(Real(1), mb / (la - ma)) : Real(0);
  const Real rho_b = b_light && mb < lb ? std::min(Real(1), ma / (lb - mb)) : Real(0);
  const Real inv_total = Real(1) / total;
  for (int d = 0; d < D; ++d) {
    if ((fixed >> d) & 1u) continue;
    const Real ja = ma * lo_a[d], jb = mb * lo_b[d];
    const Real restored = rho_a * ja + rho_b * jb;
    const Real shared = ((ja - rho_a * ja) + (jb - rho_b * jb)) * inv_total;
    grid.p[d][ia] += ma * inv_total * restored;
    grid.p[d][ib] += mb * inv_total * restored;
    dvel[d][ia] += shared - lo_a[d] + friction[d] / ma;
    dvel[d][ib] += shared - lo_b[d] - friction[d] / mb;
  }
  return absorbed;
}

}  // namespace mmpm
