// The multimaterial pass (ALGORITHM §2 steps 3 and 5, §3 … §7) over the compact
// list of multimaterial nodes. Pieces: mm_common.hpp (types), mm_normals.hpp (§5),
// mm_contact.hpp (§3.1), mm_interface.hpp (§3.2, §4). Derivations and the exact
// contract of each pass: docs/multimaterial.md.
//
//   find_multimaterial_nodes  nodes where ≥ 2 fields have m > threshold, ascending
//   multimaterial_pass_a      after P2G: contact momentum changes, interface forces
//                             into grid.fi, energy, force limit → stick_flags
//   multimaterial_pass_b      after the grid momentum update: contact on the new
//                             momenta, stick re-applied where stick_flags say so
//
// Two-material nodes of one pair are computed a chunk at a time in lanes
// (kernels/mm_pair_batch.hpp, process_chunk); every other node node by node.
//
// Every node of the list is independent (it writes only its own grid entries), so the
// node loop runs in parallel, each thread on the nodes it owns first
// (kernels/node_ownership.hpp); statistics are summed per fixed chunk of the list and the
// chunks are added in order, so results do not depend on the number of threads.
#pragma once

#include <algorithm>
#include <atomic>
#include <bit>
#include <cassert>
#include <cstdint>
#include <cstring>
#include <memory>
#include <utility>
#include <vector>

#include "kernels/grid_view.hpp"
#include "kernels/mixed_tiles.hpp"
#include "kernels/mm_common.hpp"
#include "kernels/mm_contact.hpp"
#include "kernels/mm_interface.hpp"
#include "kernels/mm_left_out.hpp"
#include "kernels/mm_normals.hpp"
#include "kernels/mm_pair_batch.hpp"
#include "kernels/node_ownership.hpp"

namespace mmpm {

// The passes run on a team from two chunks of the list up (a chunk is
// PairBatch::kLanes = 64 nodes; one chunk leaves the second thread idle).
// With the threshold at 1024 the two-layer scene's 250-490 interface nodes
// ran on one thread: its stage alone took 33-37 us per step on two threads
// and 43-45 on one; from 128, 22-24 (docs/performance.md, "The
// multimaterial pass on two threads from 128 nodes").
inline constexpr std::size_t kParallelNodes = 128;

// One material at a node, or the lump of several ("virtual b", §3, §6).
template <int D, class Real>
struct MaterialSide {
  Real m = 0, vol = 0;
  VecD<D, Real> p{}, mx{}, g{}, f{};
};

// What an interaction does to material a (b gets the negatives when deformable).
template <int D, class Real>
struct InteractionResult {
  VecD<D, Real> momentum_change{};  // added to p_a
  VecD<D, Real> force{};            // added to fi_a (interface force, P-17)
  double energy = 0;                // interface energy U_i (§3.2)
  unsigned char stick = 0;          // kStick* bits of interface directions made stick
  int limited = 0;                  // directions converted to stick by §4.4 / §4.5
  bool evaluated = false;           // false: screened (§3 Ω_min) or no normal
  bool held = false;   // pass B: a contact law applied, or a one-sided normal stuck (kHeldInPassB)
  bool stuck = false;  // pass B: held by a contact that did not slide (kStuckInPassB)
  VecD<D, Real> normal{};  // pass B: the pair's normal (for exchange_left_out)
};

// Geometry and kinematics of a pair at a node (§3, P-7 … P-15).
template <int D, class Real>
struct PairGeometry {
  VecD<D, Real> n{};   // unit normal a → b
  VecD<D, Real> dp{};  // Δp_a (P-7), rigid b: (P-29)
  VecD<D, Real> t{};   // unit tangent along the tangential opening (P-15)
  Real delta_n = 0;    // δ·n (P-12)
  Real delta_t = 0;    // |δ − δ_n n| ≥ 0 (P-15)
  Real h_perp = 0;     // (P-22)
  bool valid = false;
};

// What pass B needs of pass A's geometry for one interaction (node, field a).
// m, mx, Ω and g do not change between the passes (only the momenta do), so
// neither do the normal and the corrected normal separation; recomputing
// them (two square roots and four divisions on a dependent chain) was about
// half of a pass B, which MUSL runs twice per step (docs/multimaterial.md,
// "Pass B reuses pass A's geometry").
template <int D, class Real>
struct SavedGeometry {
  VecD<D, Real> n{};  // unit normal a → b; zero: pass A found no usable geometry
  Real dn = 0;        // corrected normal separation (§4.3)
};

// What pass A leaves for pass B: per chunk of the list its batch, per
// interaction of the per-node path its geometry.
template <int D, class Real>
struct PassAGeometry {
  // Entry [k * F + a]; written only for the interactions pass A computed
  // node by node (a batched lane's is in its chunk's batch).
  std::vector<SavedGeometry<D, Real>> nodes;
  std::vector<mm_detail::SavedBatch<D, Real>> batches;  // one per PairBatch::kLanes entries
};

// Checks a configuration once, outside the hot loops. nullptr when usable.
template <int D, class Real>
const char* validate_multimaterial(const GridView<D, Real>& grid, const MMConfig<D, Real>& cfg) {
  const int F = cfg.fields;
  if (F != grid.fields) return "MMConfig.fields differs from GridView.fields";
  if (F < 2 || F > kMaxFields) return "multimaterial pass needs 2 <= fields <= kMaxFields";
  if (!cfg.pair) return "MMConfig.pair is required";
  if (!(cfg.dt > 0)) return "MMConfig.dt must be positive";
  if (!grid.m || !grid.vol) return "grid m and vol are required";
  for (int d = 0; d < D; ++d)
    if (!grid.p[d] || !grid.mx[d]) return "grid p and mx are required";
  for (int a = 0; a < F; ++a) {
    for (int b = 0; b < F; ++b) {
      const int k = cfg.pair[a * F + b];
      if (k != cfg.pair[b * F + a]) return "MMConfig.pair must be symmetric";
      if (k < 0 || a == b) continue;
      if (!cfg.params) return "MMConfig.params is required by the pair table";
      const PairParams<Real>& pp = cfg.params[k];
      const bool gradient = reads_domain_gradient(pp);
      if (pp.presence_thin_along_normal && pp.presence_min_volume > 0 && !gradient)
        return "stick's presence test (a sliver thin along the normal) needs the mvg, avg or rigid "
               "normal";
      for (int d = 0; d < D; ++d) {
        if (gradient && !grid.g[d])
          return "grid g is required by the mvg/avg/rigid normals and the closed area";
        if (pp.law == Law::interface && !grid.fi[d]) return "grid fi is required by interfaces";
        if (cfg.use_force_difference && !grid.f[d]) return "grid f is required by Δf";
      }
    }
  }
  return nullptr;
}

namespace mm_detail {
inline constexpr std::size_t kFindBlock = 4096;
inline constexpr std::size_t kFindGroup = 64;

// Does any of the kFindGroup `present` counts at p reach 2? Eight counts at
// a time as one word: a count (< 256) is >= 2 exactly when a bit above its
// lowest is set. Why: listing a group node by node costs ~1.5 cycles per
// node, and one interface line across the grid (the two-layer scene: ~300
// of 65 000 nodes) leaves most groups without a listed node. With the
// first pass's counts kept, the search there went 80 -> 44 us per step on
// one thread (docs/multimaterial.md, "Finding the multimaterial nodes").
inline bool any_two_or_more(const unsigned char* p) {
  static_assert(kFindGroup % 8 == 0);
  std::uint64_t any = 0;
  for (std::size_t w = 0; w < kFindGroup; w += 8) {
    std::uint64_t word;
    std::memcpy(&word, p + w, sizeof word);
    any |= word;
  }
  return (any & 0xFEFEFEFEFEFEFEFEull) != 0;
}

// Bit k set when count k of the n <= 64 counts at p is >= 2. Eight counts
// per word: a byte is nonzero after masking its lowest bit exactly when its
// count is >= 2; adding 0x7F to the low 7 bits carries into the high bit of
// every nonzero byte; one multiply gathers the eight high bits (each lands
// in its own bit of the top byte, no carries). Why: the listing then costs
// a few operations per word and one per listed node, where a node-by-node
// pass over a group cost ~1.5 cycles per node; with an interface across
// the rows (two-layer scene) every row's run has a group to list.
inline std::uint64_t two_or_more_bits(const unsigned char* p, std::size_t n) {
  constexpr std::uint64_t kLow7 = 0x7F7F7F7F7F7F7F7Full, kHigh = 0x8080808080808080ull;
  std::uint64_t bits = 0;
  std::size_t k = 0;
  for (; k + 8 <= n; k += 8) {
    std::uint64_t word;
    std::memcpy(&word, p + k, sizeof word);
    const std::uint64_t t = word & 0xFEFEFEFEFEFEFEFEull;
    const std::uint64_t nonzero = (((t & kLow7) + kLow7) | t) & kHigh;
    bits |= ((nonzero >> 7) * 0x0102040810204080ull >> 56) << k;
  }
  for (; k < n; ++k) bits |= std::uint64_t(p[k] >= 2) << k;
  return bits;
}

// Fields present (m > threshold) at each node of [first, first + count),
// count <= kFindBlock. Field by field over contiguous masses: vectorised.
// The first field sets the counts (no zeroing pass: the runs of a
// mixed-tile search are short, kernels/mixed_tiles.hpp).
template <class Real>
void fields_present(const Real* m, std::size_t nodes, int fields, Real threshold, std::size_t first,
                    std::size_t count, unsigned char* present) {
  const Real* m0 = m + first;
  for (std::size_t i = 0; i < count; ++i) present[i] = m0[i] > threshold;
  for (int f = 1; f < fields; ++f) {
    const Real* mf = m + std::size_t(f) * nodes + first;
    for (std::size_t i = 0; i < count; ++i) present[i] += mf[i] > threshold;
  }
}
}  // namespace mm_detail

// Nodes where at least two fields have m > mass_threshold, in ascending order.
// Blocks of nodes are searched by the thread that owns them
// (kernels/node_ownership.hpp), each block's nodes listed into a slot of its
// own; the slots are then joined in block order, so the list does not depend
// on who did which. With `mixed` (kernels/mixed_tiles.hpp) only the nodes of
// tiles next to particles of two or more fields are read: the same list, as
// no other node can hold two fields' mass.
template <int D, class Real>
void find_multimaterial_nodes(const GridView<D, Real>& grid, Real mass_threshold,
                              std::vector<std::uint32_t>& list, const NodeOwnership& own = {},
                              const MixedTiles<D>* mixed = nullptr) {
  using mm_detail::kFindBlock;
  using mm_detail::kFindGroup;
  const std::size_t nodes = grid.nodes;
  const int F = grid.fields;
  if (F < 2 || !grid.m || nodes == 0) {
    list.clear();
    return;
  }
  const std::size_t blocks = (nodes + kFindBlock - 1) / kFindBlock;
  std::vector<std::size_t> offset(blocks + 1, 0);
  // Block b's nodes, listed at slot b * kFindBlock; only the listed entries
  // are written. Why one walk: listing in a second walk over the candidate
  // runs (from the counts of the first) cost a third of the search where an
  // interface crosses the rows, one short run per row (two-layer scene:
  // 255 runs of 48 nodes), docs/multimaterial.md "Finding the
  // multimaterial nodes".
  const std::unique_ptr<std::uint32_t[]> slots(new std::uint32_t[blocks * kFindBlock]);

  team_run(nodes >= kParallelMin, [&] {
    const auto [b0, b1] =
        own.chunks(nodes, kFindBlock, std::size_t(team_size()), std::size_t(team_rank()));
    unsigned char present[kFindBlock];
    auto block_count = [&](std::size_t b) {
      return std::min(nodes, (b + 1) * kFindBlock) - b * kFindBlock;
    };
    // body(first, count) over the nodes of block b that can hold two
    // fields: runs of mixed tiles, or the whole block without `mixed`.
    auto for_candidates = [&](std::size_t b, auto&& body) {
      if (mixed)
        mixed->for_each_mixed_run(b * kFindBlock, block_count(b), body);
      else
        body(b * kFindBlock, block_count(b));
    };
    for (std::size_t b = b0; b < b1; ++b) {
      std::uint32_t* found = slots.get() + b * kFindBlock;
      std::size_t out = 0;  // a local: `found` entries of this block
      for_candidates(b, [&](std::size_t first, std::size_t count) {
        mm_detail::fields_present(grid.m, nodes, F, mass_threshold, first, count, present);
        for (std::size_t g = 0; g < count; g += kFindGroup) {
          const std::size_t n = std::min(kFindGroup, count - g);
          if (n == kFindGroup && !mm_detail::any_two_or_more(present + g)) continue;
          for (std::uint64_t bits = mm_detail::two_or_more_bits(present + g, n); bits != 0;
               bits &= bits - 1)
            found[out++] = std::uint32_t(first + g + std::size_t(std::countr_zero(bits)));
        }
      });
      offset[b + 1] = out;
    }
  });
  // Joined after the region, on one thread: the blocks' counts and the
  // ~250 listed nodes of an interface scene take well under a microsecond,
  // where a prefix sum between two barriers inside the region cost two
  // round trips between the cores (0.3-2.4 us each on the VM hosts,
  // docs/performance.md "The multimaterial search joined after its region").
  std::size_t total = 0;
  for (std::size_t b = 0; b < blocks; ++b) total += offset[b + 1];
  list.resize(total);
  std::size_t at = 0;
  for (std::size_t b = 0; b < blocks; ++b) {
    const std::uint32_t* found = slots.get() + b * kFindBlock;
    std::copy(found, found + offset[b + 1], list.begin() + std::ptrdiff_t(at));
    at += offset[b + 1];
  }
}

namespace mm_detail {

// Normal by the pair's method (§5). `sign` orients specified/radial normals a → b.
template <int D, class Real>
VecD<D, Real> interface_normal(const PairParams<Real>& pp, const MaterialSide<D, Real>& a,
                               const MaterialSide<D, Real>& b, bool b_is_rigid, Real sign,
                               const std::array<Real, 3>& node_position) {
  switch (pp.normal_method) {
    case NormalMethod::avg:
      return normal_avg<D, Real>(a.vol, a.g, b.vol, b.g);
    case NormalMethod::specified:
      return normal_specified<D, Real>(pp.normal_vector, sign);
    case NormalMethod::radial:
      return normal_radial<D, Real>(node_position, pp.radial_center, pp.radial_axis, sign);
    case NormalMethod::rigid:  // RMVG; without a rigid partner it falls back to MVG
      if (b_is_rigid) return normal_rigid<D, Real>(b.g);
      return normal_mvg<D, Real>(a.g, b.g);
    case NormalMethod::mvg:
    default:
      return normal_mvg<D, Real>(a.g, b.g);
  }
}

template <int D, class Real>
PairGeometry<D, Real> pair_geometry(const MaterialSide<D, Real>& a, const MaterialSide<D, Real>& b,
                                    bool b_is_rigid, const PairParams<Real>& pp, Real sign,
                                    const std::array<Real, 3>& node_position,
                                    const std::array<Real, 3>& h) {
  PairGeometry<D, Real> G;
  G.n = interface_normal<D, Real>(pp, a, b, b_is_rigid, sign, node_position);
  if (dot<D, Real>(G.n, G.n) == Real(0)) return G;  // no direction: skip the node
  G.dp = momentum_change_to_center_of_mass<D, Real>(a.m, a.p, b.m, b.p, b_is_rigid);
  // δ = x_b − x_a with x_j = mx_j / m_j (P-11; rigid b: P-31).
  VecD<D, Real> delta;
  const Real inv_ma = Real(1) / a.m, inv_mb = Real(1) / b.m;
  for (int d = 0; d < D; ++d) delta[d] = b.mx[d] * inv_mb - a.mx[d] * inv_ma;
  G.delta_n = dot<D, Real>(delta, G.n);
  const VecD<D, Real> opening_t = add_scaled<D, Real>(delta, G.n, -G.delta_n);  // (P-15)
  G.delta_t = std::sqrt(
      resolved_opening_squared(dot<D, Real>(opening_t, opening_t), dot<D, Real>(delta, delta)));
  G.t = tangent_or_perpendicular<D, Real>(opening_t, G.delta_t, G.n);
  G.h_perp = mmpm::h_perp<D, Real>(G.n, h);
  G.valid = true;
  return G;
}

// One interface direction (§3.2, §4.4, §4.5).
template <class Real>
struct DirectionOutcome {
  Real force = 0;
  Real energy = 0;
  bool stick = false;
  bool limited = false;
};

template <class Real>
DirectionOutcome<Real> interface_direction(const PairParams<Real>& pp, bool perfect, Real stiffness,
                                           Real traction, Real energy_density, Real area,
                                           Real m_red, Real dt, Real limit_dt, Real separation,
                                           Real momentum_change, Real force_diff) {
  DirectionOutcome<Real> o;
  if (perfect) {  // always stick, zero energy, no force limit computation
    o.stick = true;
    return o;
  }
  if (pp.integration == Integration::exact) {
    const SpringStep<Real> s =
        exact_spring_force(stiffness * area, m_red, dt, separation, force_diff, limit_dt);
    if (s.stick) {
      o.stick = o.limited = true;
      return o;
    }
    o.force = s.force;
    o.energy = energy_density * area;
    return o;
  }
  const Real force = traction * area;
  if (pp.force_limit &&
      exceeds_force_limit(
          force, force_limit_component(m_red, limit_dt, separation, momentum_change, force_diff)) &&
      spring_beyond_one_step(force, m_red, limit_dt, separation)) {
    o.stick = o.limited = true;
    return o;
  }
  o.force = force;
  o.energy = energy_density * area;
  return o;
}

// Volume screening (§3), a rigid partner's presence (kRigidPresentFraction) or
// both deformable partners' (kContactPresentFraction, partner_absent: after the
// geometry, which stick's test reads the normal of), then the pair geometry;
// G.valid is false when the pair is skipped.
template <int D, class Real>
PairGeometry<D, Real> screened_geometry(const MaterialSide<D, Real>& a,
                                        const MaterialSide<D, Real>& b, bool b_is_rigid,
                                        const PairParams<Real>& pp, Real sign,
                                        const std::array<Real, 3>& node_position,
                                        const std::array<Real, 3>& h) {
  if (a.vol + b.vol < pp.omega_min) return PairGeometry<D, Real>{};
  if (b_is_rigid && b.vol < pp.rigid_min_volume) return PairGeometry<D, Real>{};
  const bool sliver = a.vol < pp.presence_min_volume || b.vol < pp.presence_min_volume;
  const PairGeometry<D, Real> G =
      pair_geometry<D, Real>(a, b, b_is_rigid, pp, sign, node_position, h);
  if (!b_is_rigid && sliver && G.valid &&
      partner_absent<D, Real>(a.vol, b.vol, a.g, b.g, G.n, pp.presence_min_volume,
                              pp.presence_thin_along_normal))
    return PairGeometry<D, Real>{};
  return G;
}

// held_already: hold the pair whatever the approach; stuck_already (with it): a
// Coulomb pair sticks (USF's pass A, kStuckInPassB).
template <int D, class Real>
InteractionResult<D, Real> contact_result(const PairGeometry<D, Real>& G,
                                          const PairParams<Real>& pp, Real corrected_dn,
                                          bool held_already = false, bool stuck_already = false) {
  InteractionResult<D, Real> r;
  r.evaluated = true;
  r.held = held_already || in_contact(dot<D, Real>(G.dp, G.n), corrected_dn);
  if (!r.held) return r;
  const Law law = held_already && stuck_already && pp.law == Law::friction ? Law::stick : pp.law;
  r.momentum_change = contact_momentum_change<D, Real>(law, pp.friction, G.dp, G.n, &r.stuck);
  return r;
}

// Pass B's stick directions on its momenta: a one-sided normal sticks while the pair
// approaches, or (MUSL's strain pass) where pass B held it (kHeldInPassB).
template <int D, class Real>
InteractionResult<D, Real> interface_stick_result(const PairGeometry<D, Real>& G,
                                                  unsigned char stick_flags, bool strain_pass) {
  InteractionResult<D, Real> r;
  r.evaluated = true;
  const unsigned char stick = resolve_one_sided(
      stick_flags, held_before(stick_flags, strain_pass) || dot<D, Real>(G.dp, G.n) < 0);
  r.held = (stick & kOneSidedNormal) != 0 && (stick & kStickNormal) != 0;
  r.momentum_change = directional_stick_change<D, Real>(stick, G.dp, G.n);
  return r;
}

// Everything pass A does for material a against (virtual) b. held_last_step: the last
// step's pass B held this pair (USF only, kHeldInPassB): a contact or a one-sided normal
// holds it again whatever the sign of the approach; stuck_last_step (kStuckInPassB):
// a Coulomb pair sticks.
template <int D, class Real>
InteractionResult<D, Real> interact_pass_a(
    const MaterialSide<D, Real>& a, const MaterialSide<D, Real>& b, bool b_is_rigid,
    const PairParams<Real>& pp, Real sign, const std::array<Real, 3>& node_position,
    const std::array<Real, 3>& h, Real dt, Real limit_dt, Real thickness, bool use_force_difference,
    SavedGeometry<D, Real>* save, bool held_last_step = false, bool stuck_last_step = false) {
  InteractionResult<D, Real> r;
  const PairGeometry<D, Real> G =
      screened_geometry<D, Real>(a, b, b_is_rigid, pp, sign, node_position, h);
  if (!G.valid) {
    if (save) *save = SavedGeometry<D, Real>{};
    return r;
  }
  const Real dn =
      corrected_normal_separation(pp.separation, G.delta_n, G.h_perp, pp.contact_offset);
  if (save) *save = SavedGeometry<D, Real>{G.n, dn};
  if (pp.law != Law::interface)
    return contact_result<D, Real>(G, pp, dn, held_last_step, stuck_last_step);

  r.evaluated = true;
  const Traction<Real> tr = evaluate_traction(pp, dn, G.delta_t);
  Real area;
  if (pp.area == ContactArea::gradient) {
    area =
        gradient_contact_area<D, Real>(dot<D, Real>(a.g, G.n), dot<D, Real>(b.g, G.n), thickness);
  } else {
    ClosedDomains<Real> vol{a.vol, b.vol};
    if (pp.area == ContactArea::closed) {
      const bool known = pp.separation != Separation::position;  // mx holds displacements
      const Real half = Real(0.5) * dn;
      vol = close_opening(a.vol, b.vol, dot<D, Real>(a.g, G.n), dot<D, Real>(b.g, G.n),
                          known ? dot<D, Real>(a.mx, G.n) / a.m : -half,
                          known ? dot<D, Real>(b.mx, G.n) / b.m : half);
    }
    area = contact_area<D, Real>(vol.a, vol.b, G.h_perp, thickness);
  }
  const Real m_red = reduced_mass(a.m, b.m, b_is_rigid);
  VecD<D, Real> df{};
  // The exact spring always reads Δf_i where P2G has scattered the forces
  // (pass_needs; USF's pass A precedes them, and reads zeros): without it a
  // static interface's force is k s C(θ), softer by C(θ) ≈ 1 − θ²/12, and
  // the series bars at Dn = 1e4 read their interface energy 37 % high, a
  // shortened last step then kicking them (found by an outside review,
  // docs/interface_validation.md, Findings 12).
  if (use_force_difference || pp.integration == Integration::exact)
    df = force_difference<D, Real>(a.m, a.f, b.m, b.f, b_is_rigid);

  const Real dp_n = dot<D, Real>(G.dp, G.n);
  const DirectionOutcome<Real> on =
      interface_direction(pp, tr.perfect_n, tr.stiffness_n, tr.normal, tr.energy_n, area, m_red, dt,
                          limit_dt, dn, dp_n, dot<D, Real>(df, G.n));
  const DirectionOutcome<Real> ot =
      interface_direction(pp, tr.perfect_t, tr.stiffness_t, tr.tangential, tr.energy_t, area, m_red,
                          dt, limit_dt, G.delta_t, dot<D, Real>(G.dp, G.t), dot<D, Real>(df, G.t));
  r.stick = (on.stick ? kStickNormal : 0) | (ot.stick ? kStickTangential : 0);
  if (on.stick && ot.stick) r.stick |= kStickBoth;
  // A perfect compression branch is one-sided (kOneSidedNormal): released while the pair
  // separates, as contact is (docs/multimaterial.md §4.1); perfect, it has no force or
  // energy to drop. Pass B resolves the flag the same way on its momenta.
  if (pp.traction_law == TractionLaw::bilinear && dn < 0 && tr.perfect_n)
    r.stick = resolve_one_sided(r.stick | kOneSidedNormal, held_last_step || dp_n < 0);
  r.limited = int(on.limited) + int(ot.limited);
  r.momentum_change = directional_stick_change<D, Real>(r.stick, G.dp, G.n);
  for (int d = 0; d < D; ++d) r.force[d] = on.force * G.n[d] + ot.force * G.t[d];
  r.energy = double(on.energy) + double(ot.energy);
  return r;
}

// Pass B for material a against (virtual) b: contact on the updated momenta, or stick
// re-applied along the interface directions flagged in pass A. strain_pass: MUSL's
// repeat, which also holds the pairs pass B held (kHeldInPassB).
template <int D, class Real>
InteractionResult<D, Real> interact_pass_b(const MaterialSide<D, Real>& a,
                                           const MaterialSide<D, Real>& b, bool b_is_rigid,
                                           const PairParams<Real>& pp, Real sign,
                                           const std::array<Real, 3>& node_position,
                                           const std::array<Real, 3>& h, unsigned char stick_flags,
                                           bool strain_pass) {
  InteractionResult<D, Real> r;
  if (pp.law == Law::interface && stick_flags == 0) return r;
  const PairGeometry<D, Real> G =
      screened_geometry<D, Real>(a, b, b_is_rigid, pp, sign, node_position, h);
  if (!G.valid) return r;
  if (pp.law != Law::interface)
    r = contact_result<D, Real>(
        G, pp, corrected_normal_separation(pp.separation, G.delta_n, G.h_perp, pp.contact_offset),
        held_before(stick_flags, strain_pass), stuck_before(stick_flags, strain_pass));
  else
    r = interface_stick_result<D, Real>(G, stick_flags, strain_pass);
  r.normal = G.n;
  return r;
}

// Pass B from pass A's saved geometry: the same outcome as interact_pass_b
// (which recomputes the normal and separation from the same m, mx, Ω, g),
// with only Δp computed from the updated momenta.
template <int D, class Real>
InteractionResult<D, Real> interact_pass_b_saved(const MaterialSide<D, Real>& a,
                                                 const MaterialSide<D, Real>& b, bool b_is_rigid,
                                                 const PairParams<Real>& pp,
                                                 const SavedGeometry<D, Real>& saved,
                                                 unsigned char stick_flags, bool strain_pass) {
  InteractionResult<D, Real> r;
  if (pp.law == Law::interface && stick_flags == 0) return r;
  if (dot<D, Real>(saved.n, saved.n) == Real(0)) return r;
  PairGeometry<D, Real> G;
  G.n = saved.n;
  G.dp = momentum_change_to_center_of_mass<D, Real>(a.m, a.p, b.m, b.p, b_is_rigid);
  if (pp.law != Law::interface)
    r = contact_result<D, Real>(G, pp, saved.dn, held_before(stick_flags, strain_pass),
                                stuck_before(stick_flags, strain_pass));
  else
    r = interface_stick_result<D, Real>(G, stick_flags, strain_pass);
  r.normal = G.n;
  return r;
}

// The fields present at a node, gathered into contiguous local arrays.
template <int D, class Real>
struct NodeFields {
  int count = 0;
  int field[kMaxFields];
  MaterialSide<D, Real> side[kMaxFields];
};

// What the pairs of a configuration read besides m, p, mx, vol.
struct PassNeeds {
  bool geometry = true;   // mx (pass B from saved geometry reads only m, Ω, p)
  bool gradient = false;  // some pair uses the mvg / avg / rigid normal, or the closed area
  bool position = false;  // some pair uses the radial normal
  bool force = false;     // Δf_i (pass A with cfg.use_force_difference or an exact spring)
};

template <int D, class Real>
PassNeeds pass_needs(const MMConfig<D, Real>& cfg, bool pass_a) {
  PassNeeds needs;
  needs.force = pass_a && cfg.use_force_difference;
  const int F = cfg.fields;
  for (int k = 0; k < F * F; ++k) {
    if (cfg.pair[k] < 0) continue;
    const NormalMethod method = cfg.params[cfg.pair[k]].normal_method;
    needs.position |= method == NormalMethod::radial;
    needs.gradient |= reads_domain_gradient(cfg.params[cfg.pair[k]]);
    needs.force |= pass_a && cfg.params[cfg.pair[k]].integration == Integration::exact &&
                   cfg.params[cfg.pair[k]].law == Law::interface;
  }
  return needs;
}

template <int D, class Real>
void gather_node(const GridView<D, Real>& grid, std::size_t node, Real mass_threshold,
                 const PassNeeds& needs, NodeFields<D, Real>& out) {
  out.count = 0;
  for (int j = 0; j < grid.fields; ++j) {
    const std::size_t at = grid.at(j, node);
    const Real m = grid.m[at];
    if (!(m > mass_threshold)) continue;
    MaterialSide<D, Real>& s = out.side[out.count];
    out.field[out.count++] = j;
    s.m = m;
    s.vol = grid.vol[at];
    for (int d = 0; d < D; ++d) {
      s.p[d] = grid.p[d][at];
      s.mx[d] = needs.geometry ? grid.mx[d][at] : Real(0);
      s.g[d] = needs.gradient ? grid.g[d][at] : Real(0);
      s.f[d] = needs.force && grid.f[d] ? grid.f[d][at] : Real(0);
    }
  }
}

template <int D, class Real>
inline void add_in_place(MaterialSide<D, Real>& lump, const MaterialSide<D, Real>& s) {
  lump.m += s.m;
  lump.vol += s.vol;
  for (int d = 0; d < D; ++d) {
    lump.p[d] += s.p[d];
    lump.mx[d] += s.mx[d];
    lump.g[d] += s.g[d];
    lump.f[d] += s.f[d];
  }
}

// Statistics of one chunk of the node list.
struct ChunkStats {
  double energy = 0;
  long nodes_2 = 0, nodes_3plus = 0, limited = 0;
  double* reaction = nullptr;  // F × 3
};

template <int D, class Real>
inline void add_reaction(ChunkStats& cs, int rigid_field, const VecD<D, Real>& momentum_change,
                         const VecD<D, Real>& force, Real inv_dt) {
  for (int d = 0; d < D; ++d)
    cs.reaction[3 * rigid_field + d] -=
        double(momentum_change[d]) * double(inv_dt) + double(force[d]);
}

// The momentum change that counts toward a rigid body's reaction. Particles
// take their FLIP velocity increment from the momenta after pass A, so pass
// A's contact changes never reach them; the reaction the deformable body
// feels is pass B's change (plus the interface forces, counted in pass A).
template <int D, class Real, bool kPassA>
inline VecD<D, Real> reaction_change(const InteractionResult<D, Real>& r) {
  if constexpr (kPassA) return VecD<D, Real>{};
  return r.momentum_change;
}

// Pass B's record in the stick flags of which pairs it held (kHeldInPassB) and
// which of those stuck (kStuckInPassB).
inline void record_held(unsigned char* flags_out, std::size_t slot, bool held, bool stuck) {
  if (!flags_out) return;
  const unsigned char bits =
      (unsigned char)((held ? kHeldInPassB : 0) | (held && stuck ? kStuckInPassB : 0));
  flags_out[slot] = (unsigned char)((flags_out[slot] & ~kPassBRecord) | bits);
}

// One node of the list, pass A (kPassA) or pass B. Pass B records in flags_out
// (when given, the array flags_in points to) which pairs it held; strain_pass
// (MUSL's repeat of pass B) holds them again.
template <int D, class Real, bool kPassA>
void process_node(GridView<D, Real>& grid, const MMConfig<D, Real>& cfg, std::size_t k,
                  std::size_t node, const PassNeeds& needs, NodeFields<D, Real>& nf,
                  const unsigned char* flags_in, unsigned char* flags_out,
                  const SavedGeometry<D, Real>* geometry_in, SavedGeometry<D, Real>* geometry_out,
                  bool strain_pass, ChunkStats& cs) {
  const int F = cfg.fields;
  gather_node<D, Real>(grid, node, cfg.mass_threshold, needs, nf);
  const int K = nf.count;
  if (K < 2) return;
  if constexpr (kPassA) (K == 2 ? cs.nodes_2 : cs.nodes_3plus) += 1;

  const std::array<Real, 3> x_node =
      needs.position ? grid.position(node) : std::array<Real, 3>{0, 0, 0};
  const Real inv_dt = Real(1) / cfg.dt;
  auto is_rigid = [&](int field) { return cfg.rigid != nullptr && cfg.rigid[field] != 0; };
  auto params_of = [&](int fa, int fb) -> const PairParams<Real>* {
    const int idx = cfg.pair[fa * F + fb];
    if (idx < 0 || cfg.params[idx].law == Law::separate) return nullptr;
    return &cfg.params[idx];
  };
  auto interact = [&](const MaterialSide<D, Real>& a, const MaterialSide<D, Real>& b, bool b_rigid,
                      const PairParams<Real>& pp, int field_a) {
    const Real sign = field_a == pp.first_field ? Real(1) : Real(-1);
    const std::size_t slot = k * std::size_t(F) + std::size_t(field_a);
    if constexpr (kPassA) {
      const unsigned char last = flags_in != nullptr ? flags_in[slot] : 0;
      return interact_pass_a<D, Real>(a, b, b_rigid, pp, sign, x_node, grid.h, cfg.dt,
                                      cfg.stick_dt(), cfg.thickness, cfg.use_force_difference,
                                      geometry_out ? &geometry_out[slot] : nullptr,
                                      (last & kHeldInPassB) != 0, (last & kStuckInPassB) != 0);
    } else {
      if (geometry_in)
        return interact_pass_b_saved<D, Real>(a, b, b_rigid, pp, geometry_in[slot], flags_in[slot],
                                              strain_pass);
      return interact_pass_b<D, Real>(a, b, b_rigid, pp, sign, x_node, grid.h, flags_in[slot],
                                      strain_pass);
    }
  };
  auto apply = [&](int field, const VecD<D, Real>& dp, const VecD<D, Real>& force, Real s) {
    const std::size_t at = grid.at(field, node);
    for (int d = 0; d < D; ++d) grid.p[d][at] += s * dp[d];
    if constexpr (kPassA) {
      if (grid.fi[0])
        for (int d = 0; d < D; ++d) grid.fi[d][at] += s * force[d];
    }
  };

  if (K == 2) {  // §6: compute once for a, apply the negatives to b
    int ia = 0, ib = 1;
    const PairParams<Real>* pp = params_of(nf.field[0], nf.field[1]);
    if (!pp) return;
    const bool rigid0 = is_rigid(nf.field[0]), rigid1 = is_rigid(nf.field[1]);
    if (rigid0 && rigid1) return;
    if (rigid0) std::swap(ia, ib);  // a is always the deformable one (§7)
    const int fa = nf.field[ia], fb = nf.field[ib];
    const bool b_rigid = rigid0 || rigid1;
    const InteractionResult<D, Real> r = interact(nf.side[ia], nf.side[ib], b_rigid, *pp, fa);
    apply(fa, r.momentum_change, r.force, Real(1));
    if (b_rigid)
      add_reaction<D, Real>(cs, fb, reaction_change<D, Real, kPassA>(r), r.force, inv_dt);
    else
      apply(fb, r.momentum_change, r.force, Real(-1));
    if constexpr (kPassA) {
      cs.energy += r.energy;
      cs.limited += r.limited;
      flags_out[k * std::size_t(F) + std::size_t(fa)] = r.stick;
    } else {
      const std::size_t slot = k * std::size_t(F) + std::size_t(fa);
      record_held(flags_out, slot, r.held, r.stuck);
      if (cfg.light_mass) {  // USL: a light field's left-out force where pass B held the pair
        const VecD<D, Real> taken = exchange_left_out<D, Real>(
            grid, cfg.light_mass, cfg.light_dvel, cfg.light_gravity, cfg.dt, node, fa, fb, b_rigid,
            pass_b_hold(pp->law, pp->friction, flags_in[slot], r.held, r.stuck), r.normal,
            cfg.light_fixed ? cfg.light_fixed[node] : 0);
        if (b_rigid) add_reaction<D, Real>(cs, fb, taken, VecD<D, Real>{}, inv_dt);
      }
    }
    return;
  }

  // §6, three or more materials: each deformable a against the lump of its partners
  // (or against its rigid partner), all computed from the gathered snapshot, applied after.
  VecD<D, Real> change[kMaxFields], force[kMaxFields];
  // Pass B under USL: how each field was held against its rigid partner, for
  // the left-out exchange once the changes are applied (a sliding pair's
  // friction reads the updated momenta).
  PassBHold<Real> hold[kMaxFields];
  VecD<D, Real> held_normal[kMaxFields];
  int rigid_partner[kMaxFields];
  bool lumped_energy_counted = false;
  for (int ia = 0; ia < K; ++ia) {
    rigid_partner[ia] = -1;
    change[ia] = VecD<D, Real>{};
    force[ia] = VecD<D, Real>{};
    const int fa = nf.field[ia];
    if (is_rigid(fa)) continue;
    MaterialSide<D, Real> lump;
    int largest_rigid = -1, largest_other = -1;
    for (int ib = 0; ib < K; ++ib) {
      if (ib == ia || !params_of(fa, nf.field[ib])) continue;
      if (is_rigid(nf.field[ib])) {
        if (largest_rigid < 0 || nf.side[ib].vol > nf.side[largest_rigid].vol) largest_rigid = ib;
      } else {
        add_in_place<D, Real>(lump, nf.side[ib]);
        if (largest_other < 0 || nf.side[ib].vol > nf.side[largest_other].vol) largest_other = ib;
      }
    }
    const bool b_rigid = largest_rigid >= 0;
    const int partner = b_rigid ? largest_rigid : largest_other;
    if (partner < 0) continue;
    const PairParams<Real>& pp = *params_of(fa, nf.field[partner]);
    const InteractionResult<D, Real> r =
        interact(nf.side[ia], b_rigid ? nf.side[partner] : lump, b_rigid, pp, fa);
    change[ia] = r.momentum_change;
    force[ia] = r.force;
    if (b_rigid)
      add_reaction<D, Real>(cs, nf.field[partner], reaction_change<D, Real, kPassA>(r), r.force,
                            inv_dt);
    if constexpr (kPassA) {
      // Energy once per node among lumped interactions, once per rigid interaction (§6).
      if (b_rigid) {
        cs.energy += r.energy;
      } else if (pp.law == Law::interface && r.evaluated && !lumped_energy_counted) {
        cs.energy += r.energy;
        lumped_energy_counted = true;
      }
      cs.limited += r.limited;
      flags_out[k * std::size_t(F) + std::size_t(fa)] = r.stick;
    } else {
      const std::size_t slot = k * std::size_t(F) + std::size_t(fa);
      record_held(flags_out, slot, r.held, r.stuck);
      // USL's left-out force against a rigid partner, below. Against a lump
      // of deformable partners it is left in dvel: the lump's fields do not
      // share one stuck velocity.
      if (cfg.light_mass && b_rigid) {
        rigid_partner[ia] = nf.field[partner];
        hold[ia] = pass_b_hold(pp.law, pp.friction, flags_in[slot], r.held, r.stuck);
        held_normal[ia] = r.normal;
      }
    }
  }
  for (int ia = 0; ia < K; ++ia) apply(nf.field[ia], change[ia], force[ia], Real(1));
  if constexpr (!kPassA) {
    for (int ia = 0; ia < K; ++ia) {
      if (rigid_partner[ia] < 0) continue;
      const VecD<D, Real> taken =
          exchange_left_out<D, Real>(grid, cfg.light_mass, cfg.light_dvel, cfg.light_gravity,
                                     cfg.dt, node, nf.field[ia], rigid_partner[ia], true, hold[ia],
                                     held_normal[ia], cfg.light_fixed ? cfg.light_fixed[node] : 0);
      add_reaction<D, Real>(cs, rigid_partner[ia], taken, VecD<D, Real>{}, inv_dt);
    }
  }
}

// Which entries of [begin, end) go into the batch B: two-material nodes of
// the first pair met that batchable_pair takes, both fields deformable.
// lane_of[k − begin] is the entry's lane, or −1 for the per-node path.
template <int D, class Real, bool kPassA>
void sort_chunk(const GridView<D, Real>& grid, const MMConfig<D, Real>& cfg,
                const std::vector<std::uint32_t>& list, std::size_t begin, std::size_t end,
                PairBatch<D, Real>& B, signed char* lane_of) {
  const int F = cfg.fields;
  auto is_rigid = [&](int field) { return cfg.rigid != nullptr && cfg.rigid[field] != 0; };
  B.count = 0;
  for (std::size_t k = begin; k < end; ++k) {
    lane_of[k - begin] = -1;
    const std::size_t node = list[k];
    int K = 0, fa = -1, fb = -1;
    for (int j = 0; j < F; ++j) {
      if (!(grid.m[grid.at(j, node)] > cfg.mass_threshold)) continue;
      (K == 0 ? fa : fb) = j;
      if (++K > 2) break;
    }
    if (K != 2 || is_rigid(fa) || is_rigid(fb)) continue;
    const int idx = cfg.pair[fa * F + fb];
    if (idx < 0 || cfg.params[idx].law == Law::separate) continue;
    if (!batchable_pair(cfg.params[idx], kPassA)) continue;
    if (B.count == 0) {
      B.field_a = fa;
      B.field_b = fb;
      B.params = &cfg.params[idx];
    } else if (fa != B.field_a || fb != B.field_b) {
      continue;
    }
    lane_of[k - begin] = static_cast<signed char>(B.count);
    B.node[B.count++] = std::uint32_t(node);
  }
}

// Pass A's batch of one chunk, as pass B takes it (SavedBatch).
template <int D, class Real>
void save_batch(const PairBatch<D, Real>& B, const signed char* lane_of, int entries,
                SavedBatch<D, Real>& S) {
  S.count = B.count;
  if (B.count == 0) return;
  S.field_a = B.field_a;
  S.field_b = B.field_b;
  S.params = B.params;
  const std::size_t rows = std::size_t(B.count) * sizeof(Real);
  std::memcpy(S.lane_of, lane_of, std::size_t(entries));
  std::memcpy(S.node, B.node, std::size_t(B.count) * sizeof(std::uint32_t));
  for (int s = 0; s < 2; ++s) std::memcpy(S.m[s], B.m[s], rows);
  for (int d = 0; d < D; ++d) std::memcpy(S.n[d], B.n[d], rows);
  std::memcpy(S.dn, B.dn, rows);
  std::memcpy(S.stick, B.stick, std::size_t(B.count));
}

// save_batch backwards: pass A's batch of the chunk into B and lane_of, for
// pass B (which then gathers only the momenta).
template <int D, class Real>
void restore_batch(const SavedBatch<D, Real>& S, int entries, PairBatch<D, Real>& B,
                   signed char* lane_of) {
  B.count = S.count;
  B.field_a = S.field_a;
  B.field_b = S.field_b;
  B.params = S.params;
  const std::size_t rows = std::size_t(S.count) * sizeof(Real);
  std::memcpy(lane_of, S.lane_of, std::size_t(entries));
  std::memcpy(B.node, S.node, std::size_t(S.count) * sizeof(std::uint32_t));
  for (int s = 0; s < 2; ++s) std::memcpy(B.m[s], S.m[s], rows);
  for (int d = 0; d < D; ++d) std::memcpy(B.n[d], S.n[d], rows);
  std::memcpy(B.dn, S.dn, rows);
  std::memcpy(B.stick, S.stick, std::size_t(S.count));
}

// The list entries [begin, end) (at most one batch): two-material nodes of
// the first batchable pair met go through a PairBatch, every other node
// through process_node. The results are applied and the statistics added in
// list order, so the sums are those of the per-node path.
//
// Pass A leaves its batch in *saved_out (when given) and the geometry of
// its per-node entries in geometry_out. Pass B with *saved_in takes pass
// A's lanes, masses, normals, separations and stick flags from it and
// gathers only the momenta; where pass A batched nothing in the chunk
// (every node by the per-node path, e.g. a pair with the exact
// integration), it sorts the chunk itself with geometry_in.
template <int D, class Real, bool kPassA>
void process_chunk(GridView<D, Real>& grid, const MMConfig<D, Real>& cfg,
                   const std::vector<std::uint32_t>& list, std::size_t begin, std::size_t end,
                   const PassNeeds& needs, NodeFields<D, Real>& nf, PairBatch<D, Real>& B,
                   const unsigned char* flags_in, unsigned char* flags_out,
                   const SavedGeometry<D, Real>* geometry_in, SavedGeometry<D, Real>* geometry_out,
                   const SavedBatch<D, Real>* saved_in, SavedBatch<D, Real>* saved_out,
                   bool strain_pass, ChunkStats& cs) {
  auto per_node = [&](std::size_t k) {
    process_node<D, Real, kPassA>(grid, cfg, k, list[k], needs, nf, flags_in, flags_out,
                                  geometry_in, geometry_out, strain_pass, cs);
  };
  if (!cfg.batch_pairs || (!kPassA && !geometry_in)) {
    for (std::size_t k = begin; k < end; ++k) per_node(k);
    return;
  }
  assert(end - begin <= std::size_t(PairBatch<D, Real>::kLanes));
  const int entries = int(end - begin);
  signed char lane_of[PairBatch<D, Real>::kLanes];
  if (!kPassA && saved_in && saved_in->count > 0) {
    restore_batch<D, Real>(*saved_in, entries, B, lane_of);
    if (strain_pass)  // pass B's kHeldInPassB bits, which the saved batch has not
      for (std::size_t k = begin; k < end; ++k)
        if (const int i = lane_of[k - begin]; i >= 0)
          B.stick[i] = flags_in[k * std::size_t(cfg.fields) + std::size_t(B.field_a)];
    BatchNeeds bn;
    bn.mass = bn.vol = bn.geometry = false;
    gather_batch<D, Real>(grid, bn, B);
    pass_b_batch<D, Real>(B, strain_pass);
  } else {
    sort_chunk<D, Real, kPassA>(grid, cfg, list, begin, end, B, lane_of);
    if (B.count > 0) {
      BatchNeeds bn;
      if constexpr (kPassA) {
        const NormalMethod method = B.params->normal_method;
        bn.gradient = reads_domain_gradient(*B.params);
        bn.position = method == NormalMethod::radial;
        bn.force = cfg.use_force_difference;
        gather_batch<D, Real>(grid, bn, B);
        // USF's pairs the last step's pass B held (1) and held stuck (2)
        // (multimaterial_pass_a).
        for (std::size_t k = begin; k < end; ++k)
          if (const int i = lane_of[k - begin]; i >= 0) {
            const unsigned char last =
                flags_in != nullptr ? flags_in[k * std::size_t(cfg.fields) + std::size_t(B.field_a)]
                                    : 0;
            B.held[i] = (last & kHeldInPassB) == 0    ? Real(0)
                        : (last & kStuckInPassB) == 0 ? Real(1)
                                                      : Real(2);
          }
        // The lanes read dt in the force limit only (explicit integration).
        pass_a_batch<D, Real>(B, grid.h, cfg.stick_dt(), cfg.thickness, cfg.use_force_difference);
      } else {
        bn.vol = bn.geometry = false;
        gather_batch<D, Real>(grid, bn, B);
        for (std::size_t k = begin; k < end; ++k) {
          const int i = lane_of[k - begin];
          if (i < 0) continue;
          const std::size_t slot = k * std::size_t(cfg.fields) + std::size_t(B.field_a);
          for (int d = 0; d < D; ++d) B.n[d][i] = geometry_in[slot].n[d];
          B.dn[i] = geometry_in[slot].dn;
          B.stick[i] = flags_in[slot];
        }
        pass_b_batch<D, Real>(B, strain_pass);
      }
    }
    if constexpr (kPassA) {
      if (saved_out) save_batch<D, Real>(B, lane_of, entries, *saved_out);
    }
  }

  const std::size_t at_a = B.count > 0 ? grid.at(B.field_a, 0) : 0;
  const std::size_t at_b = B.count > 0 ? grid.at(B.field_b, 0) : 0;
  const bool with_force = kPassA && grid.fi[0] != nullptr;
  for (std::size_t k = begin; k < end; ++k) {
    const int i = lane_of[k - begin];
    if (i < 0) {
      per_node(k);
      continue;
    }
    // As process_node applies a K = 2 result: a gets it, b its negative (§6).
    const std::size_t node = list[k];
    for (int d = 0; d < D; ++d) {
      grid.p[d][at_a + node] += B.change[d][i];
      grid.p[d][at_b + node] += -B.change[d][i];
    }
    if constexpr (!kPassA) {
      const std::size_t slot = k * std::size_t(cfg.fields) + std::size_t(B.field_a);
      const bool held = B.held[i] != Real(0), stuck = B.stuck[i] != Real(0);
      record_held(flags_out, slot, held, stuck);
      if (cfg.light_mass) {  // as process_node
        VecD<D, Real> n;
        for (int d = 0; d < D; ++d) n[d] = B.n[d][i];
        exchange_left_out<D, Real>(
            grid, cfg.light_mass, cfg.light_dvel, cfg.light_gravity, cfg.dt, node, B.field_a,
            B.field_b, false,
            pass_b_hold(B.params->law, B.params->friction, B.stick[i], held, stuck), n,
            cfg.light_fixed ? cfg.light_fixed[node] : 0);
      }
    }
    if constexpr (kPassA) {
      if (with_force)
        for (int d = 0; d < D; ++d) {
          grid.fi[d][at_a + node] += B.force[d][i];
          grid.fi[d][at_b + node] += -B.force[d][i];
        }
      cs.nodes_2 += 1;
      cs.energy += B.energy[i];
      cs.limited += B.limited[i];
      const std::size_t slot = k * std::size_t(cfg.fields) + std::size_t(B.field_a);
      flags_out[slot] = B.stick[i];
      if (geometry_out && !saved_out) {  // else pass B reads the lane from the batch
        for (int d = 0; d < D; ++d) geometry_out[slot].n[d] = B.n[d][i];
        geometry_out[slot].dn = B.dn[i];
      }
    }
  }
}

// A run of chunks [next, last) of the list; threads take them one at a time
// by advancing `next`.
struct alignas(64) ChunkCursor {
  std::atomic<std::size_t> next{0};
  std::size_t last = 0;
};

template <int D, class Real, bool kPassA>
void run_pass(GridView<D, Real>& grid, const std::vector<std::uint32_t>& list,
              const MMConfig<D, Real>& cfg, MMStats& stats, const unsigned char* flags_in,
              unsigned char* flags_out, const PassAGeometry<D, Real>* saved_in,
              PassAGeometry<D, Real>* saved_out, const NodeOwnership& own,
              bool strain_pass = false) {
  assert(validate_multimaterial(grid, cfg) == nullptr);
  const int F = cfg.fields;
  if (stats.rigid_reaction.size() != std::size_t(F))
    stats.rigid_reaction.resize(std::size_t(F), std::array<double, 3>{0, 0, 0});
  const std::size_t n = list.size();
  if (n == 0) return;
  PassNeeds needs = pass_needs(cfg, kPassA);
  if (saved_in) needs.geometry = needs.gradient = needs.position = false;

  // Fixed: the reduction order never depends on threads. One PairBatch.
  constexpr std::size_t kChunk = PairBatch<D, Real>::kLanes;
  const std::size_t chunks = (n + kChunk - 1) / kChunk;
  const SavedGeometry<D, Real>* geometry_in = saved_in ? saved_in->nodes.data() : nullptr;
  SavedGeometry<D, Real>* geometry_out = saved_out ? saved_out->nodes.data() : nullptr;
  const SavedBatch<D, Real>* batches_in = saved_in ? saved_in->batches.data() : nullptr;
  SavedBatch<D, Real>* batches_out = saved_out ? saved_out->batches.data() : nullptr;
  const std::size_t reaction_stride = 3 * std::size_t(F);
  std::vector<ChunkStats> partial(chunks);
  std::vector<double> reactions(chunks * reaction_stride, 0.0);
  for (std::size_t c = 0; c < chunks; ++c) partial[c].reaction = &reactions[c * reaction_stride];
  // A chunk belongs to the thread that owns its first node
  // (kernels/node_ownership.hpp): P2G wrote that node's fields from this
  // thread's tiles, so they are in its cache. Handed out dynamically, about
  // half of the chunks' grid lines crossed between the cores. A thread done
  // with its own chunks takes the others' next ones: the multimaterial
  // nodes may lie mostly in one thread's part (one straight interface).
  // The cursors are set before the team starts, for the team the region
  // will have, so the region has no barrier before its chunks (it had an
  // `omp single`: passes A and B each took 0.5-1.5 us more per step in the
  // two-layer scene on two threads, docs/performance.md "The multimaterial
  // pass on two threads from 128 nodes"). A team of another size still
  // takes every chunk: each thread walks all the cursors.
  const bool parallel = n >= kParallelNodes;
  const std::size_t planned = parallel ? std::size_t(std::max(1, omp_get_max_threads())) : 1;
  std::vector<ChunkCursor> cursor(planned);
  {
    auto first_chunk = [&](std::size_t i) {
      if (i == planned) return chunks;
      const std::size_t node = own.range(grid.nodes, planned, i).first;
      const auto k = std::size_t(std::lower_bound(list.begin(), list.end(), node) - list.begin());
      return (k + kChunk - 1) / kChunk;
    };
    for (std::size_t i = 0; i < planned; ++i) {
      cursor[i].next.store(first_chunk(i), std::memory_order_relaxed);
      cursor[i].last = first_chunk(i + 1);
    }
  }

  static_assert(kParallelNodes >= 2 * kChunk, "a team needs two chunks to share");
  team_run(parallel, [&] {
    const std::size_t me = std::size_t(team_rank());
    NodeFields<D, Real> nf;
    const auto batch = std::make_unique<PairBatch<D, Real>>();
    // A chunk's statistics are summed in the thread's own copy and stored
    // once per chunk: neighbouring chunks' entries share cache lines, and
    // updating them node by node from two threads was slower than one thread.
    std::vector<double> reaction(reaction_stride);
    for (std::size_t step = 0; step < planned; ++step) {
      ChunkCursor& from = cursor[(me + step) % planned];
      for (;;) {
        const std::size_t c = from.next.fetch_add(1, std::memory_order_relaxed);
        if (c >= from.last) break;
        ChunkStats local;
        std::fill(reaction.begin(), reaction.end(), 0.0);
        local.reaction = reaction.data();
        const std::size_t end = std::min(n, (c + 1) * kChunk);
        process_chunk<D, Real, kPassA>(grid, cfg, list, c * kChunk, end, needs, nf, *batch,
                                       flags_in, flags_out, geometry_in, geometry_out,
                                       batches_in ? &batches_in[c] : nullptr,
                                       batches_out ? &batches_out[c] : nullptr, strain_pass, local);
        local.reaction = partial[c].reaction;
        std::copy(reaction.begin(), reaction.end(), local.reaction);
        partial[c] = local;
      }
    }
  });

  for (std::size_t c = 0; c < chunks; ++c) {  // serial, in chunk order
    stats.interface_energy += partial[c].energy;
    stats.nodes_2 += partial[c].nodes_2;
    stats.nodes_3plus += partial[c].nodes_3plus;
    stats.force_limited += partial[c].limited;
    for (int j = 0; j < F; ++j)
      for (int d = 0; d < 3; ++d) stats.rigid_reaction[j][d] += partial[c].reaction[3 * j + d];
  }
}

}  // namespace mm_detail

// Pass A (ALGORITHM §2 step 3), after P2G filled m, p, mx, vol, g (and f if
// cfg.use_force_difference). The caller zeroes grid.fi beforehand. stick_flags is resized
// to list.size() * F and written: entry [k*F + a] holds the kStick* bits of the
// interaction computed for field a at node list[k]. `geometry`, when given, receives
// each interaction's normal and corrected separation for pass B (PassAGeometry).
// `own`: which thread starts on which nodes (kernels/node_ownership.hpp).
// held_last_step (USF), when given: per entry [k*F + a] as stick_flags, the
// kHeldInPassB and kStuckInPassB bits of the last step's pass B at node list[k];
// those pairs are held, and a Coulomb pair held stuck sticks.
template <int D, class Real>
void multimaterial_pass_a(GridView<D, Real>& grid, const std::vector<std::uint32_t>& list,
                          const MMConfig<D, Real>& cfg, MMStats& stats,
                          std::vector<unsigned char>& stick_flags, const NodeOwnership& own = {},
                          PassAGeometry<D, Real>* geometry = nullptr,
                          const unsigned char* held_last_step = nullptr) {
  stick_flags.assign(list.size() * std::size_t(cfg.fields), 0);
  if (geometry) {
    constexpr std::size_t kChunk = mm_detail::PairBatch<D, Real>::kLanes;
    geometry->nodes.resize(list.size() * std::size_t(cfg.fields));
    geometry->batches.resize((list.size() + kChunk - 1) / kChunk);
  }
  mm_detail::run_pass<D, Real, true>(grid, list, cfg, stats, held_last_step, stick_flags.data(),
                                     nullptr, geometry, own);
}

// Which momenta pass B works on: the updated ones (the particles take the result), or
// MUSL's re-extrapolation of the updated particles (only the strain reads the result).
enum class PassB : unsigned char { after_update, strain };

// Pass B (ALGORITHM §2 step 5), after the grid momentum update, with the same list, the
// same m, mx, vol, g and the stick_flags of pass A. No interface force, no energy.
// With pass A's `geometry` it reads only m, vol and p at the nodes (only p at
// pass A's batched nodes) and takes the normal and separation from pass A;
// without, it recomputes them (the same values).
// PassB::after_update marks in stick_flags the pairs it held (kHeldInPassB);
// PassB::strain, MUSL's repeat on the re-extrapolated momenta, holds those again.
template <int D, class Real>
void multimaterial_pass_b(GridView<D, Real>& grid, const std::vector<std::uint32_t>& list,
                          const MMConfig<D, Real>& cfg, std::vector<unsigned char>& stick_flags,
                          MMStats& stats, const NodeOwnership& own = {},
                          const PassAGeometry<D, Real>* geometry = nullptr,
                          PassB which = PassB::after_update) {
  assert(stick_flags.size() == list.size() * std::size_t(cfg.fields));
  assert(!geometry || geometry->nodes.size() == stick_flags.size());
  const bool strain = which == PassB::strain;
  mm_detail::run_pass<D, Real, false>(grid, list, cfg, stats, stick_flags.data(),
                                      strain ? nullptr : stick_flags.data(), geometry, nullptr, own,
                                      strain);
}

}  // namespace mmpm
