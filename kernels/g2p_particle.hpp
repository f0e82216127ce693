// One particle's side of G2P (ALGORITHM §2 step 6), shared by the
// one-particle gather (kernels/g2p.hpp) and the packed 2D linear one
// (kernels/g2p_packed.hpp): what a pass computes, and the particle's update
// from the grid velocity, velocity change and velocity gradient gathered
// for it.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "kernels/particle_prefetch.hpp"
#include "kernels/particle_view.hpp"
#include "kernels/position_sum.hpp"

namespace mmpm {

enum G2PWhat : unsigned {
  kUpdateMotion = 1u,      // v and x (x_next under MUSL)
  kVelocityGradient = 2u,  // L = sum v_i (x) G_ip
  // MUSL's fused passes (Stepper::step): the new particle momentum m v goes
  // straight back to the grid momentum with the same weights (the second
  // transfer), so the caller must run tiles color by color like P2G; and
  // the velocity-gradient pass moves x to x_next when it is done with x.
  kScatterMomentum = 4u,
  kCommitPosition = 8u,
  // With kVelocityGradient: the constitutive update of each particle right
  // after its L (the StressFn argument), instead of a pass of its own.
  kStressUpdate = 16u,
  // With kCommitPosition (MUSL's gradient pass, which gathers from v*):
  // the separation shift of kernels/separation_shift.hpp takes
  // dt S v* - (x_next - x) right before the commit, from the same weights
  // and the same gathered sum S v* the gradient's sums come with.
  kSeparationShift = 32u,
};

// The particle columns a G2P pass of `what` streams (kernels/particle_prefetch.hpp).
constexpr unsigned g2p_streams(unsigned what) {
  return ((what & kUpdateMotion) ? unsigned(kStreamMotion) : 0u) |
         ((what & kScatterMomentum) ? unsigned(kStreamMomentum) : 0u) |
         ((what & kVelocityGradient) ? unsigned(kStreamGradient) : 0u) |
         ((what & kCommitPosition) ? unsigned(kStreamCommit) : 0u) |
         ((what & kStressUpdate) ? unsigned(kStreamConstitutive) : 0u) |
         ((what & kSeparationShift) ? unsigned(kStreamShift) : 0u);
}

struct G2PParams {
  double dt = 0;
  double flip = 1;
  const unsigned char* rigid = nullptr;         // per field
  const double (*rigid_velocity)[3] = nullptr;  // per field, at t + dt
  double body_accel[3] = {0, 0, 0};             // for the external work of gravity
  bool prefetch_grid = true;  // 2D: the grid lines a line ahead (kernels/grid_prefetch.hpp)
  // The particle columns a batch ahead (kernels/particle_prefetch.hpp); null: none.
  const ParticleLinesAhead* particles_ahead = nullptr;
};

// Outcome of a G2P range: first bad particle (stencil off the grid or
// non-finite velocity), work of external forces, particles that changed tile.
struct G2PRangeResult {
  std::size_t bad = SIZE_MAX;
  std::size_t unsound = SIZE_MAX;  // kStressUpdate: first particle with J <= 0 or non-finite stress
  double external_work = 0;
  bool moved_tile = false;
};

namespace detail {

// Particle p moved by dt v on axis d: into x_next under MUSL, else into x.
// In float with xlo, the sum keeps its rounding error (kernels/position_sum.hpp).
// Each branch forms dt v itself: GCC fuses x + dt v into one FMA only when
// the product sits in the add's basic block, and a product formed before
// the branch changed the rounding of double runs (sphere_in_cube's damping
// energy by 2 %, from round-off differences the run amplified).
template <int D, class Real>
[[gnu::always_inline]] inline void move_particle(const ParticleView<D, Real>& P, int d,
                                                 std::size_t p, Real dt, Real v) {
  if constexpr (std::is_same_v<Real, float>)
    if (P.xlo[0]) {
      Real& to = P.x_next[0] ? P.x_next[d][p] : P.x[d][p];
      to = compensated_add(P.x[d][p], P.xlo[d][p], dt * v);
      return;
    }
  if (P.x_next[0])
    P.x_next[d][p] = P.x[d][p] + dt * v;
  else
    P.x[d][p] += dt * v;
}

// Prescribed motion (ALGORITHM §7): a particle of a rigid field moves with
// its field's velocity. True when p is one (the pass then skips the rest of
// its update, as the gathered values do not apply).
template <int D, class Real, unsigned What, bool MultiField>
[[gnu::always_inline]] inline bool rigid_motion(const ParticleView<D, Real>& P, const G2PParams& q,
                                                Real dt, std::size_t p) {
  if constexpr ((What & kUpdateMotion) != 0 && MultiField) {
    const int field = int(P.field[p]);
    if (q.rigid && q.rigid[field]) {
      for (int d = 0; d < D; ++d) {
        P.v[d][p] = Real(q.rigid_velocity[field][d]);
        move_particle(P, d, p, dt, P.v[d][p]);
      }
      return true;
    }
  }
  return false;
}

// The work of the external forces (traction, gravity) on particle p over
// the step: force times the displacement of the material point, which
// moves with the grid velocity vn (not with its FLIP velocity).
template <int D, class Real, bool Traction, bool Gravity>
[[gnu::always_inline]] inline double external_work(const ParticleView<D, Real>& P,
                                                   const G2PParams& q, std::size_t p,
                                                   const Real* vn) {
  double work = 0;
  for (int d = 0; d < D; ++d) {
    const double vmove = double(vn[d]);
    if constexpr (Traction) work += double(P.fext[d][p]) * vmove;
    if constexpr (Gravity) work += double(P.m[p]) * q.body_accel[d] * vmove;
  }
  return work * q.dt;
}

// kSeparationShift: particle p's shift += dt v* - (x_next - x), with vn
// the gathered S v*; a rigid field's particles (rigid[field] != 0) keep
// theirs (their x - x0 is the prescribed motion itself). Also the update
// of the shift's own pass (advance_separation_shift,
// kernels/separation_shift.hpp).
template <int D, class Real>
[[gnu::always_inline]] inline void advance_shift(const ParticleView<D, Real>& P,
                                                 const unsigned char* rigid, Real dt, std::size_t p,
                                                 const Real* vn) {
  if (rigid && P.field && rigid[P.field[p]]) return;
  for (int d = 0; d < D; ++d) P.sep_shift[d][p] += dt * vn[d] - (P.x_next[d][p] - P.x[d][p]);
}

// Particle p's update from vn (grid velocity), dv (its change over the
// step) and L (row-major dv_a/dx_b) gathered for it: FLIP/PIC velocity,
// position (or x_next), the work of external forces, L, the fused stress
// update, the separation shift and the position commit, as What asks.
template <int D, class Real, unsigned What, bool Traction, bool Gravity, class StressFn>
[[gnu::always_inline]] inline void update_particle(const ParticleView<D, Real>& P,
                                                   const G2PParams& q, Real dt, Real flip, Real pic,
                                                   std::size_t p, const Real* vn, const Real* dv,
                                                   const Real* L, G2PRangeResult& r,
                                                   const StressFn& stress) {
  if constexpr ((What & kUpdateMotion) != 0) {
    bool finite = true;
    for (int d = 0; d < D; ++d) {
      const Real vnew = flip * (P.v[d][p] + dv[d]) + pic * vn[d];
      P.v[d][p] = vnew;
      move_particle(P, d, p, dt, vn[d]);
      finite = finite && std::isfinite(vnew);
    }
    if constexpr (Traction || Gravity)
      r.external_work += external_work<D, Real, Traction, Gravity>(P, q, p, vn);
    if (!finite && r.bad == SIZE_MAX) r.bad = p;
  }
  if constexpr ((What & kVelocityGradient) != 0)
    for (int c = 0; c < D * D; ++c) P.L[c][p] = L[c];
  if constexpr ((What & kStressUpdate) != 0)
    if (!stress(P, p) && r.unsound == SIZE_MAX) r.unsound = p;
  if constexpr ((What & kSeparationShift) != 0) advance_shift(P, q.rigid, dt, p, vn);
  if constexpr ((What & kCommitPosition) != 0)
    for (int d = 0; d < D; ++d) P.x[d][p] = P.x_next[d][p];
}

}  // namespace detail
}  // namespace mmpm
