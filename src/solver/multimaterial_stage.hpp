// The multimaterial stage of a step: builds the pass configuration from the
// scene once, then per step finds the multimaterial nodes and runs passes
// A and B (ALGORITHM §2 steps 3 and 5). Absent entirely (no list, no
// arrays, no work) when the scene has one material field.
#pragma once

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <utility>
#include <vector>

#include "io/checkpoint.hpp"
#include "kernels/multimaterial.hpp"
#include "scene/error.hpp"
#include "solver/field_plan.hpp"
#include "solver/simulation.hpp"

namespace mmpm {

template <int D, class Real>
class MultimaterialStage {
 public:
  void setup(const Scene& scene, const FieldPlan& plan, const GridView<D, Real>& grid,
             Real min_particle_mass, double dt) {
    enabled_ = plan.multimaterial;
    fields_ = plan.fields;
    stats_.reset(plan.fields);
    if (!enabled_) return;
    pair_ = plan.pair;
    rigid_ = plan.rigid;
    double cell = 1;
    for (int d = 0; d < D; ++d) cell *= double(grid.h[d]);  // area in 2D: grid.vol holds areas
    for (const InteractionSpec& it : plan.laws) {
      PairParams<Real> pp;
      pp.law = it.law;
      pp.friction = Real(it.friction);
      pp.Dn = Real(it.Dn);
      pp.Dt = Real(it.Dt);
      pp.traction_law = it.traction_law;
      pp.Dn_compression = Real(it.Dn_compression);
      // "geometry" reads gradients the stepper has turned to the bodies'
      // faces (solver/geometry_normals.hpp) as "rigid" does: the rigid
      // partner's, or MVG's steeper of two deformable ones.
      pp.normal_method = it.normal == NormalMethod::geometry ? NormalMethod::rigid : it.normal;
      for (int d = 0; d < 3; ++d) {
        pp.normal_vector[d] = Real(it.normal_vector[d]);
        pp.radial_center[d] = Real(it.center[d]);
        pp.radial_axis[d] = Real(it.radial_axis[d]);
      }
      pp.first_field = -1;
      for (std::size_t m = 0; m < scene.materials.size(); ++m)
        if (scene.materials[m].name == it.materials[0]) pp.first_field = plan.field_of_material[m];
      pp.separation = it.separation;
      pp.contact_offset = Real(it.contact_offset);
      pp.omega_min = Real(it.min_volume * cell);
      // A rigid partner's presence (kRigidPresentFraction): for the cell-pair
      // stencils only. A B-spline reaches one cell beyond a flush surface
      // from the first step, so there the displacement method's premise
      // (both materials at the node from the start) holds; with the test the
      // platen read further from exact, not nearer (docs/contact_validation.md §11).
      const bool presence_tested =
          it.separation != Separation::position &&
          (scene.grid.shape == ShapeKind::linear || scene.grid.shape == ShapeKind::gimp);
      if (presence_tested) pp.rigid_min_volume = Real(kRigidPresentFraction * cell);
      // Both partners' presence (kContactPresentFraction), same stencils and
      // separations. Frictionless: either partner's sliver. Stick and Coulomb:
      // only a sliver thin along the normal facing a present partner (read off
      // the domain gradients, so not with a specified or radial normal); one
      // beside a free edge carries the corner's shear, and screened it made a
      // uGIMP block's free corner ring under a stiff platen. Not for an
      // interface, which is bonded at every node both materials share
      // (docs/contact_validation.md §15-17).
      const bool tangential_tie =
          (it.law == Law::stick || it.law == Law::friction) && reads_domain_gradient(pp);
      if (presence_tested && (it.law == Law::frictionless || tangential_tie))
        pp.presence_min_volume = Real(kContactPresentFraction * cell);
      pp.presence_thin_along_normal = tangential_tie;
      pp.force_limit = it.force_limit;
      pp.integration = it.integration;
      if (it.law == Law::interface) pp.area = it.area;
      if (it.law == Law::interface) has_interface_ = true;
      params_.push_back(pp);
    }
    cfg_.fields = plan.fields;
    cfg_.pair = pair_.data();
    cfg_.params = params_.data();
    cfg_.rigid = rigid_.data();
    cfg_.thickness = D == 2 ? Real(scene.simulation.thickness) : Real(1);
    // Every field the grid gives a velocity takes part in its pairs (ALGORITHM
    // §4.3: the grid's own threshold). A uGIMP particle whose domain has just
    // crossed a grid line reaches the next node row with a weight of
    // (e/h)^2 / 2; left out of the pair, such a sliver moved with its own f/m
    // and its particle took an increment of the order of the weight's
    // gradient. At 1e-6 of the lightest particle (until 2026-12-07) a perfect
    // interface let a light bar's last row lag at 0.86 of its strain (density
    // ratio 1e3; 0.012 at 1e5), and a stuck contact's slip crept 2.7 % in
    // 2.5 ms (docs/interface_validation.md Finding 13,
    // docs/contact_validation.md §24). Contact's presence tests screen by
    // volume, not by this (kContactPresentFraction, kRigidPresentFraction).
    cfg_.mass_threshold = min_particle_mass * Real(kEmptyMassFraction);
    cfg_.dt = Real(dt);
    // USF: pass A's momenta are the strain's velocities (docs/contact_validation.md §13).
    usf_ = scene.simulation.scheme == Scheme::USF;
    if (const char* why = validate_multimaterial(grid, cfg_))
      throw InputError(scene.source_file + ": multimaterial setup: " + why);
  }

  // USL's light-node masses m_L per field (Stepper::set_usl_light_thresholds;
  // empty: MUSL, USF): pass B after the update moves a light field's
  // left-out force where it sticks the pair (kernels/mm_left_out.hpp).
  // fixed_axes: per node, bit d where a support fixes axis d (or empty).
  void set_light_nodes(const std::vector<double>& light_mass,
                       std::vector<unsigned char> fixed_axes) {
    light_mass_.assign(light_mass.begin(), light_mass.end());
    light_fixed_ = std::move(fixed_axes);
  }
  // Before pass B after the update: the step's gravity (which the update
  // scaled with a light node's force) and the grid's dvel (where the update
  // left the rest). Set every step, as the pointers follow the Stepper's
  // own arrays.
  void set_light_step(const std::array<double, 3>& gravity, const std::array<Real*, D>& dvel) {
    cfg_.light_mass = light_mass_.empty() ? nullptr : light_mass_.data();
    cfg_.light_dvel = dvel;
    cfg_.light_fixed = light_fixed_.empty() ? nullptr : light_fixed_.data();
    for (int d = 0; d < 3; ++d) cfg_.light_gravity[std::size_t(d)] = Real(gravity[std::size_t(d)]);
  }

  bool has_interface_forces() const { return enabled_ && has_interface_; }

  // The step's multimaterial nodes, from the masses of the first P2G.
  // `own`: which thread works on which nodes (kernels/node_ownership.hpp);
  // `mixed`: where the particles of several fields meet
  // (kernels/mixed_tiles.hpp), the only nodes read.
  void find_nodes(const GridView<D, Real>& grid, const NodeOwnership& own,
                  const MixedTiles<D>* mixed = nullptr) {
    if (!enabled_) return;
    find_multimaterial_nodes(grid, cfg_.mass_threshold, list_, own, mixed);
  }
  const std::vector<std::uint32_t>& nodes() const { return list_; }
  Real mass_threshold() const { return cfg_.mass_threshold; }

  // After find_nodes and the multimaterial fields' P2G.
  // limit_dt: the step the stick decisions are made for (MMConfig::limit_dt;
  // 0: dt).
  void pass_a(GridView<D, Real>& grid, double dt, double limit_dt, const NodeOwnership& own) {
    if (!enabled_) return;
    cfg_.dt = Real(dt);
    cfg_.limit_dt = Real(limit_dt);
    stats_.reset(fields_);
    if (usf_) carry_held_pairs();
    multimaterial_pass_a(grid, list_, cfg_, stats_, stick_flags_, own, &geometry_,
                         usf_ ? held_last_step_.data() : nullptr);
  }
  // PassB::strain for MUSL's repeat of pass B on the re-extrapolated momenta:
  // it holds the pairs the first pass B held (kHeldInPassB) and leaves the
  // rigid reactions alone (the step's impulse on rigid bodies is already counted).
  void pass_b(GridView<D, Real>& grid, const NodeOwnership& own,
              PassB which = PassB::after_update) {
    if (!enabled_) return;
    if (which == PassB::after_update) {
      multimaterial_pass_b(grid, list_, cfg_, stick_flags_, stats_, own, &geometry_);
      if (usf_) {  // for the next step's pass A (carry_held_pairs)
        last_list_ = list_;
        last_flags_ = stick_flags_;
      }
      return;
    }
    const auto kept = stats_.rigid_reaction;
    multimaterial_pass_b(grid, list_, cfg_, stick_flags_, stats_, own, &geometry_, PassB::strain);
    stats_.rigid_reaction = kept;
  }

  // USF's record of the last pass B (carry_held_pairs) goes into checkpoints:
  // without it the first step after a restart decided pass A on approach
  // alone, and the run was no longer the uninterrupted one bit for bit.
  void save_state(std::vector<io::Blob>& out) const {
    if (!enabled_ || !usf_) return;
    out.push_back(io::make_blob("mm.held_nodes", last_list_));
    out.push_back(io::make_blob("mm.held_flags", last_flags_));
  }
  void load_state(const std::vector<io::Blob>& blobs) {
    if (!enabled_ || !usf_) return;
    last_list_.clear();
    last_flags_.clear();
    const io::Blob* nodes = io::find_optional_blob(blobs, "mm.held_nodes");
    const io::Blob* flags = io::find_optional_blob(blobs, "mm.held_flags");
    if (!nodes || !flags) return;  // an older checkpoint: the first pass A decides on approach
    io::read_blob(*nodes, last_list_);
    io::read_blob(*flags, last_flags_);
    if (last_flags_.size() != last_list_.size() * std::size_t(fields_) ||
        !std::is_sorted(last_list_.begin(), last_list_.end()))
      throw std::runtime_error(
          "checkpoint does not match the scene: mm.held_nodes / mm.held_flags");
  }

  StepCounters counters() const {
    StepCounters c;
    c.multimaterial_nodes = long(list_.size());
    c.nodes_3plus = stats_.nodes_3plus;
    c.force_limited_nodes = stats_.force_limited;
    return c;
  }
  double interface_energy() const { return stats_.interface_energy; }
  void set_interface_energy(double e) { stats_.interface_energy = e; }
  Vec3 rigid_reaction(int field) const {
    if (std::size_t(field) >= stats_.rigid_reaction.size()) return {0, 0, 0};
    const auto& r = stats_.rigid_reaction[std::size_t(field)];
    return {r[0], r[1], r[2]};
  }

 private:
  // USF: the kHeldInPassB and kStuckInPassB bits of the last step's pass B for
  // this step's list (both lists ascend), zero where the node was not in the last one.
  void carry_held_pairs() {
    const std::size_t F = std::size_t(fields_);
    held_last_step_.assign(list_.size() * F, 0);
    std::size_t j = 0;
    for (std::size_t k = 0; k < list_.size(); ++k) {
      while (j < last_list_.size() && last_list_[j] < list_[k]) ++j;
      if (j == last_list_.size()) break;
      if (last_list_[j] != list_[k]) continue;
      for (std::size_t f = 0; f < F; ++f)
        held_last_step_[k * F + f] = last_flags_[j * F + f] & kPassBRecord;
    }
  }

  bool enabled_ = false, has_interface_ = false, usf_ = false;
  int fields_ = 1;
  std::vector<int> pair_;
  std::vector<unsigned char> rigid_;
  std::vector<PairParams<Real>> params_;
  std::vector<Real> light_mass_;            // per field, USL only (set_light_nodes)
  std::vector<unsigned char> light_fixed_;  // per node, USL with supports only
  MMConfig<D, Real> cfg_;
  MMStats stats_;
  std::vector<std::uint32_t> list_;
  std::vector<unsigned char> stick_flags_;
  PassAGeometry<D, Real> geometry_;  // pass A's, for pass B
  // USF only (carry_held_pairs).
  std::vector<std::uint32_t> last_list_;
  std::vector<unsigned char> last_flags_, held_last_step_;
};

}  // namespace mmpm
