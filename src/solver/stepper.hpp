// The explicit MPM step for one (dimension, shape function, precision)
// instantiation: ALGORITHM §2 as a list of stages over SoA data. Setup
// decides once which arrays exist and which stages run.
#pragma once

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <sstream>
#include <type_traits>

#include "kernels/active_nodes.hpp"
#include "kernels/binning.hpp"
#include "kernels/constitutive.hpp"
#include "kernels/face_traction.hpp"
#include "kernels/g2p.hpp"
#include "kernels/grid_update.hpp"
#include "kernels/mirror_supports.hpp"
#include "kernels/node_ownership.hpp"
#include "kernels/p2g.hpp"
#include "kernels/p2g_multimaterial.hpp"
#include "kernels/reduce.hpp"
#include "kernels/separation_extrapolation.hpp"
#include "kernels/shape.hpp"
#include "kernels/support_gradients.hpp"
#include "kernels/supports.hpp"
#include "kernels/team.hpp"
#include "kernels/xpic.hpp"
#include "model/bodies.hpp"
#include "model/material.hpp"
#include "scene/error.hpp"
#include "solver/boundary.hpp"
#include "solver/field_plan.hpp"
#include "solver/geometry_normals.hpp"
#include "solver/multimaterial_stage.hpp"
#include "solver/ramp.hpp"
#include "solver/simulation.hpp"
#include "solver/storage.hpp"

namespace mmpm {

template <int D, class Shape, class Real>
class Stepper final : public Simulation {
  static constexpr int NS = kStressComponents<D>;
  using Clock = std::chrono::steady_clock;

 public:
  explicit Stepper(const Scene& scene);

  void step() override;
  void step_within(double t_end) override;
  long step_count() const override { return step_; }
  double time() const override { return time_; }
  double dt() const override { return dt_; }
  std::size_t particle_count() const override { return P_.n; }
  std::size_t node_count() const override { return G_.nodes; }
  int field_count() const override { return plan_.fields; }
  int tile_edge() const override { return tiles_.T; }
  Energies energies() const override;
  [[noreturn]] void fail_at_fastest_particle(const char* stage,
                                             const std::string& why) const override;
  StepCounters counters() const override {
    StepCounters c = mm_.counters();
    c.mm_fields_with_p2g = mm_fields_scattered_with_p2g_;
    c.p2g_from_tail = p2g_from_tail_;
    return c;
  }
  std::vector<Reaction> reactions() const override;
  io::ParticleField particle_field(const std::string& name) const override;
  io::Snapshot snapshot(const std::vector<std::string>& fields) const override;
  io::GridSnapshot grid_snapshot(const std::vector<std::string>& quantities) const override;
  void set_particle_field(const std::string& name, const std::vector<double>& values) override;
  std::array<double, kStageCount> stage_seconds() const override { return stage_s_; }
  std::array<long, kStageCount> stage_calls() const override { return stage_calls_; }
  std::vector<io::Blob> save_state() const override;
  void load_state(const std::vector<io::Blob>& blobs) override;
  std::string instantiation() const override {
    return std::to_string(D) + "D " + Shape::name + " " + (sizeof(Real) == 8 ? "double" : "float");
  }

  // Exposed for tests and benchmarks.
  ParticleView<D, Real>& particles() { return P_; }
  GridView<D, Real>& grid() { return G_; }
  MultimaterialStage<D, Real>& multimaterial() { return mm_; }
  const NodeOwnership& ownership() const { return own_; }
  // Whether the 2D transfers request grid lines ahead (stepper_impl.hpp).
  bool prefetch_grid() const;
  // The particle columns a pass of `streams` requests ahead
  // (kernels/particle_prefetch.hpp; nothing when prefetch_particles is off).
  ParticleLinesAhead particles_ahead(unsigned streams, bool L_in_columns = true) const;
  // For tests: request from this many bytes of a pass's columns on
  // (default kPrefetchMinParticleBytes), so small scenes take the requests.
  void set_prefetch_min_particle_bytes(std::size_t bytes) { prefetch_min_particle_bytes_ = bytes; }
  // For tests: the shortest gap the node runs skip (kernels/active_nodes.hpp,
  // kMinSkippedNodes), from the next re-sort on, which this asks for.
  void set_min_skipped_nodes(std::size_t n) {
    min_skipped_nodes_ = n;
    dirty_ = true;
  }
  const MixedTiles<D>& mixed_tiles() const { return mixed_tiles_; }

 private:
  // The tile test G2P runs on every particle: inline, from copies of the
  // layout and the grid geometry (a call per particle cost ~12 % of a 2D
  // linear step).
  using KeyFn = PositionTile<D, Real>;
  KeyFn key_fn() const {
    return KeyFn::of(tiles_, key_origins<D, Shape>(G_.origin, G_.h), G_.h, P_.x);
  }

  void setup_particles(const ParticleSeeds& seeds);
  void setup_grid();
  std::uint32_t key_of_position(std::size_t p) const;
  void sort_particles();
  void rebuild_ranges();
  void schedule_built();
  std::pair<std::size_t, std::size_t> color_share(std::size_t color) const;
  // The calling thread's particles in the loops that are not colored
  // (TileSchedule::thread_ranges): the particles of its colored passes.
  TileSchedule::Ranges my_particles() const {
    return schedule_.thread_ranges(std::size_t(team_size()), std::size_t(team_rank()));
  }
  // Whether the particle passes run on the team. A pass's work per particle
  // grows with the stencil (Shape::S^D nodes), so the particle count that
  // pays for the regions falls with it: kParallelMin (8192) for 2D linear
  // (4 nodes), 3641 for 2D uGIMP (9), 1214 for 3D uGIMP (27). With the
  // count alone, a 3D scene of 8000 particles (sphere_in_cube.toml) ran
  // every transfer on one thread (docs/performance.md "Node loops of small
  // grids, and particle passes by their work").
  bool particles_on_team() const {
    std::size_t stencil = 1;
    for (int d = 0; d < D; ++d) stencil *= std::size_t(Shape::S);
    return P_.n * stencil >= kParallelMin * 4;
  }
  void zero_grid(bool mm);
  template <unsigned What>
  void p2g(const char* stage_label);
  // mx, Omega and g (ALGORITHM §1) from the tiles whose particles reach a
  // multimaterial node, the only nodes where they are read (or nothing, when
  // the first P2G scattered them).
  void p2g_multimaterial();
  template <unsigned What>
  void g2p();
  // G2P that also scatters (kScatterMomentum): tiles color by color, as P2G.
  template <unsigned What>
  void g2p_colored();
  G2PParams g2p_params() const;
  // On the particle view P: P_, or the fused tail's view whose L points
  // into a per-thread scratch block (fused_step_tail).
  template <unsigned What>
  G2PRangeResult g2p_range_of(const G2PParams& q, std::size_t begin, std::size_t end,
                              const ParticleView<D, Real>& P) const;
  template <unsigned What>
  G2PRangeResult g2p_range_of(const G2PParams& q, std::size_t begin, std::size_t end) const {
    return g2p_range_of<What>(q, begin, end, P_);
  }
  void collect(const std::vector<G2PRangeResult>& results);
  void constitutive();
  // The constitutive update of particles [lo, hi); returns the first
  // unsound particle there, or SIZE_MAX.
  std::size_t constitutive_range(std::size_t lo, std::size_t hi, const ParticleView<D, Real>& P);
  std::size_t constitutive_range(std::size_t lo, std::size_t hi) {
    return constitutive_range(lo, hi, P_);
  }
  P2GOptions p2g_options() const;
  // The step's first P2G (What) of particles [b, e) with the scene's
  // template flags; p2g_range's contract.
  template <unsigned What>
  std::size_t p2g_tile(const P2GOptions& opt, std::size_t b, std::size_t e);
  // MUSL's last particle stages and the next step's P2G, tile by tile.
  bool step_tail_fusable() const;
  void fused_step_tail();
  double grid_kinetic_energy() const;
  // The velocity-gradient G2P (What adds to kVelocityGradient) and the
  // constitutive update: fused into one pass, or two passes and two stages.
  template <unsigned What>
  void gradient_and_stress();
  void build_stress_table();
  GridUpdateParams grid_update_params() const;
  void grid_update_stage();
  void update_node_ownership(bool rebuilt);
  void update_active_nodes();
  void set_usl_light_thresholds(const ParticleSeeds& seeds);
  void finish_velocities(bool with_dvel);
  // [simulation] xpic_order m >= 1 (kernels/xpic.hpp): v* after the step's
  // first P2G, and the G2P's increment shifted by v*.
  void xpic_filter();
  void apply_xpic_shift();
  // fn(b, e) on each of this thread's uncolored particle ranges, on the
  // team; fn returns the first particle it could not handle, or e. Returns
  // the smallest such particle, or SIZE_MAX.
  template <class RangeFn>
  std::size_t first_stop_in_particle_ranges(RangeFn&& fn);
  bool shifts_separation() const;
  Supports<Real> supports(bool with_dvel);
  void add_rigid_work();
  void collect_support_reactions();
  // Supports on planes as mirrors (kernels/mirror_supports.hpp).
  struct MirrorPlane;
  void setup_mirrors();
  MirrorView<Real> mirror_view(MirrorPlane& mp) const;
  void fold_mirrors(unsigned what, bool with_reaction);
  void fold_mirrors_multimaterial();
  void mark_mirror_nodes();
  void mirror_ghost_velocities(bool with_dvel);
  void update_tractions();
  const std::vector<std::uint32_t>& loaded_particles() const;
  void apply_face_tractions(const GridView<D, Real>& g) const;
  void add_face_traction_work();
  [[noreturn]] void fail_particle(const char* stage, std::size_t p, const std::string& why) const;
  void tic() { t0_ = Clock::now(); }
  void toc(Stage s) {
    toc_time(s);
    ++stage_calls_[s];
  }
  // Time spent on a stage's behalf that is not a pass of its own.
  void toc_time(Stage s) {
    stage_s_[s] += std::chrono::duration<double>(Clock::now() - t0_).count();
  }

  Scene scene_;
  FieldPlan plan_;
  std::vector<MaterialModel> materials_;
  std::vector<BoundaryNodes> boundaries_;
  double dt_ = 0, time_ = 0;
  // While step_within shortens dt_ to land on end_time: the regular step,
  // for the multimaterial pass's stick decisions (MMConfig::limit_dt); else 0.
  double regular_dt_ = 0;
  long step_ = 0;
  Real thickness_ = 1;
  Real mass_threshold_ = 0;
  double min_particle_mass_ = 0;
  std::vector<double> usl_light_threshold_;  // per field; empty: none (MUSL, USF)
  std::array<double, 3> gravity_{0, 0, 0};
  bool has_gravity_ = false, has_traction_ = false;
  bool domain_gradient_ = false;    // some interaction's normal needs g (P-33)
  bool fuse_constitutive_ = false;  // scene's choice and every stressed material isotropic
  std::vector<typename IsotropicStressUpdate<D, Real>::Entry> stress_table_;  // per material
  // Several materials, all isotropic in plane strain (or 3D): one contiguous
  // constitutive loop with per-material constants, no particle lists.
  bool isotropic_by_material_ = false;
  IsotropicByMaterial<D, Real> isotropic_table_;

  ColumnSet<Real> pcols_, gcols_;
  std::vector<std::uint8_t> scratch_bytes_;
  ParticleView<D, Real> P_;
  GridView<D, Real> G_;
  SeparationMoments<D, Real> moments_;           // separation = "extrapolated" only
  std::vector<std::uint8_t> separation_listed_;  // its node flags (zero between steps)
  GridVelocity<D, Real> GV_;
  std::vector<Real> scratch_;
  // xpic_filter's grid (saved p, term then v*, sum, scatter: 4 D arrays of
  // nodes x fields) and particle (D arrays) scratch.
  std::vector<Real> xpic_grid_, xpic_particles_;
  // The velocity gradient of every particle (gradient_and_stress),
  // staggered like the columns.
  std::array<StaggeredArray<Real>, D * D> L_;
  // MUSL's end-of-step positions, staggered like the particle columns (4 KiB aliasing)
  std::array<StaggeredArray<Real>, D> x_next_;
  std::size_t prefetch_min_particle_bytes_ = kPrefetchMinParticleBytes;
  std::vector<std::uint32_t> perm_, offsets_, scratch_keys_;
  // The fused tail's L of one tile per thread (fused_step_tail): the
  // velocity gradient lives from the tile's G2P to its constitutive update
  // in the L1, and never reaches memory.
  std::vector<Real> tail_L_;
  std::size_t max_tile_particles_ = 0;

  TileLayout<D> tiles_;
  TileSchedule schedule_;  // tile ranges and each thread's tiles per color
  NodeOwnership own_;      // each thread's nodes in the node loops
  std::size_t own_threads_ = 0;
  ReachTiles reach_tiles_;     // tiles reaching a multimaterial node (p2g_multimaterial)
  MixedTiles<D> mixed_tiles_;  // where multimaterial nodes can be (rebuilt with the tile ranges)
  // Per field, the nodes its particles can reach (rebuilt with the tile
  // ranges; [simulation] skip_empty_nodes).
  FieldNodeRuns active_nodes_;
  std::size_t min_skipped_nodes_ = kMinSkippedNodes;
  // This step's first P2G also scatters mx, vol, g (chosen from the share of
  // particles the previous step's multimaterial nodes reached).
  bool mm_fields_with_p2g_ = false;
  bool mm_fields_scattered_with_p2g_ = false;  // what the last step did
  bool dirty_ = true;
  // m, p, f hold the next step's P2G (fused_step_tail); grid_ke_: the grid
  // kinetic energy computed before that P2G overwrote m.
  bool grid_ready_ = false;
  double grid_ke_ = 0;
  // This step ended with a fused tail, so grid_ke_ is its grid kinetic
  // energy (m is the next P2G's, complete or not: a tail whose particles
  // changed tiles leaves it partial, and grid_ready_ false).
  bool grid_ke_from_tail_ = false;
  long p2g_from_tail_ = 0;

  // Per-material particle lists (several materials, constitutive pass unfused).
  std::vector<std::vector<std::uint32_t>> material_particles_;
  double traction_ramp_end_ = 0;  // tractions are constant after the last load ramp
  // loaded_particles(): a cache of the load column, refreshed after sorts.
  mutable std::vector<std::uint32_t> loaded_;
  mutable bool loaded_stale_ = true;
  // The loads' face offsets (columns fofs*; kernels/face_traction.hpp).
  std::array<const Real*, D> face_offset_{};

  MultimaterialStage<D, Real> mm_;
  // normal = "geometry" (solver/geometry_normals.hpp): the fields it turns,
  // and each particle id's scene body (for deformable bodies' motions).
  std::vector<GeometryNormalField> geometry_fields_;
  std::vector<std::array<std::size_t, 2>> geometry_pairs_;
  std::vector<int> body_of_id_;
  std::vector<double> rigid_velocity_now_;  // per field x 3 at t + dt
  std::vector<Vec3> boundary_reaction_;
  std::vector<SupportView<Real>> support_views_;    // per boundary, over boundaries_' lists
  std::vector<std::vector<double>> support_terms_;  // per boundary: reaction terms
  // Per node, bit d where a plane support normal to axis d fixes axis d;
  // empty without such planes or multimaterial nodes
  // (kernels/support_gradients.hpp).
  std::vector<unsigned char> plane_axes_;
  // Per node, where it lies on a mirror normal to axis d: bit 2d with the
  // body on the +d side, bit 2d + 1 on the -d side (empty without mirrors
  // or multimaterial nodes).
  std::vector<unsigned char> mirror_side_;
  // Supports on planes that act as mirrors, in boundary order: the ghost
  // layer past the plane and its partners on the body's side.
  struct MirrorPlane {
    std::size_t boundary = 0;
    int axis = 0;           // the plane's normal
    double coordinate = 0;  // where it lies on that axis at rest
    std::vector<std::uint32_t> ghost, partner;
    std::vector<Real> ghost_mass;             // fields x ghosts (MirrorView::ghost_mass)
    std::array<double, 3> reaction{0, 0, 0};  // this step's folds (fold_mirror)
    std::vector<double> fold_terms;           // fields x ghosts x D (fold_mirror's terms)
  };
  std::vector<MirrorPlane> mirrors_;
  // With mirrors (mark_mirror_nodes): the multimaterial nodes and the
  // ghosts folded into them (p2g_multimaterial's reach), the nodes the
  // separation is extrapolated at, and the per-node flags (zero between steps).
  std::vector<std::uint32_t> mm_and_ghosts_, extrapolated_nodes_;
  std::vector<unsigned char> mm_flag_;

  double external_work_ = 0, damping_loss_ = 0;
  std::array<double, kStageCount> stage_s_{};
  std::array<long, kStageCount> stage_calls_{};
  Clock::time_point t0_;
};

}  // namespace mmpm

#include "solver/stepper_impl.hpp"
