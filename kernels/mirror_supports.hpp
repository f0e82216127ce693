// Supports on a grid plane as mirrors (docs/validation.md §3.7).
//
// A quadratic or cubic B-spline reaches one node layer past a plane the body
// rests on, and linear and uGIMP particles do once compression moves them
// (or their domains) past it. Fixing only the plane's nodes leaves that
// layer free (sigma_xx = 0 and 2.34 in a supported B-spline bar's first two
// rows, -2.80 and +0.97 in a compressed uGIMP bar's); fixing it too forces a
// kink the splines cannot represent (1.06 and 1.27). A support on a plane is
// a symmetry plane: the body continued by its mirror image, the fixed
// components odd, the free ones even. The image's particles add to a node q
// on the body's side exactly what the body's particles add to q's ghost g
// (q mirrored through the plane), with the fixed components' signs flipped.
// So the ghost's mass, momentum and force are folded into its partner
// (fold_mirror), the updated partner gives the ghost its velocity
// (mirror_velocities), and a linear field that vanishes on the plane is
// represented exactly. On the plane's own nodes the image doubles the mass
// and the free components and makes the fixed ones those of the support:
// the fold sets their fixed momenta to m v_s and their fixed forces to 0.
// Without that, FLIP kept the particles' stray momentum at the plane as a
// velocity change there (a mirrored half bar differed from the whole bar by
// 1e-3 in the first row's velocity; with it, by 2e-16).
//
// Each thread folds the entries whose partner it owns and sets the ghosts
// it owns (the node ranges of kernels/node_ownership.hpp), so the lines the
// next node loop reads stay in the cache of the core that reads them. Done
// by thread 0 alone, the 3D block of bench_step (a plane of 783 nodes)
// spent 96 us per step in these loops on 2 threads against 51 on one: half
// of every entry's lines sat in the other core's cache
// (docs/performance.md "Mirror folds on the nodes a thread owns"). An
// entry's result does not depend on which thread runs it, and the
// reactions are summed afterwards in entry order (fold_reaction).
#pragma once

#include <cstddef>
#include <cstdint>

#include "kernels/grid_update.hpp"
#include "kernels/grid_view.hpp"

namespace mmpm {

template <class Real>
struct MirrorView {
  const std::uint32_t* plane = nullptr;    // node indices within a field
  const std::uint32_t* ghost = nullptr;    // plane[k] moved one node off the body
  const std::uint32_t* partner = nullptr;  // the ghost's mirror on the body's side
  std::size_t count = 0;
  // fields x count: the ghosts' masses as the last mass fold found them, for
  // the image momenta of later folds (MUSL re-scatters momenta only).
  Real* ghost_mass = nullptr;
  bool fix[3] = {false, false, false};  // the support's fixed components: odd
  Real velocity[3] = {0, 0, 0};         // the support's velocity v_s over this step
};

enum MirrorFold : unsigned { kFoldMass = 1, kFoldMomentum = 2, kFoldForce = 4 };

// Folds field f's ghost values into their partners and empties the ghosts;
// sets the plane nodes' fixed components to the support's. Only the entries
// whose partner lies in [first, last) (a thread's own nodes). The image of a
// ghost's momentum about the moving plane is 2 m_g v_s - p_g on the fixed
// components. With terms (count x D entries): entry k's f_0 + 2 f_g along
// the fixed components, whose negative is the force the image exerts on the
// body's nodes (the ghost's force leaves, its negative arrives at the
// partner); fold_reaction sums them. The momentum folds are left out of it:
// they project the velocities onto symmetric ones rather than act over the
// step, and as impulses over dt they read 49 instead of -1 in a static
// bar's last, 1e-9 ms short step.
template <int D, class Real>
void fold_mirror(const GridView<D, Real>& G, const MirrorView<Real>& M, int f, unsigned what,
                 double* terms, std::size_t first, std::size_t last) {
  const std::size_t o = std::size_t(f) * G.nodes;
  for (std::size_t k = 0; k < M.count; ++k) {
    if (M.partner[k] < first || M.partner[k] >= last) continue;
    const std::size_t g = o + M.ghost[k], q = o + M.partner[k], c = o + M.plane[k];
    Real& m_g = M.ghost_mass[std::size_t(f) * M.count + k];
    if (what & kFoldMass) {
      m_g = G.m[g];
      G.m[q] += m_g;
      G.m[g] = Real(0);
    }
    for (int d = 0; d < D; ++d) {
      if (what & kFoldMomentum) {
        G.p[d][q] += M.fix[d] ? Real(2) * m_g * M.velocity[d] - G.p[d][g] : G.p[d][g];
        G.p[d][g] = Real(0);
        if (M.fix[d]) G.p[d][c] = G.m[c] * M.velocity[d];
      }
      if (what & kFoldForce) {
        if (terms && M.fix[d]) terms[k * D + d] = double(G.f[d][c]) + 2.0 * double(G.f[d][g]);
        G.f[d][q] += M.fix[d] ? -G.f[d][g] : G.f[d][g];
        G.f[d][g] = Real(0);
        if (M.fix[d]) G.f[d][c] = Real(0);
      }
    }
  }
}

// The image of a multimaterial field's separation, volume and domain
// gradient (ALGORITHM §1: mx, Omega, g; docs/contact_validation.md §22).
// The mass fold gives a partner node the image's mass; the interface and
// contact laws read mx / m (the field's displacement or position there),
// Omega (the contact area) and g (the normals) beside it, so those get the
// image too, or a partner's displacement reads the body's sum over the
// body's and the image's mass. The image's separation coordinate is the
// body's reflected: along an odd axis, s_odd - u with s_odd = 2 x the
// plane's displacement (or position); along the others, u. Its gradient is
// the body's with the plane-normal component negated (normal_axis).
//
// On the plane's own nodes the image doubles every sum (as the mass, which
// the fold leaves single: a ratio is all the laws read) and makes the odd
// components of mx those of the plane itself: m s / 2 per field. Only the
// entries whose partner is read (is_read nonzero: a multimaterial node, or a
// ghost of another mirror folded into one) and lies in [first, last):
// elsewhere the ghost's fields need not have been scattered this step
// (Stepper::p2g_multimaterial scatters the tiles reaching the multimaterial
// nodes and those ghosts).
template <int D, class Real>
void fold_mirror_multimaterial(const GridView<D, Real>& G, const MirrorView<Real>& M, int f,
                               const bool (&odd)[3], const Real (&s_odd)[3], int normal_axis,
                               const unsigned char* is_read, std::size_t first, std::size_t last) {
  const std::size_t o = std::size_t(f) * G.nodes;
  for (std::size_t k = 0; k < M.count; ++k) {
    const std::uint32_t partner = M.partner[k];
    if (partner < first || partner >= last || !is_read[partner]) continue;
    const std::size_t g = o + M.ghost[k], q = o + partner, c = o + M.plane[k];
    const Real m_g = M.ghost_mass[std::size_t(f) * M.count + k];
    if (G.vol) {
      G.vol[q] += G.vol[g];
      G.vol[g] = Real(0);
    }
    for (int d = 0; d < D; ++d) {
      if (G.mx[d]) {
        G.mx[d][q] += odd[d] ? m_g * s_odd[d] - G.mx[d][g] : G.mx[d][g];
        G.mx[d][g] = Real(0);
        if (odd[d]) G.mx[d][c] = Real(0.5) * G.m[c] * s_odd[d];
      }
      if (G.g[d]) {
        G.g[d][q] += d == normal_axis ? -G.g[d][g] : G.g[d][g];
        G.g[d][g] = Real(0);
      }
    }
  }
}

// Adds to reaction (D entries) the force the image exerted on the body in
// fold_mirror's force fold, from its terms (count x D), in entry order: the
// bits of the serial loop that accumulated them as it folded.
template <int D, class Real>
void fold_reaction(const MirrorView<Real>& M, const double* terms, double* reaction) {
  for (std::size_t k = 0; k < M.count; ++k)
    for (int d = 0; d < D; ++d)
      if (M.fix[d]) reaction[d] -= terms[k * D + d];
}

// The ghosts' velocities from their partners': v_g = 2 v_s - v_q on the
// fixed components (v_s the support's velocity: the odd image about the
// moving plane), v_g = v_q on the free ones; the changes over the step
// likewise, -dv_q and dv_q.
// Only the ghosts in [first, last) (a thread's own nodes), once every
// partner's velocity is final.
template <int D, class Real>
void mirror_velocities(const GridView<D, Real>& G, const GridVelocity<D, Real>& V,
                       const MirrorView<Real>& M, int f, bool with_dvel, std::size_t first,
                       std::size_t last) {
  const std::size_t o = std::size_t(f) * G.nodes;
  for (std::size_t k = 0; k < M.count; ++k) {
    if (M.ghost[k] < first || M.ghost[k] >= last) continue;
    const std::size_t g = o + M.ghost[k], q = o + M.partner[k];
    for (int d = 0; d < D; ++d) {
      const bool odd = M.fix[d];
      V.vel[d][g] = odd ? Real(2) * M.velocity[d] - V.vel[d][q] : V.vel[d][q];
      if (with_dvel) V.dvel[d][g] = odd ? -V.dvel[d][q] : V.dvel[d][q];
    }
  }
}

}  // namespace mmpm
