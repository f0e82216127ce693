// Multimaterial pass: parameter and result types shared by its pieces, and the
// few small-vector helpers the pass needs. See docs/multimaterial.md and
// ALGORITHM §3-§7. Header-only, no allocation, no I/O.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "scene/scene.hpp"  // enums Law, NormalMethod, Separation, Integration, TractionLaw

namespace mmpm {

template <int D, class Real>
using VecD = std::array<Real, D>;

// At a node, a field of at most this fraction of the lightest particle's
// mass is empty (ALGORITHM §4.3): the grid update forms no velocity for it
// (Stepper::setup says why so small), and contact and interfaces leave it
// out (MultimaterialStage::setup says why the same).
inline constexpr double kEmptyMassFraction = 1e-15;

// USL only: at a node, a field of at most this fraction of the lightest
// particle's mass (or the Courant-scaled mass of linear shapes) is a light
// node, whose force the update leaves out (Stepper::set_usl_light_thresholds,
// kernels/mm_left_out.hpp).
inline constexpr double kSliverMassFraction = 1e-6;

// A rigid partner whose nodal domain fills less than this fraction of a cell
// is taken as absent at the node under the displacement (and extrapolated)
// separation: its surface lies about 0.65-0.7 h or more beyond the node
// (a flat face at distance s fills (1 - s)^2 / 2 of a linear hat's cell when
// it lies along a grid axis, and nearly as much at 45 degrees: 0.042 against
// 0.045 at s = 0.7 h), where only the overhang of its nearest particles reaches.
// Without it, a rigid platen pressed into a body pins that body's nodes one
// cell inside its surface, as the rigid's centre-of-mass velocity is its own
// whatever its mass there (ALGORITHM §7): the body's last cell of particles
// rode with the platen and the reaction read +h/(L - h) too stiff
// (docs/contact_validation.md §11). The position method has its own gap test;
// B-spline stencils do not use this one (MultimaterialStage::setup says why).
inline constexpr double kRigidPresentFraction = 0.05;

// Either material of a deformable frictionless pair whose nodal domain fills
// less than this fraction of a cell is taken as absent at the node, under the
// same separations and stencils as kRigidPresentFraction; under stick and
// Coulomb, only a sliver thin along the normal that faces a present partner
// (PairParams::presence_thin_along_normal; MultimaterialStage says why). A
// uGIMP particle's domain reaches the next node row as soon as it moves: a
// pressed face that travels e past a grid line puts a sliver of about
// e^2 / (2 h^2) of a cell on the row beyond it (0.3 % at e = 0.08 h), and
// the partner's load then entered one row too deep: a stiff platen on a
// block stiffened by 1.7 % over 0.08 h of travel
// (docs/contact_validation.md §14). Smaller than the rigid fraction because
// here both partners' slivers are screened: at 0.05 two blocks meeting at a
// third of a cell past a grid line (linear shapes) exchanged their velocities
// with a 7.7 % error instead of 1.5 %; 0.01-0.03 gave the same impacts within
// 1 % of each other (§15).
inline constexpr double kContactPresentFraction = 0.02;

// Properties of one interacting material pair (one [[interaction]] of the scene).
template <class Real>
struct PairParams {
  static constexpr Real kPerfect = std::numeric_limits<Real>::infinity();

  Law law = Law::stick;  // Law::separate behaves like a -1 entry of the pair table
  Real friction = 0;     // Coulomb mu (Law::friction), (P-16)
  Real Dn = 0;           // interface stiffness, normal (tension for bilinear); kPerfect = perfect
  Real Dt = 0;           // interface stiffness, tangential; kPerfect = perfect
  TractionLaw traction_law = TractionLaw::linear;
  Real Dn_compression = kPerfect;  // bilinear: normal stiffness used when delta_n < 0
  NormalMethod normal_method = NormalMethod::mvg;
  std::array<Real, 3> normal_vector{1, 0, 0};  // specified normal, from `first_field` to the other
  std::array<Real, 3> radial_center{0, 0, 0};  // radial normal n ∝ x_i − c, from `first_field` out
  // Unit axis of a cylindrical inclusion (3D): the radial normal drops its
  // component along it. Zero: radial about the point (the subtraction is
  // then exactly nothing).
  std::array<Real, 3> radial_axis{0, 0, 0};
  // Field the specified / radial normal points away from (the scene's materials[0]).
  // When the pass treats the other field as `a`, those normals are negated (n runs a → b).
  int first_field = -1;
  Separation separation = Separation::displacement;
  // δ_con / h⊥ of the position method (P-14): the extrapolated separation of
  // two surfaces that touch. The paper's 0.8; a smaller value registers
  // contact later (docs/contact_validation.md §4.3).
  Real contact_offset = Real(0.8);
  Real omega_min = 0;  // ABSOLUTE nodal domain below which the node is skipped (units of grid.vol)
  // ABSOLUTE nodal domain of a rigid partner below which it is absent at the
  // node (units of grid.vol; kRigidPresentFraction of a cell, 0 = no test).
  Real rigid_min_volume = 0;
  // ABSOLUTE nodal domain below which either material of a deformable contact
  // pair is absent at the node (units of grid.vol; kContactPresentFraction of
  // a cell, 0 = no test).
  Real presence_min_volume = 0;
  // The presence test absents only a sliver thin along the normal whose
  // partner is present (mm_detail::partner_absent); needs g (P-33).
  bool presence_thin_along_normal = false;
  bool force_limit = true;  // §4.4 (explicit integration only)
  Integration integration = Integration::explicit_;
  // Interface law only: (P-20) on the domains as they are (paper), on the domains
  // with the opening closed (closed, docs/multimaterial.md §7.1), or from the
  // domain gradients (gradient, §7.2). The last two read g (P-33) whatever the normal.
  ContactArea area = ContactArea::paper;
};

// Whether a pair reads the domain gradients g (P-33): the mvg, avg and rigid
// normals, and the closed and gradient areas (docs/multimaterial.md §7.1, §7.2).
template <class Real>
bool reads_domain_gradient(const PairParams<Real>& pp) {
  return pp.normal_method == NormalMethod::mvg || pp.normal_method == NormalMethod::avg ||
         pp.normal_method == NormalMethod::rigid || pp.area != ContactArea::paper;
}

// Everything the two passes need besides the grid.
template <int D, class Real>
struct MMConfig {
  int fields = 0;             // F: material velocity fields
  const int* pair = nullptr;  // F*F table: [a*F+b] = index into params, -1 = separate
  const PairParams<Real>* params = nullptr;
  const unsigned char* rigid = nullptr;  // F flags; null = no rigid field
  Real dt = 0;                           // time step
  // The step the stick decisions of §4.4 (force limit) and §4.5 (ωΔt above
  // kExactStickOmegaDt) are made for: the run's regular step, also in a last
  // step shortened to land on end_time (Stepper::step_within); 0: dt. With
  // the shortened dt those tests let directions go that every earlier step
  // held stuck, and their springs, at separations stick had frozen, came
  // back at once: the last row of a stiff sphere_in_cube run read 5.7 times
  // the interface energy of the row before (docs/multimaterial.md §8).
  Real limit_dt = 0;
  Real stick_dt() const { return limit_dt > 0 ? limit_dt : dt; }
  // 2D only: multiplies the area (P-20). Use the thickness t when grid.vol holds areas
  // (Σ S_ip A_p, as in P-19); use 1 when grid.vol already holds A_p·t.
  Real thickness = 1;
  Real mass_threshold = 0;  // a field with m <= threshold is empty at the node
  // Include Δf_i of (P-27) from grid.f in the force limit and in the exact integration.
  // Off by default (ALGORITHM §2: neglected in pass A).
  bool use_force_difference = false;
  // Two-material nodes of one pair in SIMD batches (kernels/mm_pair_batch.hpp).
  // false: every node by the per-node path; the tests compare the two.
  bool batch_pairs = true;
  // USL only (null otherwise): per field the light-node mass m_L, and the
  // grid's dvel, where update_deformable put a light field's left-out force.
  // Pass B after the update moves it where it sticks a pair
  // (kernels/mm_left_out.hpp).
  const Real* light_mass = nullptr;
  std::array<Real*, D> light_dvel{};
  std::array<Real, 3> light_gravity{};         // the step's gravity (the update's)
  const unsigned char* light_fixed = nullptr;  // per node: bit d, a support fixes axis d
};

// Per-step diagnostics. Both passes ADD to it; reset() before pass A of a step.
struct MMStats {
  double interface_energy = 0;  // Σ U_i (ALGORITHM §3.2), counted per §6
  long nodes_2 = 0;             // nodes with exactly two materials (pass A)
  long nodes_3plus = 0;         // nodes with three or more materials (pass A)
  long force_limited = 0;       // node-directions converted to stick (§4.4 / §4.5) in pass A
  // Reaction force on each rigid field: −Σ(momentum changes/dt + interface forces) applied
  // to the non-rigid materials it touches (zero for non-rigid fields). Size F.
  std::vector<std::array<double, 3>> rigid_reaction;

  void reset(int fields) {
    interface_energy = 0;
    nodes_2 = nodes_3plus = force_limited = 0;
    rigid_reaction.assign(std::size_t(fields), std::array<double, 3>{0, 0, 0});
  }
};

// stick_flags bits (one byte per (node of the list, field a)): interface directions that
// pass A turned into stick (perfect or limited), which pass B re-applies.
inline constexpr unsigned char kStickNormal = 1;
inline constexpr unsigned char kStickTangential = 2;
inline constexpr unsigned char kStickBoth = 4;
// The normal direction is in the perfect compression branch of the bilinear law: a
// one-sided constraint, as contact is (docs/multimaterial.md §4.1). It sticks only while
// the pair approaches (Δp_a·n < 0): pass A decides it on its momenta, pass B again on the
// updated ones. Before, the stick held a closed gap shut while the bodies pulled apart
// (the bouncing bars of §4.1).
inline constexpr unsigned char kOneSidedNormal = 8;
// Set by pass B after the momentum update where it applied a contact law, or stuck a
// one-sided normal: the pair was held against approach there, and the particles moved
// with that. MUSL's repeat of pass B on the re-extrapolated momenta (the strain's
// velocities) holds these pairs too, even where the new momenta part; elsewhere it
// decides on approach as pass B does. Why: the re-extrapolated relative velocity of a
// pressed pair is noise of either sign, and a repeat that only stops approach let the
// strain see every parting the particles never made. Under pure FLIP that noise is
// kept, the strain fell behind the motion step by step, and a platen pressed into a
// block read 0.1-2.1 of its reaction (docs/contact_validation.md §12). USF's pass A,
// whose momenta are the strain's velocities, holds the pairs the last step's pass B
// held for the same reason (MultimaterialStage carries the bits from step to step;
// docs/contact_validation.md §13).
inline constexpr unsigned char kHeldInPassB = 16;
// Set with kHeldInPassB where the held pair did not slide (the stick law, or Coulomb
// friction inside its cone). USF's pass A sticks such a Coulomb pair: its extrapolated
// momenta carry no normal push to bound the friction with (that comes with the
// forces, in pass B), so the cone of its own let the strain slide where the bodies
// stuck (a platen pressed through mu = 0.3 read 1.003-1.010 of the stiffness it has
// stuck, 1.051; docs/contact_validation.md §13).
inline constexpr unsigned char kStuckInPassB = 32;
// The bits pass B leaves for the next step (USF's pass A reads them,
// MultimaterialStage::carry_held_pairs carries them).
inline constexpr unsigned char kPassBRecord = kHeldInPassB | kStuckInPassB;
// Whether pass B holds this pair regardless of approach: only in MUSL's strain pass,
// and only where the pass B before it held the pair.
inline bool held_before(unsigned char stick, bool strain_pass) {
  return strain_pass && (stick & kHeldInPassB) != 0;
}
// Whether MUSL's strain pass sticks a Coulomb pair: where the pass B before it
// held the pair inside its cone (kStuckInPassB). The re-extrapolated momenta
// carry no normal push to bound the friction with, as USF's pass A's do not
// (kStuckInPassB above): the cone of their own let the strain slide along a
// face the particles held (docs/contact_validation.md §17).
inline bool stuck_before(unsigned char stick, bool strain_pass) {
  return held_before(stick, strain_pass) && (stick & kStuckInPassB) != 0;
}

// The stick flags with a one-sided normal decided by whether the pair approaches.
inline unsigned char resolve_one_sided(unsigned char stick, bool approaching) {
  if ((stick & kOneSidedNormal) == 0) return stick;
  const bool tangential = (stick & (kStickTangential | kStickBoth)) != 0;
  return (unsigned char)(kOneSidedNormal | (approaching ? kStickNormal : 0) |
                         (tangential ? kStickTangential : 0) |
                         (approaching && tangential ? kStickBoth : 0));
}

// Fields handled at one node (gathered into fixed-size local arrays).
inline constexpr int kMaxFields = 32;

namespace mm_detail {

template <int D, class Real>
inline Real dot(const VecD<D, Real>& u, const VecD<D, Real>& v) {
  Real s = 0;
  for (int d = 0; d < D; ++d) s += u[d] * v[d];
  return s;
}

template <int D, class Real>
inline VecD<D, Real> scaled(const VecD<D, Real>& u, Real s) {
  VecD<D, Real> r;
  for (int d = 0; d < D; ++d) r[d] = u[d] * s;
  return r;
}

// u + s v
template <int D, class Real>
inline VecD<D, Real> add_scaled(const VecD<D, Real>& u, const VecD<D, Real>& v, Real s) {
  VecD<D, Real> r;
  for (int d = 0; d < D; ++d) r[d] = u[d] + s * v[d];
  return r;
}

// Unit vector along u, or all zeros when |u| is zero or not finite.
template <int D, class Real>
inline VecD<D, Real> normalized_or_zero(const VecD<D, Real>& u) {
  const Real len = std::sqrt(dot<D, Real>(u, u));
  if (!(len > 0) || !std::isfinite(len)) return VecD<D, Real>{};
  return scaled<D, Real>(u, Real(1) / len);
}

// Whether a material's nodal domain is thin along n: its gradient g (P-33)
// lies within 45 degrees of the normal. A sliver beyond a face pressed
// across a grid line is thin along the normal; one beside a free edge that
// bulges past a grid line in the contact row is thin across it (zero g: not
// along n).
template <int D, class Real>
inline bool thin_along_normal(const VecD<D, Real>& g, const VecD<D, Real>& n) {
  const Real gn = dot<D, Real>(g, n);
  return Real(2) * gn * gn > dot<D, Real>(g, g);
}

// The presence test of a deformable pair (PairParams::presence_min_volume,
// 0: none). Frictionless: either partner's sliver is absent. With
// thin_along_only (PairParams::presence_thin_along_normal, stick): only a
// sliver thin along n that faces a present partner, the kind that carried
// the partner's load a row too deep (docs/contact_validation.md §15). A
// sliver beside a free edge carries the corner's shear into the partner:
// freed, its node drove the corner particle (§16). & and | keep the test
// branch-free in the pair batch's lanes.
template <int D, class Real>
inline bool partner_absent(Real vol_a, Real vol_b, const VecD<D, Real>& g_a,
                           const VecD<D, Real>& g_b, const VecD<D, Real>& n, Real presence,
                           bool thin_along_only) {
  const bool sliver_a = vol_a < presence, sliver_b = vol_b < presence;
  const bool along = (sliver_a & !sliver_b & thin_along_normal<D, Real>(g_a, n)) |
                     (sliver_b & !sliver_a & thin_along_normal<D, Real>(g_b, n));
  return ((!thin_along_only) & (sliver_a | sliver_b)) | (thin_along_only & along);
}

}  // namespace mm_detail
}  // namespace mmpm
