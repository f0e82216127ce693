// Implementation of Stepper (included by stepper.hpp only).
#pragma once

namespace mmpm {

// The stress components a particle has, as Voigt indices (xx yy zz yz xz
// xy) and as its stress columns: 3D all six in Voigt order; 2D xx, yy, zz,
// xy, whose columns are stored xx, yy, xy, zz (yz and xz are 0). The
// strain energy and the strain output read the stress through this map.
template <int D>
struct StressVoigt {
  static constexpr int count = D == 2 ? 4 : 6;
  static constexpr std::array<int, 6> voigt =
      D == 2 ? std::array<int, 6>{0, 1, 2, 5, 0, 0} : std::array<int, 6>{0, 1, 2, 3, 4, 5};
  static constexpr std::array<int, 6> column =
      D == 2 ? std::array<int, 6>{0, 1, 3, 2, 0, 0} : std::array<int, 6>{0, 1, 2, 3, 4, 5};
};

template <int D, class Shape, class Real>
Stepper<D, Shape, Real>::Stepper(const Scene& scene) : scene_(scene), plan_(plan_fields(scene)) {
  for (const auto& m : scene.materials)
    materials_.push_back(make_material(m, D, scene.simulation.plane));
  boundaries_ = resolve_boundaries(scene);
  boundary_reaction_.assign(boundaries_.size(), Vec3{0, 0, 0});
  dt_ = stable_time_step(scene);
  fuse_constitutive_ = scene.simulation.fuse_constitutive;
  build_stress_table();
  thickness_ = D == 2 ? Real(scene.simulation.thickness) : Real(1);
  for (const auto& l : scene.loads) {
    if (l.kind == LoadKind::gravity) {
      has_gravity_ = true;
    } else {
      has_traction_ = true;
      traction_ramp_end_ = std::max(traction_ramp_end_, l.ramp);
    }
  }
  domain_gradient_ = plan_.multimaterial && needs_domain_gradient(plan_);
  setup_grid();
  // From the stepper's own copy of the scene: the shapes point into its bodies.
  geometry_fields_ = geometry_normal_fields(scene_, plan_);
  geometry_pairs_ = geometry_normal_pairs(geometry_fields_, plan_);
  setup_particles(make_particles(scene));
  setup_mirrors();
  mm_.setup(scene, plan_, G_, Real(min_particle_mass_), dt_);
  {
    // Which axes the supports fix at each node, for pass B's left-out exchange.
    std::vector<unsigned char> fixed;
    if (!usl_light_threshold_.empty() && plan_.multimaterial && !boundaries_.empty()) {
      fixed.assign(G_.nodes, 0);
      for (const BoundaryNodes& bc : boundaries_)
        for (const std::uint32_t node : bc.nodes)
          for (int d = 0; d < D; ++d)
            if (bc.fix[d]) fixed[node] |= (unsigned char)(1u << d);
    }
    mm_.set_light_nodes(usl_light_threshold_, std::move(fixed));
  }
  // The symmetry planes' nodes, for the domain gradients there.
  if (plan_.multimaterial)
    for (const BoundaryNodes& bc : boundaries_) {
      const int ax = symmetry_axis(bc, D);
      if (ax < 0) continue;
      if (plane_axes_.empty()) plane_axes_.assign(G_.nodes, 0);
      for (const std::uint32_t node : bc.nodes) plane_axes_[node] |= (unsigned char)(1u << ax);
    }
  support_views_.resize(boundaries_.size());
  support_terms_.resize(boundaries_.size());
  for (std::size_t b = 0; b < boundaries_.size(); ++b)
    support_terms_[b].assign(std::size_t(plan_.fields) * boundaries_[b].nodes.size() * D, 0.0);
  rigid_velocity_now_.assign(std::size_t(plan_.fields) * 3, 0.0);
}

template <int D, class Shape, class Real>
void Stepper<D, Shape, Real>::setup_grid() {
  const auto& g = scene_.grid;
  G_.fields = plan_.fields;
  G_.nodes = 1;
  for (int d = 0; d < D; ++d) {
    G_.nodes_per_dim[d] = g.cells[d] + 1;
    G_.h[d] = Real(g.cell[d]);
    G_.origin[d] = Real(g.origin[d]);
    G_.nodes *= std::size_t(g.cells[d] + 1);
  }
  const std::size_t n = G_.nodes * std::size_t(plan_.fields);
  const char* axis = "xyz";
  G_.m = gcols_.add_real("m", n);
  for (int d = 0; d < D; ++d) {
    G_.p[d] = gcols_.add_real(std::string("p") + axis[d], n);
    G_.f[d] = gcols_.add_real(std::string("f") + axis[d], n);
    GV_.vel[d] = gcols_.add_real(std::string("vel") + axis[d], n);
    GV_.dvel[d] = gcols_.add_real(std::string("dvel") + axis[d], n);
  }
  if (plan_.multimaterial) {
    G_.vol = gcols_.add_real("vol", n);
    for (int d = 0; d < D; ++d) {
      G_.mx[d] = gcols_.add_real(std::string("mx") + axis[d], n);
      if (domain_gradient_) G_.g[d] = gcols_.add_real(std::string("g") + axis[d], n);
      G_.fi[d] = gcols_.add_real(std::string("fi") + axis[d], n);
    }
    if (plan_.extrapolated_separation) {
      for (int a = 0; a < D; ++a) {
        moments_.r[a] = gcols_.add_real(std::string("sep_r") + axis[a], n);
        for (int c = 0; c < D; ++c)
          moments_.ur[std::size_t(a * D + c)] =
              gcols_.add_real(std::string("sep_u") + axis[a] + axis[c], n);
      }
      for (int k = 0; k < moments_.kSym; ++k)
        moments_.rr[std::size_t(k)] = gcols_.add_real("sep_rr" + std::to_string(k), n);
    }
  }
  // Tile edge: the largest of 64, 32, 16, 8, 4 in 2D (8, 4 in 3D) that leaves
  // every color at least 32 tiles (20 at edge 64, below). A thread's share of
  // a color is cut at tile boundaries (TileSchedule), so the two threads' work
  // differs by up to one tile: with 8 tiles per color the 3D block of
  // bench_step (28 x 28 x 26 cells) stepped 1.5x faster on 2 threads, with 43
  // (edge 4) 1.9x. Within that limit larger tiles pay for the whole step: 2D
  // linear with 10^6 particles (504^2 cells) steps 1.03-1.07x faster with 32
  // than with 16 (bench step_ab tile_16), with 3e6 (870^2 cells) 1.03-1.04x
  // faster with 64 than with 32 (docs/performance.md "Tile edge of the whole
  // step"), while the 250k scenes, which 32 would leave 16 tiles per color,
  // keep 16. Not beyond 64: the fused tail's per-thread L block of one tile
  // (64^2 cells x 4 particles x 32 B = 512 KiB) is half the L2 already. Edge
  // 64 needs only 20 tiles per color (2D grids from 513^2 cells, 705^2 before
  // 2026-11-29): from 504^2 to 640^2 cells the 2D linear block stepped 5-13 %
  // faster on one thread with 64 than with 32 and the same on two (median
  // ratios 0.97-0.98); with 16 per color (451^2, 480^2) two threads lost
  // 1-38 % (docs/performance.md "Tile edge 64 from 513^2 cells"). Chosen
  // from the grid alone, never from the thread count, so the summation
  // order (and the result) is the same for any number of threads.
  int T = g.tile;
  if (T <= 0) {
    T = D == 2 ? 64 : 8;
    for (; T > 4; T /= 2) {
      std::size_t tiles = 1;
      for (int d = 0; d < D; ++d) tiles *= std::size_t((g.cells[d] + T - 1) / T);
      const std::size_t per_color = T == 64 ? 20 : 32;
      if (tiles >= per_color << D) break;
    }
  }
  tiles_.setup(T, g.cells, scene_.simulation.particle_order == ParticleOrder::color);
}

template <int D, class Shape, class Real>
void Stepper<D, Shape, Real>::setup_particles(const ParticleSeeds& seeds) {
  const std::size_t n = seeds.x.size();
  P_.n = n;
  if (std::any_of(geometry_fields_.begin(), geometry_fields_.end(),
                  [](const GeometryNormalField& f) { return f.rigid_material < 0; }))
    body_of_id_ = seeds.body;  // ids number the seeds (the column id, last below)
  const char* axis = "xyz";
  const bool finite = std::any_of(materials_.begin(), materials_.end(),
                                  [](const MaterialModel& m) { return m.finite_strain(); });
  const bool need_x0 = true;  // displacement output and the displacement separation method
  for (int d = 0; d < D; ++d) P_.x[d] = pcols_.add_real(std::string("x") + axis[d], n);
  for (int d = 0; d < D; ++d) P_.v[d] = pcols_.add_real(std::string("v") + axis[d], n);
  P_.m = pcols_.add_real("m", n);
  P_.V = pcols_.add_real("V", n);
  for (int c = 0; c < NS; ++c) P_.s[c] = pcols_.add_real("s" + std::to_string(c), n);
  // L is no column: it lives within a step (G2P writes it, the
  // constitutive update reads it), so sorts do not permute it and
  // checkpoints do not carry it; gradient_and_stress allocates it.
  if (finite)
    for (int c = 0; c < D * D; ++c) P_.H[c] = pcols_.add_real("H" + std::to_string(c), n);
  if (need_x0)
    for (int d = 0; d < D; ++d) P_.x0[d] = pcols_.add_real(std::string("x0") + axis[d], n);
  // uGIMP half-widths: a column only in a direction where the particles'
  // differ (bodies seeded with different particles per cell); else the
  // one value in the view (kernels/particle_view.hpp half_width), and the
  // transfers build its lanes once per batch instead of reading a column
  // (docs/performance.md "One half-width for all particles").
  if (scene_.grid.shape == ShapeKind::gimp)
    for (int d = 0; d < D; ++d) {
      const Real first = n > 0 ? Real(seeds.half_width[0][d]) : P_.lp_all[std::size_t(d)];
      const bool shared = std::all_of(seeds.half_width.begin(), seeds.half_width.end(),
                                      [&](const Vec3& l) { return Real(l[d]) == first; });
      if (shared)
        P_.lp_all[std::size_t(d)] = first;
      else
        P_.lp[d] = pcols_.add_real(std::string("lp") + axis[d], n);
    }
  if (has_traction_)
    for (int d = 0; d < D; ++d) P_.fext[d] = pcols_.add_real(std::string("fext") + axis[d], n);
  P_.mat = pcols_.add_byte("mat", n);
  std::uint8_t* body = pcols_.add_byte("body", n);
  if (plan_.multimaterial) P_.field = pcols_.add_byte("field", n);
  Real *fbase[3] = {}, *fofs[3] = {};
  std::uint8_t* load = nullptr;
  if (has_traction_) {
    // Base traction force and load index travel with the particle as columns.
    for (int d = 0; d < D; ++d) fbase[d] = pcols_.add_real(std::string("fbase") + axis[d], n);
    load = pcols_.add_byte("load", n);
    // Where the load acts, from the particle (kernels/face_traction.hpp).
    for (int d = 0; d < D; ++d) {
      fofs[d] = pcols_.add_real(std::string("fofs") + axis[d], n);
      face_offset_[std::size_t(d)] = fofs[d];
    }
  }
  pcols_.key.allocate(n, pcols_.next_slot++);
  P_.key = pcols_.key.data();
  // float: the positions' low parts (kernels/position_sum.hpp), after every
  // other column so those keep their allocation slots (staggered_array.hpp).
  if constexpr (std::is_same_v<Real, float>)
    for (int d = 0; d < D && scene_.simulation.compensated_positions; ++d) {
      P_.xlo[d] = pcols_.add_real(std::string("xlo") + axis[d], n);
      std::fill(P_.xlo[d], P_.xlo[d] + n, Real(0));
    }
  // MUSL with an imperfect interface: the separation's shift
  // (kernels/separation_shift.hpp), zero at the start (x = x0).
  if (shifts_separation())
    for (int d = 0; d < D; ++d)
      P_.sep_shift[d] = pcols_.add_real(std::string("sep_shift") + axis[d], n);
  // Last, so every other column keeps its allocation slot.
  pcols_.id.allocate(n, pcols_.next_slot++);
  std::iota(pcols_.id.data(), pcols_.id.data() + n, std::uint32_t(0));

  double min_mass = std::numeric_limits<double>::max();
  for (std::size_t p = 0; p < n; ++p) {
    const auto& mat = materials_[std::size_t(seeds.material[p])];
    for (int d = 0; d < D; ++d) {
      P_.x[d][p] = Real(seeds.x[p][d]);
      P_.x0[d][p] = Real(seeds.x[p][d]);
      P_.v[d][p] = Real(seeds.v[p][d]);
      if (P_.lp[d]) P_.lp[d][p] = Real(seeds.half_width[p][d]);
    }
    const double mass = mat.density * seeds.volume[p];
    min_mass = std::min(min_mass, mass);
    P_.m[p] = Real(mass);
    P_.V[p] = Real(seeds.volume[p]);
    if (P_.H[0])
      for (int c = 0; c < D * D; ++c) P_.H[c][p] = Real(0);  // F = I
    P_.mat[p] = std::uint8_t(seeds.material[p]);
    body[p] = std::uint8_t(std::min(seeds.body[p], 255));
    if (P_.field)
      P_.field[p] = std::uint8_t(plan_.field_of_material[std::size_t(seeds.material[p])]);
    if (has_traction_) {
      for (int d = 0; d < D; ++d) {
        fbase[d][p] = Real(seeds.traction_force[p][d]);
        fofs[d][p] = Real(seeds.traction_offset[p][d]);
      }
      load[p] = std::uint8_t(seeds.load[p] < 0 ? 255 : seeds.load[p]);
    }
  }
  // Fields lighter than this at a node are empty there (ALGORITHM §4.3):
  // their velocity is not formed. 1e-15 of the lightest particle: p / m of
  // a light node is as accurate as of a heavy one (its few contributions
  // carry no cancellation), and its weights' products reach the particles
  // scaled by S, so what a threshold drops is an error of its own. At 1e-9
  // it dropped nodes whose weight gradient is ~sqrt(S) ~ 3e-5 / h (uGIMP's
  // support edge), and a block translating diagonally took a spurious
  // strain (stress 8e-9 MPa at E = 100 after two steps, velocity error
  // 1.4e-8; Extremes.TranslationIsExactForEveryShape). Contact and
  // interfaces use the same (MultimaterialStage::setup).
  mass_threshold_ = Real(kEmptyMassFraction * min_mass);
  min_particle_mass_ = min_mass;
  set_usl_light_thresholds(seeds);
  // Check every particle's stencil fits the grid before anything runs.
  const std::array<Real, 3> inv_h{Real(1) / G_.h[0], Real(1) / G_.h[1], Real(1) / G_.h[2]};
  Stencil<D, Shape, Real> st{};
  for (std::size_t p = 0; p < n; ++p)
    if (!st.build(P_, G_, inv_h, p))
      throw InputError(located(scene_.source_file, 0, "grid",
                               "particle " + std::to_string(p) +
                                   " is too close to the grid edge for the '" + Shape::name +
                                   "' shape function: enlarge the grid"));
  const std::size_t nm = materials_.size();
  isotropic_by_material_ = nm > 1 && nm <= isotropic_table_.lam.size();
  isotropic_table_.dt = Real(dt_);
  for (std::size_t i = 0; i < nm; ++i) {
    const MaterialModel& mat = materials_[i];
    if (mat.type != MaterialType::isotropic || mat.k.plane_stress) {
      isotropic_by_material_ = false;
      break;
    }
    const IsotropicPoint<D, Real> point(mat.k, dt_);
    isotropic_table_.lam[i] = point.lam;
    isotropic_table_.mu2[i] = point.mu2;
  }
  if (nm > 1 && !fuse_constitutive_ && !isotropic_by_material_) material_particles_.resize(nm);
  dirty_ = true;
}

// The fused update's per-material table (gradient_and_stress sets each
// step's dt); fusing needs every stressed material to be isotropic
// (kernels/constitutive.hpp IsotropicStressUpdate).
template <int D, class Shape, class Real>
void Stepper<D, Shape, Real>::build_stress_table() {
  stress_table_.assign(materials_.size(), {});
  for (std::size_t i = 0; i < materials_.size(); ++i) {
    const MaterialModel& mat = materials_[i];
    if (mat.type == MaterialType::isotropic) {
      stress_table_[i].update = IsotropicPoint<D, Real>(mat.k, dt_);
      stress_table_[i].stressed = true;
    } else if (mat.type != MaterialType::rigid) {
      fuse_constitutive_ = false;
    }
  }
}

template <int D, class Shape, class Real>
std::uint32_t Stepper<D, Shape, Real>::key_of_position(std::size_t p) const {
  std::array<int, 3> c{0, 0, 0};
  for (int d = 0; d < D; ++d)
    c[d] = cell_of(P_.x[d][p], key_origin<D, Shape>(G_.origin[d], G_.h[d]), Real(1) / G_.h[d]);
  return tiles_.key(c);
}

template <int D, class Shape, class Real>
void Stepper<D, Shape, Real>::sort_particles() {
  const std::size_t n = P_.n;
  team_for(n >= kParallelMin, n, [&](std::size_t p) { P_.key[p] = key_of_position(p); });
  counting_sort(P_.key, n, tiles_.key_count(), offsets_, perm_, pcols_.id.data());
  // The keys first: the schedule of the new order says which thread's
  // loops take which particles, and so where every other column goes.
  scratch_keys_.resize(n);
  permute_in_place(P_.key, scratch_keys_.data(), perm_.data(), n);
  schedule_.build(tiles_, P_.key, n);
  permute_particle_columns(pcols_, perm_.data(), n, schedule_, scratch_keys_, scratch_,
                           scratch_bytes_);
  schedule_built();
  dirty_ = false;
  grid_ready_ = false;  // a P2G in the old order
  loaded_stale_ = true;
}

// The tail can take the next step's P2G when nothing changes what that P2G
// reads before the next step begins: MUSL (the other schemes' last pass
// sums the external work in chunk order) and the constitutive update in its
// own pass. Tractions do not enter it: the next step adds them at the faces
// (apply_face_tractions) after update_tractions has set them.
template <int D, class Shape, class Real>
bool Stepper<D, Shape, Real>::step_tail_fusable() const {
  if (!scene_.simulation.fuse_step_tail || fuse_constitutive_) return false;
  return scene_.simulation.scheme == Scheme::MUSL;
}

// The particles a traction load acts on, by seed index: their loads then
// add to the nodes in the same order whatever order the sorts and
// [simulation] particle_order store them in (the bits do not depend on
// it). Rebuilt after a sort or a restart moved them.
template <int D, class Shape, class Real>
const std::vector<std::uint32_t>& Stepper<D, Shape, Real>::loaded_particles() const {
  if (loaded_stale_) {
    loaded_.clear();
    const std::uint8_t* load = pcols_.byte("load");
    for (std::size_t p = 0; p < P_.n; ++p)
      if (load[p] != 255) loaded_.push_back(std::uint32_t(p));
    const std::uint32_t* id = pcols_.id.data();
    std::sort(loaded_.begin(), loaded_.end(),
              [id](std::uint32_t a, std::uint32_t b) { return id[a] < id[b]; });
    loaded_stale_ = false;
  }
  return loaded_;
}

// The traction loads' nodal forces, at the loaded faces
// (kernels/face_traction.hpp); the transfers leave them out.
template <int D, class Shape, class Real>
void Stepper<D, Shape, Real>::apply_face_tractions(const GridView<D, Real>& g) const {
  if (!has_traction_) return;
  const std::vector<std::uint32_t>& list = loaded_particles();
  const std::size_t bad =
      scatter_face_tractions<D, Shape>(P_, g, face_offset_, list.data(), list.size());
  if (bad != list.size())
    fail_particle("p2g", list[bad], "its shape-function stencil left the grid");
}

// The work of the traction loads over the step: the power of their nodal
// forces at the grid velocity the strains come from (USL, USF: the updated
// one, before G2P moves the particles; MUSL: the re-extrapolated one).
template <int D, class Shape, class Real>
void Stepper<D, Shape, Real>::add_face_traction_work() {
  if (!has_traction_) return;
  const std::vector<std::uint32_t>& list = loaded_particles();
  // Once every ramp ended a step ago, USF's last loads are these loads.
  if (scene_.simulation.scheme != Scheme::USF || time_ - 0.5 * dt_ >= traction_ramp_end_) {
    external_work_ +=
        dt_ * face_traction_power<D, Shape>(P_, G_, GV_, face_offset_, list.data(), list.size());
    return;
  }
  // USF reads, at the start of a step, the velocities of the last step's
  // motion, which the last step's loads drove: their work is those loads'
  // (at the last step's mid-time) on these velocities, as MUSL pairs a
  // step's loads with the velocities it re-extrapolates at its end.
  std::vector<double> factor(scene_.loads.size(), 0.0);  // the listed particles have a load
  for (std::size_t l = 0; l < scene_.loads.size(); ++l) {
    const double ramp = scene_.loads[l].ramp;
    const double now = ramp_fraction(time_ + 0.5 * dt_, ramp);
    const double last = std::max(0.0, ramp_fraction(time_ - 0.5 * dt_, ramp));
    factor[l] = now > 0 ? last / now : 0.0;
  }
  const std::uint8_t* load = pcols_.byte("load");
  external_work_ += dt_ * face_traction_power<D, Shape>(P_, G_, GV_, face_offset_, list.data(),
                                                        list.size(), load, factor.data());
}

// MUSL's last particle stages and the next step's P2G in one pass, tile by
// tile, color by color (docs/performance.md "The step's tail fused tile by
// tile"): the gradient G2P of a tile (L, x <- x_next), its constitutive
// update, then its P2G of m, m v, V sigma into the zeroed m, p, f, which
// no stage reads after the velocity pass (G2P reads vel and dvel). P2G then
// reads particle columns the tile's two stages have just touched, instead
// of fetching them from memory a pass later. Each node receives its sums in
// the colored P2G's order, so the next step sees bitwise the grid its own
// P2G would have made. A tile with a particle that changed tile skips its
// P2G (the particle may reach past the tile's reach) and the next step,
// which re-sorts, scatters again. The wall time is shared among the g2p,
// constitutive and p2g stages in the proportions thread 0 measured.
template <int D, class Shape, class Real>
void Stepper<D, Shape, Real>::fused_step_tail() {
  using Sec = std::chrono::duration<double>;
  const auto start = Clock::now();
  grid_ke_ = grid_kinetic_energy();  // energies(): m is about to be overwritten
  grid_ke_from_tail_ = true;
  isotropic_table_.dt = Real(dt_);  // as in constitutive()
  const bool mm = plan_.multimaterial;
  zero_grid(mm);
  G2PParams q = g2p_params();
  const P2GOptions opt = p2g_options();
  // The gradient pass requests the columns of all three stages: the
  // constitutive update and P2G then find them in the cache.
  const ParticleLinesAhead ahead = particles_ahead(
      g2p_streams(kCommitPosition | kVelocityGradient) | kStreamConstitutive | kStreamScatter,
      false);
  q.particles_ahead = &ahead;
  const bool with_mm = mm && mm_fields_with_p2g_;  // what the next step's P2G scatters
  std::vector<G2PRangeResult> res(tiles_.tile_count);
  std::atomic<std::size_t> first_bad{SIZE_MAX}, first_unsound{SIZE_MAX};
  double part[3] = {0, 0, 0};  // thread 0: gradient G2P, constitutive, P2G
  // L of one tile per thread, columns a multiple of 64 bytes apart.
  const std::size_t l_stride = (max_tile_particles_ + 7) / 8 * 8;
  const std::size_t l_block = l_stride * std::size_t(D * D);
  const std::size_t team = particles_on_team() ? std::size_t(omp_get_max_threads()) : 1;
  if (tail_L_.size() < team * l_block) tail_L_.assign(team * l_block, Real(0));
  for (std::size_t c = 0; c < schedule_.tiles.size(); ++c) {
    if (schedule_.tiles[c].empty()) continue;
    team_run(particles_on_team(), [&] {
      std::size_t bad = SIZE_MAX, unsound = SIZE_MAX;
      double mine[3] = {0, 0, 0};
      ParticleView<D, Real> Pt = P_;
      Real* const scratch = tail_L_.data() + std::size_t(team_rank()) * l_block;
      for (auto [k, last] = color_share(c); k < last; ++k) {
        const std::uint32_t t = schedule_.tiles[c][k];
        const std::size_t b = schedule_.begin[t], e = schedule_.begin[t + 1];
        // Pt.L[i][p] is scratch[i * l_stride + p - b] for p in [b, e).
        for (int i = 0; i < D * D; ++i)
          Pt.L[std::size_t(i)] = offset_for_range(scratch + std::size_t(i) * l_stride, b);
        const auto t0 = Clock::now();
        res[t] = g2p_range_of<kCommitPosition | kVelocityGradient>(q, b, e, Pt);
        const auto t1 = Clock::now();
        unsound = std::min(unsound, constitutive_range(b, e, Pt));
        const auto t2 = Clock::now();
        if (!res[t].moved_tile) {
          const std::size_t r = with_mm
                                    ? p2g_tile<kMassMomentum | kForce | kMultimaterial>(opt, b, e)
                                    : p2g_tile<kMassMomentum | kForce>(opt, b, e);
          if (r != e) bad = std::min(bad, r);
        }
        const auto t3 = Clock::now();
        mine[0] += Sec(t1 - t0).count();
        mine[1] += Sec(t2 - t1).count();
        mine[2] += Sec(t3 - t2).count();
      }
      if (team_rank() == 0)
        for (int i = 0; i < 3; ++i) part[i] += mine[i];
      offer_min(first_bad, bad);
      offer_min(first_unsound, unsound);
    });
  }
  const std::size_t bad = first_bad.load(), unsound = first_unsound.load();
  const double wall = Sec(Clock::now() - start).count();
  const double measured = part[0] + part[1] + part[2];
  const Stage stage[3] = {kStageG2P, kStageConstitutive, kStageP2G};
  for (int i = 0; i < 3; ++i) {
    stage_s_[stage[i]] += measured > 0 ? wall * part[i] / measured : (i == 0 ? wall : 0.0);
    ++stage_calls_[stage[i]];
  }
  collect(res);  // G2P failures first, as the separate passes report them
  if (unsound != SIZE_MAX)
    fail_particle("constitutive", unsound, "J <= 0 or a non-finite stress/volume");
  if (bad != SIZE_MAX) fail_particle("p2g", bad, "its shape-function stencil left the grid");
  grid_ready_ = !dirty_;  // a tile change skipped P2Gs; the next step re-sorts
}

// Kinetic energy of the grid velocity field (after the last update).
template <int D, class Shape, class Real>
double Stepper<D, Shape, Real>::grid_kinetic_energy() const {
  const std::size_t total = G_.nodes * std::size_t(G_.fields);
  auto sum = [&](std::size_t b, std::size_t end, std::array<double, 1>& acc) {
    for (std::size_t i = b; i < end; ++i) {
      double v2 = 0;
      for (int d = 0; d < D; ++d) v2 += double(GV_.vel[d][i]) * double(GV_.vel[d][i]);
      acc[0] += 0.5 * double(G_.m[i]) * v2;
    }
  };
  const FieldNodeRuns* active = own_.active;
  return deterministic_sum<1>(
      total, [&](std::size_t b, std::size_t end, std::array<double, 1>& acc) {
        // Field by field, rigid fields left out (as in energies()); with
        // `active`, a field's runs in node order: the nodes skipped hold
        // m = 0 and would add +0.
        for (std::size_t i = b; i < end;) {
          const std::size_t f = i / G_.nodes, o = f * G_.nodes;
          const std::size_t last = std::min(end, o + G_.nodes);
          if (!plan_.rigid[f] && !active) sum(i, last, acc);
          if (!plan_.rigid[f] && active)
            active->for_each(int(f), i - o, last - o,
                             [&](std::size_t r0, std::size_t r1) { sum(o + r0, o + r1, acc); });
          i = last;
        }
      })[0];
}

// Tile ranges, color lists and per-material lists from the (sorted) keys.
template <int D, class Shape, class Real>
void Stepper<D, Shape, Real>::rebuild_ranges() {
  schedule_.build(tiles_, P_.key, P_.n);
  schedule_built();
}

// What follows the tile schedule: node split, mixed tiles, material lists.
template <int D, class Shape, class Real>
void Stepper<D, Shape, Real>::schedule_built() {
  const std::size_t n = P_.n;
  max_tile_particles_ = 0;
  for (std::size_t t = 0; t < tiles_.tile_count; ++t)
    max_tile_particles_ =
        std::max(max_tile_particles_, std::size_t(schedule_.begin[t + 1] - schedule_.begin[t]));
  if (scene_.simulation.skip_empty_nodes)
    update_active_nodes();  // before the split, which counts them
  update_node_ownership(true);
  if (plan_.multimaterial) mixed_tiles_.build(tiles_, G_.nodes_per_dim, schedule_.begin, P_.field);
  if (!material_particles_.empty()) {
    for (auto& l : material_particles_) l.clear();
    for (std::size_t p = 0; p < n; ++p) material_particles_[P_.mat[p]].push_back(std::uint32_t(p));
  }
}

// The calling thread's tiles of `color` in a colored pass
// (kernels/binning.hpp TileSchedule).
template <int D, class Shape, class Real>
std::pair<std::size_t, std::size_t> Stepper<D, Shape, Real>::color_share(std::size_t color) const {
  return schedule_.share(color, std::size_t(team_size()), std::size_t(team_rank()));
}

// The node split for the current team size (kernels/node_ownership.hpp),
// from the sorted keys; `rebuilt`: the keys changed.
template <int D, class Shape, class Real>
void Stepper<D, Shape, Real>::update_node_ownership(bool rebuilt) {
  const auto threads = std::size_t(omp_get_max_threads());
  if (!rebuilt && own_threads_ == threads) return;
  own_threads_ = threads;
  own_ = node_ownership<D>(tiles_, G_.nodes_per_dim, schedule_, threads,
                           scene_.simulation.skip_empty_nodes ? &active_nodes_ : nullptr);
}

// The nodes each field's particles can reach, from the new tile ranges
// (kernels/active_nodes.hpp). The node passes skip the rest, which must
// hold zeros: every node that leaves a field's runs is zeroed here in every
// grid array, and stays zero until it rejoins (no particle reaches it, no
// pass visits it). In a run these nodes are zero already (a particle moves
// less than a cell per step, so the last P2G reached only nodes of the new
// runs); the zeroing keeps the invariant whatever the history, and the
// multimaterial search reads every field's mass at the mixed tiles' nodes
// (with three fields, nodes outside one field's runs). The support
// reaction terms are zeroed for the same reason (a skipped support node
// writes none); the step that follows writes those of the nodes it visits.
template <int D, class Shape, class Real>
void Stepper<D, Shape, Real>::update_active_nodes() {
  if (active_nodes_.field.empty()) active_nodes_ = all_node_runs(G_.nodes, G_.fields);
  FieldNodeRuns next = active_node_runs<D>(tiles_, G_.nodes_per_dim, schedule_.begin, P_.field,
                                           G_.fields, min_skipped_nodes_);
  const std::size_t nodes = G_.nodes;
  for_each_dropped(active_nodes_, next, [&](int f, std::size_t b, std::size_t e) {
    const std::size_t o = std::size_t(f) * nodes;
    for (auto& column : gcols_.reals)
      std::fill(column.data() + o + b, column.data() + o + e, Real(0));
  });
  active_nodes_ = std::move(next);
  for (auto& terms : support_terms_) std::fill(terms.begin(), terms.end(), 0.0);
}

template <int D, class Shape, class Real>
void Stepper<D, Shape, Real>::zero_grid(bool mm) {
  // One region for every array, each thread zeroing the nodes it owns. The
  // multimaterial arrays: fi always; mx, vol, g only when this step's first
  // P2G scatters them, else p2g_multimaterial zeroes what it writes.
  std::array<Real*, 2 + 5 * D> arrays{};  // null entries are skipped
  std::size_t k = 0;
  arrays[k++] = G_.m;
  for (int d = 0; d < D; ++d) arrays[k++] = G_.p[d], arrays[k++] = G_.f[d];
  if (mm) {
    for (int d = 0; d < D; ++d) arrays[k++] = G_.fi[d];
    if (mm_fields_with_p2g_) {
      arrays[k++] = G_.vol;
      for (int d = 0; d < D; ++d) arrays[k++] = G_.mx[d], arrays[k++] = G_.g[d];
    }
  }
  zero_owned(own_, G_.nodes, G_.fields, arrays);
}

// Whether the 2D transfers request the grid lines a line ahead
// (kernels/grid_prefetch.hpp): [simulation] prefetch_grid, on grids whose
// nine arrays (all fields) take kPrefetchMinGridBytes or more. On smaller
// grids, which stay in a core's L2, the requests only cost: the 2D linear
// step at 3*10^4 particles (0.58 MiB of grid) read 27.4 against 26.5
// ns/particle-step (docs/performance.md "Grid lines a line ahead").
template <int D, class Shape, class Real>
bool Stepper<D, Shape, Real>::prefetch_grid() const {
  const std::size_t bytes = G_.nodes * std::size_t(G_.fields) * 9 * sizeof(Real);
  return scene_.simulation.prefetch_grid && bytes >= kPrefetchMinGridBytes;
}

// The particle columns a pass requests ahead (kernels/particle_prefetch.hpp):
// [simulation] prefetch_particles, in 2D, when the pass's columns take
// kPrefetchMinParticleBytes or more (smaller ones stay in the caches, where
// the requests only cost). Not in 3D: the 3D uGIMP step, whose windows take
// 4-8 times the 2D work per particle, did not gain (paired blocks at 101 376
// particles 0.992 / 0.962 on 1 / 2 threads; 10^6 particles, alternated runs,
// 171.5-173.3 against 172.4-179.1 ns/particle-step on one thread).
template <int D, class Shape, class Real>
ParticleLinesAhead Stepper<D, Shape, Real>::particles_ahead(unsigned streams,
                                                            bool L_in_columns) const {
  if (D == 3 || !scene_.simulation.prefetch_particles) return {};
  // The commit pass also advances the separation shift, where there is one
  // (g2p_range_of).
  if ((streams & kStreamCommit) && P_.sep_shift[0]) streams |= kStreamShift;
  ParticleLinesAhead ahead(P_, streams, L_in_columns);
  if (P_.n * ahead.bytes_per_particle() < prefetch_min_particle_bytes_) return {};
  return ahead;
}

template <int D, class Shape, class Real>
P2GOptions Stepper<D, Shape, Real>::p2g_options() const {
  P2GOptions opt;
  opt.position_separation = plan_.position_separation;
  opt.inv_thickness = 1.0 / double(thickness_);
  opt.prefetch_grid = prefetch_grid();
  return opt;
}

template <int D, class Shape, class Real>
template <unsigned What>
std::size_t Stepper<D, Shape, Real>::p2g_tile(const P2GOptions& opt, std::size_t b, std::size_t e) {
  if (plan_.multimaterial && domain_gradient_) {
    constexpr unsigned W = What | ((What & kMultimaterial) ? unsigned(kDomainGradient) : 0u);
    return p2g_range<D, Shape, Real, W, true, false>(P_, G_, opt, b, e);
  }
  // Traction loads act at the faces (apply_face_tractions), not in the transfers.
  if (plan_.multimaterial) return p2g_range<D, Shape, Real, What, true, false>(P_, G_, opt, b, e);
  return p2g_range<D, Shape, Real, What, false, false>(P_, G_, opt, b, e);
}

template <int D, class Shape, class Real>
template <unsigned What>
void Stepper<D, Shape, Real>::p2g(const char* label) {
  P2GOptions opt = p2g_options();
  const ParticleLinesAhead ahead = particles_ahead(kStreamScatter);
  opt.particles_ahead = &ahead;
  std::atomic<std::size_t> first_bad{SIZE_MAX};
  for (std::size_t c = 0; c < schedule_.tiles.size(); ++c) {
    if (schedule_.tiles[c].empty()) continue;
    team_run(particles_on_team(), [&] {
      std::size_t bad = SIZE_MAX;
      for (auto [k, last] = color_share(c); k < last; ++k) {
        const std::uint32_t t = schedule_.tiles[c][k];
        const std::size_t b = schedule_.begin[t], e = schedule_.begin[t + 1];
        const std::size_t r = p2g_tile<What>(opt, b, e);
        if (r != e) bad = std::min(bad, r);
      }
      offer_min(first_bad, bad);
    });
  }
  if (const std::size_t bad = first_bad.load(); bad != SIZE_MAX)
    fail_particle(label, bad, "its shape-function stencil left the grid");
}

// kernels/p2g_multimaterial.hpp: mx, vol, g only from the tiles that reach
// a multimaterial node, unless this step scattered them with the first P2G.
// Either way the values at multimaterial nodes are the same (bitwise,
// tests/test_p2g.cpp, tests/test_multimaterial_fields.cpp), so the choice
// changes no result. Scattering them apart costs the reaching tiles'
// particles a second window build, so when those are more than
// [simulation] mm_fields_share of the particles (fields mixed everywhere:
// many small inclusions) the next step scatters them with the first P2G.
template <int D, class Shape, class Real>
void Stepper<D, Shape, Real>::p2g_multimaterial() {
  // With mirrors the ghosts folded into multimaterial nodes join the reach,
  // and mm_flag_ holds what fold_mirrors_multimaterial reads (below).
  const bool mirrored = !mirrors_.empty();
  if (mirrored) mark_mirror_nodes();
  const std::size_t reaching = find_reach_tiles<D, Shape, Real>(
      G_, tiles_, schedule_, mirrored ? mm_and_ghosts_ : mm_.nodes(), reach_tiles_);
  const bool scattered = mm_fields_with_p2g_;
  mm_fields_scattered_with_p2g_ = scattered;
  mm_fields_with_p2g_ = double(reaching) > scene_.simulation.mm_fields_share * double(P_.n);
  if (!scattered) {
    const P2GOptions opt = p2g_options();
    const std::size_t bad = p2g_multimaterial_fields<D, Shape, Real>(
        P_, G_, opt, tiles_, schedule_, reach_tiles_, domain_gradient_, particles_on_team());
    if (bad != SIZE_MAX) fail_particle("p2g", bad, "its shape-function stencil left the grid");
  }
  if (moments_.enabled()) {  // separation = "extrapolated": mx from the centroids to the nodes
    const std::size_t bad = extrapolate_separation<D, Shape, Real>(
        P_, G_, moments_, schedule_, reach_tiles_, mirrored ? extrapolated_nodes_ : mm_.nodes(),
        plan_.rigid.data(), mm_.mass_threshold(), separation_listed_, particles_on_team());
    if (bad != SIZE_MAX) fail_particle("p2g", bad, "its shape-function stencil left the grid");
  }
  if (mirrored) fold_mirrors_multimaterial();
}

// p2g_multimaterial's node lists with mirrors (after find_nodes and the mass
// fold), in mm_and_ghosts_ and extrapolated_nodes_: the multimaterial nodes
// plus the ghosts whose fields the fold adds into them
// (fold_mirror_multimaterial), so that the tiles reaching those ghosts
// scatter too; and the nodes the separation is extrapolated at.
// mm_flag_: bit 0 a multimaterial node, bit 2 a ghost folded into one (where
// two mirrors meet, the first mirror's corner ghost folds into the second's
// ghost, which folds into a partner: so the mirrors are visited last to
// first), bit 1 a multimaterial node that took an image's mass. Those are
// not extrapolated: their particles' moments hold the body's side alone,
// about a centroid the fold moved, so they keep the centroid of the body and
// its image (the paper's estimate).
template <int D, class Shape, class Real>
void Stepper<D, Shape, Real>::mark_mirror_nodes() {
  constexpr unsigned char kMM = 1, kImaged = 2, kGhost = 4;
  const std::vector<std::uint32_t>& nodes = mm_.nodes();
  if (mm_flag_.size() != G_.nodes) mm_flag_.assign(G_.nodes, 0);
  for (const std::uint32_t n : nodes) mm_flag_[n] = kMM;
  mm_and_ghosts_ = nodes;
  for (std::size_t i = mirrors_.size(); i-- > 0;) {
    const MirrorPlane& mp = mirrors_[i];
    const std::size_t count = mp.partner.size();
    for (std::size_t k = 0; k < count; ++k) {
      const std::uint32_t q = mp.partner[k];
      if (!(mm_flag_[q] & (kMM | kGhost))) continue;
      if (!(mm_flag_[mp.ghost[k]] & kGhost)) mm_and_ghosts_.push_back(mp.ghost[k]);
      mm_flag_[mp.ghost[k]] |= kGhost;
      if (mm_flag_[q] & kMM)
        for (int f = 0; f < G_.fields; ++f)
          if (!plan_.rigid[std::size_t(f)] && mp.ghost_mass[std::size_t(f) * count + k] > Real(0))
            mm_flag_[q] |= kImaged;
    }
  }
  extrapolated_nodes_.clear();
  for (const std::uint32_t n : nodes)
    if (!(mm_flag_[n] & kImaged)) extrapolated_nodes_.push_back(n);
}

// The image's mx, Omega and g of every field (rigid ones too) at the mirror
// partners that are multimaterial nodes or ghosts folded into one (kernels/mirror_supports.hpp),
// after p2g_multimaterial and the separation's extrapolation, before the normals and pass A read
// them; the mirrors in the order of the mass fold. The separation coordinate is odd along the
// support's fixed axes about the plane's displacement u_s(t) (as the momenta about its velocity);
// with positions (separation = "position") along the plane's normal only, about the plane's
// position: the image's reflected coordinates.
template <int D, class Shape, class Real>
void Stepper<D, Shape, Real>::fold_mirrors_multimaterial() {
  team_run(G_.nodes * std::size_t(G_.fields) >= kParallelMinNodes, [&] {
    const auto [first, last] = own_.mine(G_.nodes);
    for (std::size_t i = 0; i < mirrors_.size(); ++i) {
      if (i > 0) team_barrier();
      MirrorPlane& mp = mirrors_[i];
      const BoundaryNodes& bc = boundaries_[mp.boundary];
      const double moved = bc.moving ? ramp_fraction(time_, bc.ramp) : 0.0;
      bool odd[3] = {false, false, false};
      Real s_odd[3] = {0, 0, 0};
      for (int d = 0; d < D; ++d) {
        const double u_s = bc.fix[d] ? bc.displacement[d] * moved : 0.0;
        if (plan_.position_separation) {
          odd[d] = d == mp.axis;
          if (odd[d]) s_odd[d] = Real(2.0 * (mp.coordinate + u_s));
        } else {
          odd[d] = bc.fix[d];
          s_odd[d] = Real(2.0 * u_s);
        }
      }
      const MirrorView<Real> v = mirror_view(mp);
      for (int f = 0; f < G_.fields; ++f)
        fold_mirror_multimaterial(G_, v, f, odd, s_odd, mp.axis, mm_flag_.data(), first, last);
    }
  });
  for (const std::uint32_t n : mm_and_ghosts_) mm_flag_[n] = 0;
}

template <int D, class Shape, class Real>
G2PParams Stepper<D, Shape, Real>::g2p_params() const {
  G2PParams q;
  q.dt = dt_;
  q.flip = scene_.simulation.flip;
  q.rigid = plan_.rigid.data();
  q.rigid_velocity = reinterpret_cast<const double(*)[3]>(rigid_velocity_now_.data());
  for (int d = 0; d < D; ++d) q.body_accel[d] = gravity_[d];
  q.prefetch_grid = prefetch_grid();
  return q;
}

// One G2P range with the scene's features as template flags.
template <int D, class Shape, class Real>
template <unsigned What>
G2PRangeResult Stepper<D, Shape, Real>::g2p_range_of(const G2PParams& q, std::size_t b,
                                                     std::size_t e,
                                                     const ParticleView<D, Real>& P) const {
  const KeyFn key_of = key_fn();
  auto run = [&]<bool MF, bool TR, bool GR, unsigned W = What>() {
    if constexpr ((W & kStressUpdate) != 0)
      return g2p_range<D, Shape, Real, W, MF, TR, GR>(
          P, G_, GV_, q, key_of, b, e, IsotropicStressUpdate<D, Real>{stress_table_.data()});
    else
      return g2p_range<D, Shape, Real, W, MF, TR, GR>(P, G_, GV_, q, key_of, b, e);
  };
  // MUSL's gradient pass advances the separation shift where the scene has
  // one (shifts_separation; only multimaterial scenes have interfaces).
  if constexpr ((What & kCommitPosition) != 0)
    if (plan_.multimaterial && P.sep_shift[0]) {
      constexpr unsigned WS = What | kSeparationShift;
      return has_gravity_ ? run.template operator()<true, false, true, WS>()
                          : run.template operator()<true, false, false, WS>();
    }
  // The tractions' work is the face loads' (add_face_traction_work).
  if (plan_.multimaterial)
    return has_gravity_ ? run.template operator()<true, false, true>()
                        : run.template operator()<true, false, false>();
  return has_gravity_ ? run.template operator()<false, false, true>()
                      : run.template operator()<false, false, false>();
}

// Outcomes in a fixed order (chunk or tile index), so the external work sums
// the same way for any number of threads.
template <int D, class Shape, class Real>
void Stepper<D, Shape, Real>::collect(const std::vector<G2PRangeResult>& res) {
  for (const auto& r : res) {
    if (r.bad != SIZE_MAX)
      fail_particle("g2p", r.bad, "non-finite velocity or stencil off the grid");
    if (r.unsound != SIZE_MAX)
      fail_particle("constitutive", r.unsound, "J <= 0 or a non-finite stress/volume");
    external_work_ += r.external_work;
    if (r.moved_tile) dirty_ = true;
  }
}

template <int D, class Shape, class Real>
template <unsigned What>
void Stepper<D, Shape, Real>::g2p() {
  G2PParams q = g2p_params();
  const ParticleLinesAhead ahead = particles_ahead(g2p_streams(What));
  q.particles_ahead = &ahead;
  const std::size_t n = P_.n, chunks = chunk_count(n);
  std::vector<G2PRangeResult> res(chunks);
  // Fixed chunks (the external work sums in chunk order whatever the
  // threads), each run by the thread whose particles it begins in.
  team_run(particles_on_team(), [&] {
    const TileSchedule::Ranges mine = my_particles();
    for (std::size_t r = 0; r < mine.count; ++r) {
      const auto [first, last] = mine.range[r];
      for (std::size_t c = chunk_count(first); c * kReduceChunk < last; ++c) {
        const std::size_t b = c * kReduceChunk, e = std::min(n, b + kReduceChunk);
        res[c] = g2p_range_of<What>(q, b, e);
      }
    }
  });
  collect(res);
}

template <int D, class Shape, class Real>
template <unsigned What>
void Stepper<D, Shape, Real>::g2p_colored() {
  G2PParams q = g2p_params();
  const ParticleLinesAhead ahead = particles_ahead(g2p_streams(What));
  q.particles_ahead = &ahead;
  std::vector<G2PRangeResult> res(tiles_.tile_count);
  for (std::size_t c = 0; c < schedule_.tiles.size(); ++c) {
    if (schedule_.tiles[c].empty()) continue;
    team_run(particles_on_team(), [&] {
      for (auto [k, last] = color_share(c); k < last; ++k) {
        const std::uint32_t t = schedule_.tiles[c][k];
        res[t] = g2p_range_of<What>(q, schedule_.begin[t], schedule_.begin[t + 1]);
      }
    });
  }
  collect(res);
}

// One parallel region for all materials, each thread on its own particles
// (TileSchedule::thread_ranges): a material's list is cut at the ranges'
// ends, so a thread updates only particles it touched in the passes before
// and the threads share the work of every material without a barrier per
// material. Then each thread checks its own ranges for inverted or blown-up
// particles (non-positive or non-finite volume, non-finite stress) while
// they are still in its cache.
template <int D, class Shape, class Real>
void Stepper<D, Shape, Real>::constitutive() {
  std::atomic<std::size_t> first_bad{SIZE_MAX};
  // This step's dt (the last step may be shorter: step_within), set before
  // the threads read the table.
  isotropic_table_.dt = Real(dt_);
  team_run(particles_on_team(), [&] {
    const TileSchedule::Ranges mine = my_particles();
    std::size_t bad = SIZE_MAX;
    for (std::size_t r = 0; r < mine.count; ++r)
      bad = std::min(bad, constitutive_range(mine.range[r].first, mine.range[r].second));
    offer_min(first_bad, bad);
  });
  if (const std::size_t bad = first_bad.load(); bad != SIZE_MAX)
    fail_particle("constitutive", bad, "J <= 0 or a non-finite stress/volume");
}

template <int D, class Shape, class Real>
std::size_t Stepper<D, Shape, Real>::constitutive_range(std::size_t lo, std::size_t hi,
                                                        const ParticleView<D, Real>& P) {
  if (isotropic_by_material_) isotropic_table_.range(P, lo, hi);
  for (std::size_t mi = 0; mi < materials_.size() && !isotropic_by_material_; ++mi) {
    const MaterialModel& mat = materials_[mi];
    const std::uint32_t* idx = nullptr;
    std::size_t first = lo, last = hi;
    if (!material_particles_.empty()) {
      const auto& list = material_particles_[mi];
      idx = list.data();
      first = std::size_t(std::lower_bound(list.begin(), list.end(), lo) - list.begin());
      last = std::size_t(std::lower_bound(list.begin(), list.end(), hi) - list.begin());
    }
    switch (mat.type) {
      case MaterialType::isotropic:
        update_particles(P, idx, first, last, IsotropicPoint<D, Real>(mat.k, dt_));
        break;
      case MaterialType::transverse:
        update_particles(P, idx, first, last, AnisotropicPoint<D, Real>(mat.k, dt_));
        break;
      case MaterialType::neohookean:
        update_particles(P, idx, first, last, NeoHookeanPoint<D, Real>(mat.k, dt_));
        break;
      case MaterialType::rigid:
        break;
    }
  }
  return first_unsound(P, lo, hi);
}

template <int D, class Shape, class Real>
template <unsigned What>
void Stepper<D, Shape, Real>::gradient_and_stress() {
  // The only passes that keep L for every particle: MUSL's fused tail keeps
  // a tile's L at a time, so a run that only takes the tail never allocates it.
  for (int c = 0; c < D * D; ++c) {
    auto& column = L_[std::size_t(c)];
    if (column.size() != P_.n) column.allocate(P_.n, pcols_.next_slot++);
    P_.L[std::size_t(c)] = column.data();
  }
  if (fuse_constitutive_) {
    // This step's dt: the table was built with the run's, and the last step
    // may be shorter (step_within). Kept at the run's, the fused update
    // took a full step's strain from the short step's gradient: two_layer
    // ending 0.2 of a step past a multiple of dt read 0.33 % off in stress.
    // (The separate pass's table for several isotropic materials in one
    // field had the same fault: constitutive(), fused_step_tail().)
    for (auto& entry : stress_table_) entry.update.dt = Real(dt_);
    tic();
    g2p<What | kVelocityGradient | kStressUpdate>();
    toc(kStageG2P);
  } else {
    tic();
    g2p<What | kVelocityGradient>();
    toc(kStageG2P);
    tic();
    constitutive();
    toc(kStageConstitutive);
  }
}

// The grid update's parameters for this step; finish_velocities reads its
// light nodes from the same values.
template <int D, class Shape, class Real>
GridUpdateParams Stepper<D, Shape, Real>::grid_update_params() const {
  GridUpdateParams q;
  q.dt = dt_;
  q.damping = scene_.grid.damping;
  q.mass_threshold = double(mass_threshold_);
  for (int d = 0; d < D; ++d) q.body_accel[d] = gravity_[d];
  q.rigid = plan_.rigid.data();
  q.rigid_velocity = reinterpret_cast<const double(*)[3]>(rigid_velocity_now_.data());
  q.has_interface_force = mm_.has_interface_forces();
  q.light_threshold = usl_light_threshold_.empty() ? nullptr : usl_light_threshold_.data();
  return q;
}

template <int D, class Shape, class Real>
void Stepper<D, Shape, Real>::grid_update_stage() {
  GridUpdateParams q = grid_update_params();
  // Without pass B nothing changes p before the velocities: one pass, which
  // also applies the supports.
  q.velocities = !plan_.multimaterial;
  q.keep_momentum = !q.velocities;  // the velocity pass is the last to read p
  if (q.velocities) {
    const Supports<Real> s = supports(true);
    damping_loss_ += grid_update(G_, GV_, q, own_, [&](int f, std::size_t b, std::size_t e) {
      apply_supports(G_, GV_, s, f, b, e);
    });
    mirror_ghost_velocities(true);
    collect_support_reactions();
  } else {
    damping_loss_ += grid_update(G_, GV_, q, own_);
  }
}

// The supports for this step (kernels/supports.hpp), applied by the node
// passes on the nodes each thread owns; with_dvel: the application after
// the momentum update, which records the reaction terms.
template <int D, class Shape, class Real>
Supports<Real> Stepper<D, Shape, Real>::supports(bool with_dvel) {
  for (std::size_t b = 0; b < boundaries_.size(); ++b) {
    // The pointers are set here, not once, so they follow the Stepper's
    // own vectors whatever happened to it since.
    const BoundaryNodes& bc = boundaries_[b];
    SupportView<Real>& v = support_views_[b];
    v.nodes = bc.nodes.data();
    v.count = bc.nodes.size();
    v.reaction_terms = support_terms_[b].data();
    const Vec3 vb = boundary_velocity(bc, time_, dt_);
    for (int d = 0; d < 3; ++d) v.fix[d] = bc.fix[d], v.velocity[d] = Real(vb[d]);
  }
  Supports<Real> s;
  s.list = support_views_.data();
  s.count = support_views_.size();
  s.rigid = plan_.rigid.data();
  s.mass_threshold = mass_threshold_;
  s.dt = dt_;
  s.with_dvel = with_dvel;
  if (with_dvel && !usl_light_threshold_.empty()) {
    s.light = usl_light_threshold_.data();
    for (int d = 0; d < 3; ++d) s.gravity[d] = Real(gravity_[std::size_t(d)]);
  }
  return s;
}

// The reactions (what a load cell would read) and the supports' work, from
// the terms the application after the momentum update wrote, plus what a
// mirror's image added to the body's nodes (fold_mirror).
template <int D, class Shape, class Real>
void Stepper<D, Shape, Real>::collect_support_reactions() {
  for (std::size_t b = 0; b < boundaries_.size(); ++b)
    boundary_reaction_[b] =
        sum_support_reaction<D>(support_views_[b], G_.fields, plan_.rigid.data());
  for (MirrorPlane& mp : mirrors_) {
    for (int d = 0; d < D; ++d) boundary_reaction_[mp.boundary][d] += mp.reaction[d];
    mp.reaction = {0, 0, 0};
  }
  for (std::size_t b = 0; b < boundaries_.size(); ++b) {
    const Vec3 vb = boundary_velocity(boundaries_[b], time_, dt_);
    for (int d = 0; d < D; ++d) external_work_ += boundary_reaction_[b][d] * vb[d] * dt_;
  }
}

// A support on a grid plane mirrors the body (kernels/mirror_supports.hpp)
// when it fixes its normal component, the particles within 2 cells of it
// (the splines' reach; all particles if none is that close) lie on one
// side of it, and the partner layer is in the grid. Decided once from the
// seeded particles, so a restart decides alike. Every shape: the splines
// always reach the layer behind the plane, and linear and uGIMP particles
// do once compression moves them (or their domains) past it; a compressed
// uGIMP bar read -2.80 and +0.97 t in its first rows with that layer free
// (docs/validation.md §3.7).
template <int D, class Shape, class Real>
void Stepper<D, Shape, Real>::setup_mirrors() {
  for (std::size_t b = 0; b < boundaries_.size(); ++b) {
    const BoundaryNodes& bc = boundaries_[b];
    // A plane that leaves its normal free lets the body leave it: an even
    // image would hold the normal strain at 0 there instead of the normal
    // stress, so it only fixes its nodes.
    const int ax = symmetry_axis(bc, D);
    if (ax < 0) continue;
    const double h = double(G_.h[ax]);
    const long plane = bc.plane_index;
    const double a = double(G_.origin[ax]) + double(plane) * h;
    // Which side the body is on: from the particles within reach of the
    // plane, or, with none there (a body that will fall onto it), from all.
    bool below = false, above = false, all_below = false, all_above = false;
    for (std::size_t p = 0; p < P_.n; ++p) {
      if (P_.field && plan_.rigid[P_.field[p]]) continue;
      const double x = double(P_.x[ax][p]);
      // A particle on the plane itself sides with neither.
      const bool on_below = x < a - 1e-9 * h;
      const bool on_above = x > a + 1e-9 * h;
      all_below = all_below || on_below;
      all_above = all_above || on_above;
      if (std::abs(x - a) >= 2.0 * h) continue;
      below = below || on_below;
      above = above || on_above;
    }
    if (!below && !above) below = all_below, above = all_above;
    if (below == above) continue;  // on both sides, or no particle at all
    const long side = above ? 1 : -1;
    const long ghost = plane - side, partner = plane + side;
    const long last = long(G_.nodes_per_dim[ax]) - 1;
    if (ghost < 0 || ghost > last || partner < 0 || partner > last) continue;
    MirrorPlane mp;
    mp.boundary = b;
    mp.axis = ax;
    mp.coordinate = a;
    const std::size_t stride =
        ax == 0   ? 1
        : ax == 1 ? std::size_t(G_.nodes_per_dim[0])
                  : std::size_t(G_.nodes_per_dim[0]) * std::size_t(G_.nodes_per_dim[1]);
    for (std::uint32_t n : bc.nodes) {
      mp.ghost.push_back(std::uint32_t(long(n) - side * long(stride)));
      mp.partner.push_back(std::uint32_t(long(n) + side * long(stride)));
    }
    mp.ghost_mass.assign(std::size_t(G_.fields) * mp.ghost.size(), Real(0));
    if (plan_.multimaterial) {
      if (mirror_side_.empty()) mirror_side_.assign(G_.nodes, 0);
      for (const std::uint32_t n : bc.nodes)
        mirror_side_[n] |= (unsigned char)(1u << (2 * ax + (side > 0 ? 0 : 1)));
    }
    mirrors_.push_back(std::move(mp));
  }
}

template <int D, class Shape, class Real>
MirrorView<Real> Stepper<D, Shape, Real>::mirror_view(MirrorPlane& mp) const {
  const BoundaryNodes& bc = boundaries_[mp.boundary];
  MirrorView<Real> v;
  v.plane = bc.nodes.data();
  v.ghost = mp.ghost.data();
  v.partner = mp.partner.data();
  v.count = mp.ghost.size();
  v.ghost_mass = mp.ghost_mass.data();
  const Vec3 vb = boundary_velocity(bc, time_, dt_);
  for (int d = 0; d < 3; ++d) v.fix[d] = bc.fix[d], v.velocity[d] = Real(vb[d]);
  return v;
}

// Each thread folds the entries whose partner it owns
// (kernels/mirror_supports.hpp), one mirror after the other: where two meet,
// the second folds what the first left at the corner. A rigid field folds
// its mass and momenta too: the contact laws read its p / m (its velocity),
// mx / m, Omega and g at the partners beside the deformable fields', which
// hold their images (docs/contact_validation.md §22: a rigid platen across
// the plane read the whole model's strain energy 0.4-1.8 % off without it).
template <int D, class Shape, class Real>
void Stepper<D, Shape, Real>::fold_mirrors(unsigned what, bool with_reaction) {
  const bool reaction = with_reaction && (what & kFoldForce);
  if (reaction)
    for (MirrorPlane& mp : mirrors_)
      mp.fold_terms.resize(mp.ghost.size() * std::size_t(G_.fields * D));
  team_run(G_.nodes * std::size_t(G_.fields) >= kParallelMinNodes, [&] {
    const auto [first, last] = own_.mine(G_.nodes);
    for (std::size_t i = 0; i < mirrors_.size(); ++i) {
      if (i > 0) team_barrier();
      MirrorPlane& mp = mirrors_[i];
      const MirrorView<Real> v = mirror_view(mp);
      for (int f = 0; f < G_.fields; ++f)
        if (!plan_.rigid[std::size_t(f)])
          fold_mirror(G_, v, f, what,
                      reaction ? mp.fold_terms.data() + std::size_t(f) * v.count * D : nullptr,
                      first, last);
        else  // its image too (no forces: the grid update sets its momenta)
          fold_mirror(G_, v, f, what & (kFoldMass | kFoldMomentum), nullptr, first, last);
    }
  });
  if (!reaction) return;
  for (MirrorPlane& mp : mirrors_) {
    const MirrorView<Real> v = mirror_view(mp);
    for (int f = 0; f < G_.fields; ++f)
      if (!plan_.rigid[std::size_t(f)])
        fold_reaction<D>(v, mp.fold_terms.data() + std::size_t(f) * v.count * D,
                         mp.reaction.data());
  }
}

// In the reverse order of the folds: where two mirrors meet, the ghost of
// the first (folded first) at the corner takes its velocity from a node in
// the second's ghost layer, which the second has just set. Each thread sets
// the ghosts it owns.
template <int D, class Shape, class Real>
void Stepper<D, Shape, Real>::mirror_ghost_velocities(bool with_dvel) {
  if (mirrors_.empty()) return;
  team_run(G_.nodes * std::size_t(G_.fields) >= kParallelMinNodes, [&] {
    const auto [first, last] = own_.mine(G_.nodes);
    for (std::size_t i = mirrors_.size(); i-- > 0;) {
      if (i + 1 < mirrors_.size()) team_barrier();
      const MirrorView<Real> v = mirror_view(mirrors_[i]);
      for (int f = 0; f < G_.fields; ++f)
        if (!plan_.rigid[std::size_t(f)]) mirror_velocities(G_, GV_, v, f, with_dvel, first, last);
    }
  });
}

// A rigid material does work on the bodies like a moving support: the force
// it exerts on them (minus the reaction the bodies exert on it, ALGORITHM §7)
// times the velocity it moved at this step.
template <int D, class Shape, class Real>
void Stepper<D, Shape, Real>::add_rigid_work() {
  for (int f = 0; f < plan_.fields; ++f) {
    if (plan_.rigid_material[std::size_t(f)] < 0) continue;
    const Vec3 r = mm_.rigid_reaction(f);
    for (int d = 0; d < D; ++d)
      external_work_ -= r[d] * rigid_velocity_now_[std::size_t(f) * 3 + std::size_t(d)] * dt_;
  }
}

// USL's light-node masses m_L (kernels/grid_update.hpp, update_deformable),
// per field; none in MUSL and USF. Every shape: 1e-6 of the lightest
// particle, the threshold below which the multimaterial pass already takes
// a field as empty (ALGORITHM §4.3); uGIMP's and the B-splines' feedback
// |grad S|^2 / S stays bounded as S -> 0 (docs/validation.md §3.5). Linear
// shapes also: 2 m_p (c_p dt / h)^2 over the field's particles p, because
// their feedback (c dt / h)^2 m_p / m grows without bound as a particle
// enters a cell (|grad S| = 1 / h while S -> 0): USL with linear shapes
// broke at every cell crossing (at cfl 0.5 the incline block and the
// rolling disk stopped with J <= 0 by step 400, the impact by step 100, a
// translating free bar at step 5072). With m_L a particle's feedback
// through a light node is at most (c dt / h)^2 (m_p / m_L) h^2 |grad S|^2
// = h^2 |grad S|^2 / 2 <= 1 (1.5 in 3D), summed over the particles that
// reach it; the factor 2 is measured: at 1, the incline block and a block
// on a slanted staircase still grew at cfl 0.7.
template <int D, class Shape, class Real>
void Stepper<D, Shape, Real>::set_usl_light_thresholds(const ParticleSeeds& seeds) {
  usl_light_threshold_.clear();
  if (scene_.simulation.scheme != Scheme::USL) return;
  usl_light_threshold_.assign(std::size_t(plan_.fields), min_particle_mass_ * kSliverMassFraction);
  if constexpr (std::is_same_v<Shape, LinearShape>) {
    double h = double(G_.h[0]);
    for (int d = 1; d < D; ++d) h = std::min(h, double(G_.h[d]));
    for (std::size_t p = 0; p < seeds.x.size(); ++p) {
      const auto material = std::size_t(seeds.material[p]);
      const double mass = materials_[material].density * seeds.volume[p];
      const double courant = dt_ * materials_[material].wave_speed / h;
      double& light = usl_light_threshold_[std::size_t(plan_.field_of_material[material])];
      light = std::max(light, 2.0 * mass * courant * courant);
    }
  }
}

template <int D, class Shape, class Real>
void Stepper<D, Shape, Real>::finish_velocities(bool with_dvel) {
  const Supports<Real> s = supports(with_dvel);
  auto hook = [&](int f, std::size_t b, std::size_t e) { apply_supports(G_, GV_, s, f, b, e); };
  if (with_dvel) {
    grid_velocities(G_, GV_, mass_threshold_, own_, hook);
    mirror_ghost_velocities(true);
    collect_support_reactions();
  } else {
    grid_momentum_velocities(G_, GV_, mass_threshold_, own_, hook);
    mirror_ghost_velocities(false);
  }
}

// XPIC(m) (kernels/xpic.hpp, docs/validation.md §3.12): v* = sum of the
// first m terms (I - A)^k v from the velocities v = p / m of this step's
// P2G. The particles' new velocities S v* + S (v_L - v) come out of the
// FLIP G2P itself: apply_xpic_shift adds v* to its increment and zeroes the
// deformable particles' velocities, which saves an interpolation. The
// interpolations and the scatter run on the team (the scatter colored, as
// every P2G: the same bits on 1 and 2 threads). p is put back as the P2G
// left it: the supports' application inside finish_velocities writes it,
// and the grid update's support reactions read the change they make.
template <int D, class Shape, class Real>
void Stepper<D, Shape, Real>::xpic_filter() {
  const std::size_t N = G_.nodes * std::size_t(G_.fields), n = P_.n;
  xpic_grid_.resize(4 * std::size_t(D) * N);
  xpic_particles_.resize(std::size_t(D) * n);
  std::array<Real*, D> saved, term, sum, q, w;
  for (int d = 0; d < D; ++d) {
    saved[d] = xpic_grid_.data() + std::size_t(d) * N;
    term[d] = xpic_grid_.data() + std::size_t(D + d) * N;
    sum[d] = xpic_grid_.data() + std::size_t(2 * D + d) * N;
    q[d] = xpic_grid_.data() + std::size_t(3 * D + d) * N;
    w[d] = xpic_particles_.data() + std::size_t(d) * n;
  }
  auto as_const = [](const std::array<Real*, D>& a) {
    std::array<const Real*, D> c;
    for (int d = 0; d < D; ++d) c[d] = a[d];
    return c;
  };
  // The node passes below visit the nodes of the grid passes (each field's
  // runs, kernels/active_nodes.hpp), each thread its own, as the grid
  // update does: a node's value does not depend on who computes it. The
  // scratch arrays outside the runs keep stale (finite) values, which no
  // particle reads: its window lies in its field's runs, and a window node
  // it does not reach has weight 0. The serial whole-grid loops were 4.4 %
  // of an XPIC(4) step on one thread (perf, the disks at h = 1/160, 192^2
  // nodes), besides their copies and fills, and did not gain from a second
  // thread.
  auto node_pass = [&](auto&& body) { team_own_nodes(own_, G_.nodes, G_.fields, body); };
  node_pass([&](std::size_t b, std::size_t e) {
    for (int d = 0; d < D; ++d) std::copy(G_.p[d] + b, G_.p[d] + e, saved[d] + b);
  });
  finish_velocities(false);  // v = p / m, the supports, the mirrors' ghosts
  node_pass([&](std::size_t b, std::size_t e) {
    for (int d = 0; d < D; ++d) {
      std::copy(GV_.vel[d] + b, GV_.vel[d] + e, term[d] + b);
      std::copy(GV_.vel[d] + b, GV_.vel[d] + e, sum[d] + b);
      std::fill(q[d] + b, q[d] + e, Real(0));  // the first scatter's; add_xpic_term re-zeroes it
    }
  });
  for (int k = 1; k < scene_.simulation.xpic_order; ++k) {
    // The interpolation writes each particle's own entries: on the team, in
    // the particle ranges of the uncolored loops.
    if (const std::size_t bad = first_stop_in_particle_ranges([&](std::size_t b, std::size_t e) {
          return interpolate_to_particles<D, Shape, Real>(P_, G_, as_const(term), w, b, e);
        });
        bad < n)
      fail_particle("xpic", bad, "its shape-function stencil left the grid");
    // The scatter of m_p w_p is the P2G of momenta (colored, MUSL's second
    // transfer's kernel) with the particles' velocities and the grid's
    // momenta pointing at the scratch arrays; the mirrors fold the image's
    // share in as they do the P2G's.
    std::swap(P_.v, w);
    std::swap(G_.p, q);
    p2g<kMomentumOnly>("xpic");
    if (!mirrors_.empty()) fold_mirrors(kFoldMomentum, false);
    std::swap(P_.v, w);
    std::swap(G_.p, q);
    node_pass([&](std::size_t b, std::size_t e) {
      add_xpic_term<D, Real>(G_.m, q, term, sum, mass_threshold_, b, e);
    });
    // The folds left the ghost layer's mass at the partners, so the new
    // term is 0 there: give the ghosts their partners' reflected values,
    // which the next interpolation reads (as the whole body's would).
    if (!mirrors_.empty() && k + 1 < scene_.simulation.xpic_order) {
      std::swap(GV_.vel, term);
      mirror_ghost_velocities(false);
      std::swap(GV_.vel, term);
    }
  }
  // v* with the supports and the mirrors' ghosts, as the velocities of
  // momenta m v*; it waits in `term` for apply_xpic_shift.
  node_pass([&](std::size_t b, std::size_t e) {
    for (int d = 0; d < D; ++d)
      for (std::size_t i = b; i < e; ++i) G_.p[d][i] = G_.m[i] * sum[d][i];
  });
  finish_velocities(false);
  node_pass([&](std::size_t b, std::size_t e) {
    for (int d = 0; d < D; ++d) {
      std::copy(GV_.vel[d] + b, GV_.vel[d] + e, term[d] + b);
      std::copy(saved[d] + b, saved[d] + e, G_.p[d] + b);
    }
  });
}

template <int D, class Shape, class Real>
template <class RangeFn>
std::size_t Stepper<D, Shape, Real>::first_stop_in_particle_ranges(RangeFn&& fn) {
  std::atomic<std::size_t> first{SIZE_MAX};
  team_run(particles_on_team(), [&] {
    const TileSchedule::Ranges mine = my_particles();
    std::size_t stop = SIZE_MAX;
    for (std::size_t r = 0; r < mine.count; ++r) {
      const auto [b, e] = mine.range[r];
      if (const std::size_t s = fn(b, e); s < e) stop = std::min(stop, s);
    }
    offer_min(first, stop);
  });
  return first.load();
}

// Whether the separation reads the shifted displacement of
// kernels/separation_shift.hpp: MUSL (its strain reads v*, its particles
// move with v^L) with some FLIP in the particle velocities (pure PIC's own
// dissipation removes the growth the shift cures: the bars of Finding 14
// keep 0.000 E0 after 3 ms, and the shift only cost it accuracy, a wave
// through Dn = 1000 2.20 -> 2.63 %), and interface springs that read
// displacements (a perfect interface has none; the position method reads
// x), every one of them under the paper's explicit force limit or the exact
// integration (§4.5, whose stick above θ = 1.5 does the limit's job). Why
// the limit: where a field is a sliver at an interface node its spring is
// beyond the explicit bound at any D (docs/multimaterial.md §8), and only
// the limit holds it once the opening no longer follows the particles'
// own moves: two_layer.toml without the limit at 0.35x the bound read
// (K + U + U_int + damping) / W = 1.12 at 1 ms with the shift, 1.007
// without it; with the limit 1.008 (docs/interface_validation.md Finding 14).
// The exact spring without the shift grows as the explicit one does without
// the limit: the bars of Finding 14 read 3.11 E0 at 3 ms, 1.004 with it
// (Finding 15).
template <int D, class Shape, class Real>
bool Stepper<D, Shape, Real>::shifts_separation() const {
  if (scene_.simulation.scheme != Scheme::MUSL || !(scene_.simulation.flip > 0)) return false;
  bool springs = false, all_limited = true;
  for (const auto& i : scene_.interactions) {
    if (!has_displacement_spring(i)) continue;
    springs = true;
    all_limited = all_limited && (i.integration == Integration::exact || i.force_limit);
  }
  return springs && all_limited;
}

// Right before the step's G2P (kernels/xpic.hpp): the FLIP increment
// v_L - v takes v* more, and the deformable particles start from 0, so the
// G2P gives them S (v* + v_L - v) (with flip < 1, blended with PIC's
// S v_L). Rigid particles take their prescribed motion in the G2P whatever
// they held.
template <int D, class Shape, class Real>
void Stepper<D, Shape, Real>::apply_xpic_shift() {
  const std::size_t N = G_.nodes * std::size_t(G_.fields);
  const Real* v_star = xpic_grid_.data() + std::size_t(D) * N;
  team_own_nodes(own_, G_.nodes, G_.fields, [&](std::size_t b, std::size_t e) {
    for (int d = 0; d < D; ++d)
      for (std::size_t i = b; i < e; ++i) GV_.dvel[d][i] += v_star[std::size_t(d) * N + i];
  });
  team_run(particles_on_team(), [&] {
    const TileSchedule::Ranges mine = my_particles();
    for (std::size_t r = 0; r < mine.count; ++r)
      for (std::size_t p = mine.range[r].first; p < mine.range[r].second; ++p)
        if (!P_.field || !plan_.rigid[P_.field[p]])
          for (int d = 0; d < D; ++d) P_.v[d][p] = Real(0);
  });
}

template <int D, class Shape, class Real>
void Stepper<D, Shape, Real>::update_tractions() {
  // Only while a ramp runs: the force is constant afterwards.
  if (!has_traction_) return;
  if (time_ > traction_ramp_end_ + dt_ && step_ > 1) return;
  const std::uint8_t* load = pcols_.byte("load");
  Real* base[3] = {pcols_.real("fbasex"), pcols_.real("fbasey"),
                   D == 3 ? pcols_.real("fbasez") : nullptr};
  std::vector<Real> scale(scene_.loads.size() + 1, Real(0));
  for (std::size_t l = 0; l < scene_.loads.size(); ++l) {
    const double r = scene_.loads[l].ramp;
    // Force at mid-step, so the impulse over the ramp is exact.
    const double tm = time_ + 0.5 * dt_;
    scale[l] = Real(ramp_fraction(tm, r));
  }
  team_run(particles_on_team(), [&] {
    const TileSchedule::Ranges mine = my_particles();
    for (std::size_t r = 0; r < mine.count; ++r)
      for (std::size_t p = mine.range[r].first; p < mine.range[r].second; ++p) {
        const Real s = load[p] == 255 ? Real(0) : scale[load[p]];
        for (int d = 0; d < D; ++d) P_.fext[d][p] = s * base[d][p];
      }
  });
}

template <int D, class Shape, class Real>
void Stepper<D, Shape, Real>::step() {
  const Scheme scheme = scene_.simulation.scheme;
  const bool mm = plan_.multimaterial;
  grid_ke_from_tail_ = false;
  for (int f = 0; f < plan_.fields; ++f) {
    const int m = plan_.rigid_material[std::size_t(f)];
    if (m < 0) continue;
    const Vec3 v = rigid_velocity(scene_.materials[std::size_t(m)], time_ + dt_);
    for (int d = 0; d < 3; ++d) rigid_velocity_now_[std::size_t(f) * 3 + std::size_t(d)] = v[d];
  }
  if (has_gravity_) {
    // Gravity at mid-step, ramped linearly when the load has a ramp.
    gravity_ = {0, 0, 0};
    for (const auto& l : scene_.loads) {
      if (l.kind != LoadKind::gravity) continue;
      const double f = ramp_fraction(time_ + 0.5 * dt_, l.ramp);
      for (int d = 0; d < D; ++d) gravity_[d] += f * l.acceleration[d];
    }
  }
  tic();
  const int every = scene_.simulation.sort_every;
  if (dirty_ || (every > 0 && step_ % every == 0)) sort_particles();  // clears grid_ready_
  update_node_ownership(false);
  update_tractions();
  toc(kStageSort);

  // The last step's fused tail has done this P2G already, unless the
  // particles were re-sorted since (fused_step_tail; it timed its P2G).
  if (grid_ready_) {
    grid_ready_ = false;
    ++p2g_from_tail_;
  } else {
    tic();
    zero_grid(mm);
    // mx, Omega, g with this P2G only when p2g_multimaterial chose so.
    const bool with_mm = mm && mm_fields_with_p2g_;
    if (scheme == Scheme::USF) {
      if (with_mm)
        p2g<kMassMomentum | kMultimaterial>("p2g");
      else
        p2g<kMassMomentum>("p2g");
    } else {
      if (with_mm)
        p2g<kMassMomentum | kForce | kMultimaterial>("p2g");
      else
        p2g<kMassMomentum | kForce>("p2g");
    }
    toc(kStageP2G);
  }
  // The image's mass and momenta (and USL's forces) before anything reads them.
  if (!mirrors_.empty()) {
    tic();
    fold_mirrors(kFoldMass | kFoldMomentum | kFoldForce, true);
    toc_time(kStageGrid);
  }
  if (scene_.simulation.xpic_order > 0) {
    tic();
    xpic_filter();
    toc_time(kStageG2P);
  }

  if (mm) {
    tic();
    mm_.find_nodes(G_, own_, &mixed_tiles_);
    toc(kStageMultimaterial);
    tic();
    p2g_multimaterial();
    toc(kStageP2G);
    tic();
    if (!geometry_fields_.empty()) {
      move_rigid_shapes(geometry_fields_, scene_, time_);
      fit_body_motions(geometry_fields_, P_, pcols_.id.data(), P_.n, body_of_id_,
                       scene_.bodies.size());
      double cell = 0;
      for (int d = 0; d < D; ++d) cell = std::max(cell, double(G_.h[d]));
      orient_gradients(G_, mm_.nodes(), geometry_fields_, geometry_pairs_, 0.5 * Shape::S * cell);
    }
    if (!plane_axes_.empty())
      drop_gradients_across_planes(G_, mm_.nodes().data(), mm_.nodes().size(), plane_axes_.data(),
                                   mirror_side_.empty() ? nullptr : mirror_side_.data());
    mm_.pass_a(G_, dt_, regular_dt_, own_);  // 0: decide for dt_
    toc(kStageMultimaterial);
  }

  if (scheme == Scheme::USF) {
    // Stress first, from the velocities of the extrapolated momenta.
    tic();
    finish_velocities(false);
    toc(kStageGrid);
    // The face loads' work at the velocities this strain reads, as MUSL's
    // (docs/validation.md §3.13): the updated grid velocity of a light node
    // past a loaded face, which the particles do not take, read 9-13 % of
    // extra work in the two-layer and double-lap-shear scenes with uGIMP.
    add_face_traction_work();
    gradient_and_stress<0>();
    tic();
    p2g<kForce>("p2g");
    toc(kStageP2G);
  }

  if (has_traction_) {  // part of the P2G stage's time, not a pass of its own
    tic();
    apply_face_tractions(G_);
    toc_time(kStageP2G);
  }
  tic();
  // The forces added since the first fold (USF's P2G, the loads); without
  // them the fold would only move the zeros the first one left.
  if (!mirrors_.empty() && (scheme == Scheme::USF || has_traction_)) fold_mirrors(kFoldForce, true);
  grid_update_stage();
  toc(kStageGrid);
  if (mm) {
    tic();
    mm_.set_light_step(gravity_, GV_.dvel);
    mm_.pass_b(G_, own_);
    add_rigid_work();
    toc(kStageMultimaterial);
  }
  if (mm) {  // else grid_update_stage set the velocities
    tic();
    finish_velocities(true);
    toc(kStageGrid);
  }

  if (scheme == Scheme::USL) add_face_traction_work();
  if (scene_.simulation.xpic_order > 0) {
    tic();
    apply_xpic_shift();
    toc_time(kStageG2P);
  }
  if (scheme == Scheme::USL) {
    gradient_and_stress<kUpdateMotion>();
  } else if (scheme == Scheme::USF) {
    tic();
    g2p<kUpdateMotion>();
    toc(kStageG2P);
  } else {  // MUSL: the gradient from the momenta of the updated particles
    // Two fused passes (kernels/g2p.hpp): (1) G2P of the updated grid
    // velocity and P2G of the new particle momenta with the same weights,
    // (2) G2P of the velocity gradient, which then moves the particles.
    // Both use the step's starting positions (Sulsky's MUSL).
    tic();
    for (int d = 0; d < D; ++d) {
      if (x_next_[d].size() != P_.n) x_next_[d].allocate(P_.n, pcols_.next_slot++);
      P_.x_next[d] = x_next_[d].data();
    }
    std::array<Real*, D> momenta;
    for (int d = 0; d < D; ++d) momenta[std::size_t(d)] = G_.p[d];
    zero_owned(own_, G_.nodes, G_.fields, momenta);
    g2p_colored<kUpdateMotion | kScatterMomentum>();
    toc(kStageG2P);
    if (!mirrors_.empty()) {
      tic();
      fold_mirrors(kFoldMomentum, false);
      toc_time(kStageGrid);
    }
    if (mm) {
      tic();
      mm_.pass_b(G_, own_, PassB::strain);
      toc(kStageMultimaterial);
    }
    tic();
    finish_velocities(false);
    toc(kStageGrid);
    // MUSL's strain comes from these re-extrapolated velocities; the first
    // update's can keep a node motion the particles do not take (a static
    // bar's loaded node moved on, and that work drifted by 8 %). The
    // gradient pass below also advances the separation shift from them
    // (kSeparationShift, where shifts_separation()).
    add_face_traction_work();
    if (step_tail_fusable())
      fused_step_tail();
    else
      gradient_and_stress<kCommitPosition>();
    for (int d = 0; d < D; ++d) P_.x_next[d] = nullptr;
  }
  time_ += dt_;
  ++step_;
}

// Every stage reads dt_ when it runs and keeps nothing that depends on it
// for the next step (the multimaterial pass takes it per call, the fused
// tail's P2G does not use it), so one shortened step needs no other state.
// One exception, on purpose: the multimaterial pass decides which interface
// directions stick for the regular step (regular_dt_, MMConfig::limit_dt),
// so the last row does not depend on how short the last step is.
// time_ + (t_end - time_) is t_end exactly: the difference is exact
// (Sterbenz) once time_ is within a step of t_end, and so is the sum.
template <int D, class Shape, class Real>
void Stepper<D, Shape, Real>::step_within(double t_end) {
  const double left = t_end - time_;
  if (!(left > 0 && left < dt_)) return step();
  const double regular = dt_;
  dt_ = left;
  regular_dt_ = regular;
  try {
    step();
  } catch (...) {
    dt_ = regular;
    regular_dt_ = 0;
    throw;
  }
  dt_ = regular;
  regular_dt_ = 0;
}

template <int D, class Shape, class Real>
void Stepper<D, Shape, Real>::fail_particle(const char* stage, std::size_t p,
                                            const std::string& why) const {
  std::ostringstream os;
  // The seed index: the particle's row in the outputs (p is where the sorts put it).
  os << "unstable: stage " << stage << ", step " << step_ << ", particle " << pcols_.id[p]
     << " (material '" << materials_[P_.mat[p]].name << "', x = [";
  for (int d = 0; d < D; ++d) os << (d ? ", " : "") << double(P_.x[d][p]);
  os << "]): " << why;
  throw SimulationError(os.str());
}

template <int D, class Shape, class Real>
void Stepper<D, Shape, Real>::fail_at_fastest_particle(const char* stage,
                                                       const std::string& why) const {
  std::size_t fastest = SIZE_MAX;
  double v2_max = -1;
  for (std::size_t p = 0; p < P_.n; ++p) {
    if (materials_[P_.mat[p]].rigid()) continue;
    double v2 = 0;
    for (int d = 0; d < D; ++d) v2 += double(P_.v[d][p]) * double(P_.v[d][p]);
    if (!std::isfinite(v2)) {
      fastest = p;
      v2_max = v2;
      break;
    }
    if (v2 > v2_max) fastest = p, v2_max = v2;
  }
  if (fastest == SIZE_MAX)
    throw SimulationError("unstable: stage " + std::string(stage) + ", step " +
                          std::to_string(step_) + ": " + why);
  std::ostringstream m;
  m.precision(4);
  m << why
    << "; no particle check tripped: this is the fastest particle, |v| = " << std::sqrt(v2_max);
  fail_particle(stage, fastest, m.str());
}

template <int D, class Shape, class Real>
Energies Stepper<D, Shape, Real>::energies() const {
  Energies e;
  const std::size_t n = P_.n;
  // Per material, what the particle loop reads, in a compact table. In 2D
  // the stress has the Voigt components xx, yy, zz, xy (0, 1, 2, 5): yz and
  // xz are 0, so s C s runs over the 4 x 4 block of those four instead of
  // all 36 entries. The terms left out were exactly +-0 and the others are
  // added in the same order, so the sum keeps its bits. Why: with a series
  // row every step the old loop cost 11 ns/particle per row, half of a 2D
  // linear step (docs/performance.md "The energies of a series row").
  using Map = StressVoigt<D>;
  constexpr int NV = Map::count;
  enum class Kind : unsigned char { rigid, small_strain, finite_strain };
  struct EnergyMaterial {
    double c[NV][NV];  // compliance over the components of Map
    double mu, lambda, density;
    Kind kind;
  };
  std::vector<EnergyMaterial> table(materials_.size());
  for (std::size_t k = 0; k < materials_.size(); ++k) {
    const MaterialModel& mat = materials_[k];
    EnergyMaterial& t = table[k];
    for (int i = 0; i < NV; ++i)
      for (int j = 0; j < NV; ++j)
        t.c[i][j] = mat.compliance[Map::voigt[std::size_t(i)]][Map::voigt[std::size_t(j)]];
    t.mu = mat.k.mu, t.lambda = mat.k.lambda, t.density = mat.density;
    t.kind = mat.rigid()           ? Kind::rigid
             : mat.finite_strain() ? Kind::finite_strain
                                   : Kind::small_strain;
  }
  const EnergyMaterial* const mats = table.data();
  auto parts =
      deterministic_sum<2>(n, [&](std::size_t b, std::size_t end, std::array<double, 2>& acc) {
        for (std::size_t p = b; p < end; ++p) {
          // A rigid material's motion is prescribed, not part of the
          // system's energy: its work on the bodies is external work
          // (add_rigid_work), and its nominal mass carries no kinetic energy.
          const EnergyMaterial& mat = mats[P_.mat[p]];
          if (mat.kind == Kind::rigid) continue;
          double v2 = 0;
          for (int d = 0; d < D; ++d) v2 += double(P_.v[d][p]) * double(P_.v[d][p]);
          acc[0] += 0.5 * double(P_.m[p]) * v2;
          if (mat.kind == Kind::finite_strain) {
            double F[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
            for (int i = 0; i < D; ++i)
              for (int j = 0; j < D; ++j) F[i * 3 + j] += double(P_.H[i * D + j][p]);
            const double J = F[0] * (F[4] * F[8] - F[5] * F[7]) -
                             F[1] * (F[3] * F[8] - F[5] * F[6]) +
                             F[2] * (F[3] * F[7] - F[4] * F[6]);
            double I1 = 0;
            for (int c = 0; c < 9; ++c) I1 += F[c] * F[c];
            const double lnJ = std::log(J), V0 = double(P_.m[p]) / mat.density;
            acc[1] += V0 * (0.5 * mat.mu * (I1 - 3 - 2 * lnJ) + 0.5 * mat.lambda * lnJ * lnJ);
          } else {
            double s[NV];
            for (int i = 0; i < NV; ++i) s[i] = double(P_.s[Map::column[std::size_t(i)]][p]);
            double u = 0;
            for (int i = 0; i < NV; ++i)
              for (int j = 0; j < NV; ++j) u += s[i] * mat.c[i][j] * s[j];
            acc[1] += 0.5 * u * double(P_.V[p]);
          }
        }
      });
  e.kinetic = parts[0];
  e.strain = parts[1];
  e.interface = mm_.interface_energy();
  e.external_work = external_work_;
  e.damping = damping_loss_;
  // m holds the next step's P2G after a fused tail, which kept the sum.
  // (Not grid_ready_: a tail that skipped some tiles' P2G leaves m partly
  // overwritten and grid_ready_ false; the sum over that m made
  // kinetic_unresolved jump about in contact scenes.)
  const double grid_ke = grid_ke_from_tail_ ? grid_ke_ : grid_kinetic_energy();
  e.kinetic_unresolved = step_ > 0 ? e.kinetic - grid_ke : 0.0;
  return e;
}

template <int D, class Shape, class Real>
std::vector<Reaction> Stepper<D, Shape, Real>::reactions() const {
  std::vector<Reaction> out;
  for (std::size_t b = 0; b < boundaries_.size(); ++b)
    out.push_back({boundaries_[b].label, boundary_reaction_[b]});
  for (int f = 0; f < plan_.fields; ++f) {
    const int m = plan_.rigid_material[std::size_t(f)];
    if (m >= 0)
      out.push_back({"rigid:" + scene_.materials[std::size_t(m)].name, mm_.rigid_reaction(f)});
  }
  return out;
}

template <int D, class Shape, class Real>
io::ParticleField Stepper<D, Shape, Real>::particle_field(const std::string& name) const {
  const std::size_t n = P_.n;
  // Rows in seed order (id), so a particle keeps its row from snapshot to
  // snapshot whatever order the sorts leave the columns in.
  const std::uint32_t* row = pcols_.id.data();
  io::ParticleField out{name, 1, {}};
  // plus: xlo, the part of the position x does not hold (float only).
  auto vec = [&](const std::array<Real*, D>& a, const std::array<Real*, D>* minus,
                 const std::array<Real*, D>& plus) {
    out.components = D;
    out.values.resize(n * D);
    for (std::size_t p = 0; p < n; ++p)
      for (int d = 0; d < D; ++d) {
        // No + 0.0 where there is no term: it would turn a -0 into +0.
        double value = double(a[d][p]);
        if (minus) value -= double((*minus)[d][p]);
        if (plus[0]) value += double(plus[d][p]);
        out.values[row[p] * D + std::size_t(d)] = value;
      }
  };
  if (name == "position") {
    vec(P_.x, nullptr, P_.xlo);
  } else if (name == "displacement") {
    vec(P_.x, &P_.x0, P_.xlo);
  } else if (name == "velocity") {
    vec(P_.v, nullptr, {});
  } else if (name == "stress") {
    out.components = NS;
    out.values.resize(n * NS);
    for (std::size_t p = 0; p < n; ++p)
      for (int c = 0; c < NS; ++c) out.values[row[p] * NS + std::size_t(c)] = double(P_.s[c][p]);
  } else if (name == "strain") {
    // Small-strain materials: eps = S sigma (tensor components, as the
    // stress); finite-strain ones: Green-Lagrange E = (F^T F - I) / 2.
    out.components = NS;
    out.values.resize(n * NS);
    for (std::size_t p = 0; p < n; ++p) {
      const MaterialModel& mat = materials_[P_.mat[p]];
      double e[6] = {0, 0, 0, 0, 0, 0};  // Voigt xx yy zz yz xz xy, tensor shear
      if (mat.finite_strain()) {
        double F[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
        for (int i = 0; i < D; ++i)
          for (int j = 0; j < D; ++j) F[i * 3 + j] += double(P_.H[i * D + j][p]);
        auto C = [&](int i, int j) {
          return F[i] * F[j] + F[3 + i] * F[3 + j] + F[6 + i] * F[6 + j];
        };
        e[0] = 0.5 * (C(0, 0) - 1), e[1] = 0.5 * (C(1, 1) - 1), e[2] = 0.5 * (C(2, 2) - 1);
        e[3] = 0.5 * C(1, 2), e[4] = 0.5 * C(0, 2), e[5] = 0.5 * C(0, 1);
      } else if (!mat.rigid()) {
        double sv[6] = {0, 0, 0, 0, 0, 0};
        using Map = StressVoigt<D>;
        for (int i = 0; i < Map::count; ++i)
          sv[Map::voigt[std::size_t(i)]] = double(P_.s[Map::column[std::size_t(i)]][p]);
        for (int i = 0; i < 6; ++i) {
          for (int j = 0; j < 6; ++j) e[i] += mat.compliance[i][j] * sv[j];
          if (i >= 3) e[i] *= 0.5;
        }
      }
      double* o = &out.values[row[p] * NS];
      if constexpr (D == 2) {
        o[0] = e[0], o[1] = e[1], o[2] = e[5], o[3] = e[2];
      } else {
        for (int c = 0; c < 6; ++c) o[c] = e[c];
      }
    }
  } else if (name == "deformation_gradient") {
    if (!P_.H[0])
      throw InputError(
          "output field 'deformation_gradient' needs a finite-strain (neohookean) material");
    out.components = D * D;
    out.values.resize(n * D * D);
    for (std::size_t p = 0; p < n; ++p)
      for (int c = 0; c < D * D; ++c)
        out.values[row[p] * D * D + std::size_t(c)] =
            double(P_.H[c][p]) + ((c % (D + 1)) == 0 ? 1.0 : 0.0);  // F = I + H
  } else if (name == "body") {
    out.values.resize(n);
    const std::uint8_t* body = pcols_.byte("body");
    for (std::size_t p = 0; p < n; ++p) out.values[row[p]] = double(body[p]);
  } else if (name == "material" || name == "mass" || name == "volume") {
    out.values.resize(n);
    for (std::size_t p = 0; p < n; ++p)
      out.values[row[p]] = name == "material"
                               ? double(P_.mat[p])
                               : (name == "mass" ? double(P_.m[p]) : double(P_.V[p]));
  } else {
    throw InputError("output field '" + name +
                     "' is unknown (position, displacement, velocity, stress, strain, "
                     "material, body, mass, volume, deformation_gradient)");
  }
  return out;
}

template <int D, class Shape, class Real>
void Stepper<D, Shape, Real>::set_particle_field(const std::string& name,
                                                 const std::vector<double>& values) {
  if (name != "velocity" || values.size() != P_.n * D)
    throw std::invalid_argument("set_particle_field: only 'velocity' with D values per particle");
  const std::uint32_t* row = pcols_.id.data();  // values in seed order, as particle_field
  for (std::size_t p = 0; p < P_.n; ++p)
    for (int d = 0; d < D; ++d) P_.v[d][p] = Real(values[row[p] * D + std::size_t(d)]);
  grid_ready_ = false;  // a fused tail scattered the old momenta
}

template <int D, class Shape, class Real>
io::Snapshot Stepper<D, Shape, Real>::snapshot(const std::vector<std::string>& fields) const {
  io::Snapshot s;
  s.step = step_;
  s.time = time_;
  s.dimension = D;
  s.count = P_.n;
  s.position = particle_field("position").values;
  for (const auto& f : fields)
    if (f != "position") s.fields.push_back(particle_field(f));
  return s;
}

// A scatter of its own (the reference pointwise kernel, one thread) into
// arrays of its own: between steps the solver's grid holds the last step's
// values or, after MUSL's fused tail, the next step's P2G only on the nodes
// that step will use, so it is not what the particles say now. Output only:
// the cost is one serial P2G per snapshot.
template <int D, class Shape, class Real>
io::GridSnapshot Stepper<D, Shape, Real>::grid_snapshot(
    const std::vector<std::string>& quantities) const {
  io::GridSnapshot out;
  if (quantities.empty()) return out;
  for (int d = 0; d < D; ++d) {
    out.nodes[std::size_t(d)] = G_.nodes_per_dim[std::size_t(d)];
    out.origin[std::size_t(d)] = scene_.grid.origin[std::size_t(d)];
    out.spacing[std::size_t(d)] = scene_.grid.cell[std::size_t(d)];
  }
  const std::size_t N = G_.nodes, F = std::size_t(plan_.fields);
  std::vector<Real> m(N * F, Real(0));
  std::array<std::vector<Real>, D> p, f;
  GridView<D, Real> g;
  g.nodes_per_dim = G_.nodes_per_dim;
  g.h = G_.h;
  g.origin = G_.origin;
  g.nodes = N;
  g.fields = plan_.fields;
  g.m = m.data();
  for (int d = 0; d < D; ++d) {
    p[std::size_t(d)].assign(N * F, Real(0));
    f[std::size_t(d)].assign(N * F, Real(0));
    g.p[std::size_t(d)] = p[std::size_t(d)].data();
    g.f[std::size_t(d)] = f[std::size_t(d)].data();
  }
  constexpr unsigned What = kMassMomentum | kForce;
  const P2GOptions opt = p2g_options();
  const bool multi = F > 1;
  std::size_t bad = 0;
  if (multi)
    bad = p2g_range_pointwise<D, Shape, Real, What, true, false>(P_, g, opt, 0, P_.n);
  else
    bad = p2g_range_pointwise<D, Shape, Real, What, false, false>(P_, g, opt, 0, P_.n);
  if (bad != P_.n) fail_particle("output", bad, "its shape-function stencil left the grid");
  apply_face_tractions(g);

  // A field's name in dataset names: its material's, when it has one
  // material with a plain name, else field<k>.
  std::vector<std::string> label(F);
  for (std::size_t k = 0; k < F; ++k) {
    const std::vector<std::size_t> of = materials_in_field(plan_, int(k));
    const std::string& name = of.size() == 1 ? materials_[of[0]].name : std::string();
    const bool plain = !name.empty() && std::all_of(name.begin(), name.end(), [](char c) {
      return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-';
    });
    label[k] = plain ? name : "field" + std::to_string(k);
  }
  // One quantity over the fields [k0, k1): the sum (velocity: of the
  // momenta over the sum of the masses, 0 where that is a sliver).
  auto quantity = [&](const std::string& q, std::size_t k0, std::size_t k1, std::string name) {
    const int C = q == "mass" ? 1 : D;
    io::ParticleField out_f{std::move(name), C, std::vector<double>(N * std::size_t(C), 0.0)};
    for (std::size_t n = 0; n < N; ++n) {
      double mass = 0, mom[3] = {0, 0, 0}, force[3] = {0, 0, 0};
      for (std::size_t k = k0; k < k1; ++k) {
        mass += double(m[k * N + n]);
        for (int d = 0; d < D; ++d) {
          mom[d] += double(p[std::size_t(d)][k * N + n]);
          force[d] += double(f[std::size_t(d)][k * N + n]);
        }
      }
      double* v = &out_f.values[n * std::size_t(C)];
      if (q == "mass") {
        v[0] = mass;
      } else {
        const bool heavy = mass > double(mass_threshold_);
        for (int d = 0; d < D; ++d)
          v[d] = q == "momentum" ? mom[d] : q == "force" ? force[d] : (heavy ? mom[d] / mass : 0.0);
      }
    }
    return out_f;
  };
  for (const std::string& q : quantities) {
    out.fields.push_back(quantity(q, 0, F, q));
    if (multi)
      for (std::size_t k = 0; k < F; ++k)
        out.fields.push_back(quantity(q, k, k + 1, q + "." + label[k]));
  }
  return out;
}

template <int D, class Shape, class Real>
std::vector<io::Blob> Stepper<D, Shape, Real>::save_state() const {
  std::vector<io::Blob> out;
  const std::size_t n = P_.n;
  for (std::size_t c = 0; c < pcols_.reals.size(); ++c)
    out.push_back(
        io::make_blob("p." + pcols_.real_names[c],
                      std::vector<Real>(pcols_.reals[c].data(), pcols_.reals[c].data() + n)));
  for (std::size_t c = 0; c < pcols_.bytes.size(); ++c)
    out.push_back(io::make_blob(
        "b." + pcols_.byte_names[c],
        std::vector<std::uint8_t>(pcols_.bytes[c].data(), pcols_.bytes[c].data() + n)));
  out.push_back(io::make_blob("key", std::vector<std::uint32_t>(P_.key, P_.key + n)));
  out.push_back(
      io::make_blob("id", std::vector<std::uint32_t>(pcols_.id.data(), pcols_.id.data() + n)));
  out.push_back(io::make_scalar_blob("step", step_));
  out.push_back(io::make_scalar_blob("time", time_));
  out.push_back(io::make_scalar_blob("external_work", external_work_));
  out.push_back(io::make_scalar_blob("damping_loss", damping_loss_));
  out.push_back(io::make_scalar_blob("dirty", int(dirty_)));
  out.push_back(io::make_scalar_blob("interface_energy", mm_.interface_energy()));
  mm_.save_state(out);
  return out;
}

template <int D, class Shape, class Real>
void Stepper<D, Shape, Real>::load_state(const std::vector<io::Blob>& blobs) {
  const std::size_t n = P_.n;
  auto load_column = [&](const std::string& name, auto* dst) {
    using T = std::remove_pointer_t<decltype(dst)>;
    std::vector<T> v;
    io::read_blob(io::find_blob(blobs, name), v);
    if (v.size() != n)
      throw std::runtime_error("checkpoint does not match the scene: column " + name);
    std::memcpy(dst, v.data(), n * sizeof(T));
  };
  for (std::size_t c = 0; c < pcols_.reals.size(); ++c)
    load_column("p." + pcols_.real_names[c], const_cast<Real*>(pcols_.reals[c].data()));
  for (std::size_t c = 0; c < pcols_.bytes.size(); ++c)
    load_column("b." + pcols_.byte_names[c], const_cast<std::uint8_t*>(pcols_.bytes[c].data()));
  load_column("key", P_.key);
  load_column("id", pcols_.id.data());
  step_ = io::read_scalar_blob<long>(io::find_blob(blobs, "step"));
  time_ = io::read_scalar_blob<double>(io::find_blob(blobs, "time"));
  external_work_ = io::read_scalar_blob<double>(io::find_blob(blobs, "external_work"));
  loaded_stale_ = true;
  damping_loss_ = io::read_scalar_blob<double>(io::find_blob(blobs, "damping_loss"));
  dirty_ = io::read_scalar_blob<int>(io::find_blob(blobs, "dirty")) != 0;
  grid_ready_ = false;  // the grid is not in the checkpoint: the next step scatters it again
  grid_ke_from_tail_ = false;
  mm_.set_interface_energy(io::read_scalar_blob<double>(io::find_blob(blobs, "interface_energy")));
  mm_.load_state(blobs);
  rebuild_ranges();
}

}  // namespace mmpm
