// Grid momentum update (ALGORITHM §2 step 4) and the velocities G2P reads.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "kernels/grid_view.hpp"
#include "kernels/node_ownership.hpp"
#include "kernels/reduce.hpp"

namespace mmpm {

template <int D, class Real>
struct GridVelocity {           // per field and node, same layout as GridView
  std::array<Real*, D> vel{};   // velocity after the update
  std::array<Real*, D> dvel{};  // velocity change over the step (FLIP)
};

struct GridUpdateParams {
  double dt = 0;
  double damping = 0;                           // grid damping alpha: a = f/m - alpha v
  double mass_threshold = 0;                    // below: the field is empty at that node
  double body_accel[3] = {0, 0, 0};             // gravity on deformable fields
  const unsigned char* rigid = nullptr;         // per field
  const double (*rigid_velocity)[3] = nullptr;  // per field, at t + dt
  bool has_interface_force = false;
  // Also set vel = p/m and complete dvel (what grid_velocities does) in the
  // same pass: for steps where nothing changes p in between (no
  // multimaterial pass B). Bitwise the two separate passes.
  bool velocities = false;
  // USL only (nullptr otherwise), per field: the light-node mass m_L (see
  // update_deformable's light nodes below).
  const double* light_threshold = nullptr;
  // With velocities: false when nothing reads p after this pass (the
  // single-field step: G2P reads vel and dvel, MUSL zeroes p for its second
  // scatter, the next step's P2G starts from zero), so the updated momentum
  // is not stored: 3 of the 3D pass's 16 arrays (2 of 11 in 2D).
  bool keep_momentum = true;
};

namespace detail {

// grid_update on nodes [b, e) of a deformable field, as a loop the compiler
// vectorises: heavy and sliver nodes computed alike and selected, no branch
// per node. Why: the branchy loop with the damping sum ran scalar, ~3x the
// time of this one (grid stage of the 2D linear step, docs/performance.md
// "Loops the compiler vectorises"). With Damping, node n's p.p/m goes to
// pv[n - b] (0 for slivers), and the caller sums them in node order, the
// order of the scalar loop, so the damping loss keeps its bits.
// noinline: inlined into grid_update's lambda (in bench_grid.cpp's
// translation unit), GCC 12 compiled the loop as scalar code, 4.7 ns/node
// against 1.2 in 3D (docs/performance.md "The grid stage on two threads");
// out of line it vectorises in every unit, and tools/check_vectorised.py
// sees every copy.
template <int D, class Real, bool Interface, bool Damping, bool Velocities, bool KeepP = true>
[[gnu::noinline]] void update_deformable(const GridView<D, Real>& G, const GridVelocity<D, Real>& V,
                                         std::size_t o, std::size_t b, std::size_t e, Real dt,
                                         Real alpha, Real thr, Real light, const Real (&gacc)[D],
                                         double* __restrict pv) {
  const Real inv_light = light > Real(0) ? Real(1) / light : Real(0);
  const Real* __restrict m_ = G.m + o;
  Real* __restrict p_[D];
  const Real* __restrict f_[D];
  const Real* __restrict fi_[D];
  Real* __restrict dv_[D];
  Real* __restrict vel_[D];
  for (int d = 0; d < D; ++d) {
    p_[d] = G.p[d] + o;
    f_[d] = G.f[d] + o;
    fi_[d] = Interface ? G.fi[d] + o : nullptr;
    dv_[d] = V.dvel[d] + o;
    vel_[d] = Velocities ? V.vel[d] + o : nullptr;
  }
#pragma GCC ivdep
  for (std::size_t n = b; n < e; ++n) {
    const Real m = m_[n];
    const bool heavy = m > thr;
    // A sliver of mass (a particle barely reaching the node): its velocity
    // is not trusted (vel = 0 for positions and strain rates), but the
    // force it collects still reaches the particles as a FLIP increment
    // S dt f / m (finite: S ~ m), or momentum would be lost at every uGIMP
    // surface. m = 0 gives 0/0 here, which the select drops.
    const bool some = m > Real(0);
    const Real inv_m = Real(1) / m;
    // USL's light nodes (m <= m_L, USL only). USL's velocity gradient reads
    // the grid velocity after the momentum update, v = (p + dt (f + m g -
    // alpha p)) / m. At a node that a particle barely reaches, m ~ S m_p
    // while the force f, made of the weight gradient, does not vanish with
    // S (~sqrt(S) at a uGIMP support edge, 1/h for linear shapes): the
    // particle's strain rate takes dt f / m times the gradient, a feedback
    // on its own strain of (c dt / h)^2 m_p / m that flips sign every step
    // (USL's small-mass instability; docs/validation.md §3.5). There the
    // momentum takes the force as if the node held m_L: f m / m_L, so the
    // feedback is bounded by (c dt / h)^2 m_p / m_L. What the node leaves
    // out, dt f (1 / m - 1 / m_L), still reaches the particles through the
    // FLIP increment dvel (scaled by S): momentum is kept to round-off, and
    // the multimaterial pass B, which runs between this pass and the
    // velocities, sees momenta whose velocities are bounded. MUSL and USF
    // (m_L = 0) read p / m of re-extrapolated momenta and have no such term.
    const Real keep = m <= light ? m * inv_light : Real(1);
    double sum = 0;
    // Unrolled completely: with USL's light-node select the body grew past
    // GCC's complete-unroll limit in 3D, the n loop then held a loop over d,
    // and it stayed scalar (tools/check_vectorised.py).
#pragma GCC unroll 3
    for (int d = 0; d < D; ++d) {
      const Real p = p_[d][n];
      // The per-node formulas (§2) with every multiply-add an explicit fma:
      // left to -ffp-contract, GCC fused them differently in the vector
      // loop (where the select makes an add conditional) and in its scalar
      // remainder, so a node's bits depended on where a thread's range
      // began (tests/test_node_ownership.cpp caught it).
      // A light node scales its whole force, gravity and the interface
      // force too: at equilibrium they balance f, and scaled apart they left
      // the momentum and dvel each a part that no longer balanced (a static
      // interface kept a particle-velocity mode, docs/validation.md §3.5).
      // keep = 1 (every heavy node, MUSL, USF) multiplies exactly: the same
      // bits as without the scaling.
      Real force = std::fma(m, gacc[d], f_[d][n]);
      Real damped = std::fma(-alpha, p, std::fma(m * keep, gacc[d], f_[d][n] * keep));
      if constexpr (Interface) force += fi_[d][n], damped += fi_[d][n] * keep;
      const Real sliver = some ? dt * force / m : Real(0);
      const Real updated = std::fma(dt, damped, p);
      // The light node's force left out of the momentum, for dvel: 0 elsewhere.
      // light_left_out (kernels/light_nodes.hpp) forms it again for the
      // supports and pass B: change both together.
      const Real left_out = dt * force * (Real(1) - keep) * inv_m;
      if constexpr (Velocities) {
        // grid_velocities' formulas on the updated momentum.
        vel_[d][n] = heavy ? updated * inv_m : Real(0);
        const Real dv = std::fma(updated, inv_m, -p * inv_m);
        dv_[d][n] = heavy ? (m <= light ? dv + left_out : dv) : sliver;
      } else {
        dv_[d][n] = heavy ? (m <= light ? left_out - p * inv_m : -p * inv_m) : sliver;
      }
      if constexpr (KeepP) p_[d][n] = heavy ? updated : p;
      sum = std::fma(double(p) * double(p), double(inv_m), sum);
    }
    if constexpr (Damping) pv[n - b] = heavy ? sum : 0.0;
  }
}

}  // namespace detail

// p <- p + dt (f + f_interface + m g - alpha p); stores -v_old in dvel
// (with q.velocities: also vel, and dvel = v_new - v_old). Returns the
// energy removed by grid damping this step (deterministic sum).
// Each thread updates the nodes it owns (kernels/node_ownership.hpp), then
// calls after(f, first, last) on each range of field f it updated (the
// supports, kernels/supports.hpp), in the same parallel region.
template <int D, class Real, class After = NoNodeHook>
double grid_update(const GridView<D, Real>& G, const GridVelocity<D, Real>& V,
                   const GridUpdateParams& q, const NodeOwnership& own = {}, After&& after = {}) {
  const Real dt = Real(q.dt), alpha = Real(q.damping), thr = Real(q.mass_threshold);
  auto body = [&](int f, std::size_t b, std::size_t e, std::array<double, 1>& acc) {
    const std::size_t o = std::size_t(f) * G.nodes;
    const Real light = q.light_threshold ? Real(q.light_threshold[std::size_t(f)]) : Real(0);
    if (q.rigid && q.rigid[f]) {
      // Prescribed motion (ALGORITHM §7): p = m v_rigid; no force, no loss.
      for (std::size_t n = b; n < e; ++n) {
        const std::size_t i = o + n;
        const Real m = G.m[i];
        const Real inv_m = Real(1) / m;
        for (int d = 0; d < D; ++d) {
          const Real p = G.p[d][i];
          if (m > thr) {
            const Real rigid_p = m * Real(q.rigid_velocity[f][d]);
            G.p[d][i] = rigid_p;
            if (q.velocities) {  // grid_velocities' formulas, as in update_deformable
              V.vel[d][i] = rigid_p * inv_m;
              V.dvel[d][i] = std::fma(rigid_p, inv_m, -p * inv_m);
            } else {
              V.dvel[d][i] = -p * inv_m;
            }
          } else {
            V.dvel[d][i] = Real(0);
            if (q.velocities) V.vel[d][i] = Real(0);
          }
        }
      }
      return;
    }
    Real gacc[D];
    for (int d = 0; d < D; ++d) gacc[d] = Real(q.body_accel[d]);
    // Damping: p.p/m per node, summed below in node order.
    double pv[kNodeReduceChunk];
    const bool damping = q.damping != 0;
    auto run = [&]<bool I, bool Dmp>() {
      if (q.velocities && q.keep_momentum)
        detail::update_deformable<D, Real, I, Dmp, true>(G, V, o, b, e, dt, alpha, thr, light, gacc,
                                                         pv);
      else if (q.velocities)
        detail::update_deformable<D, Real, I, Dmp, true, false>(G, V, o, b, e, dt, alpha, thr,
                                                                light, gacc, pv);
      else
        detail::update_deformable<D, Real, I, Dmp, false>(G, V, o, b, e, dt, alpha, thr, light,
                                                          gacc, pv);
    };
    if (q.has_interface_force)
      damping ? run.template operator()<true, true>() : run.template operator()<true, false>();
    else
      damping ? run.template operator()<false, true>() : run.template operator()<false, false>();
    // First order, alpha dt p.p/m, as the external work is (the force times
    // the step's new velocity, the one that moves the particles): at alpha
    // dt = 1 a loaded body that the damping stops every step balances
    // (incline_disk at damping 1e5: 0.01 %), while an unloaded one reads
    // twice the kinetic energy it lost (collision.toml: 0.8 against 0.4).
    // The second-order alpha dt (1 - alpha dt / 2) p.p/m, tried, swapped
    // the two (0.00 % and 49.8 %); docs/validation.md §3.8.
    if (damping)
      for (std::size_t n = 0; n < e - b; ++n) acc[0] += double(alpha) * double(dt) * pv[n];
  };
  auto update_then_hook = [&](int f, std::size_t b, std::size_t e, std::array<double, 1>& acc) {
    body(f, b, e, acc);
    after(f, b, e);
  };
  if (q.damping == 0) {
    // No loss to sum: each thread updates exactly the nodes it owns. The
    // fixed chunks of the sum below hand a thread the nodes up to its last
    // chunk's end, which the other thread owns (and whose lines sit in the
    // other core's cache): with 4096-node chunks, in the 3D block of 22 707
    // nodes split at 11 353, thread 0 took 12 288 and ran ~1.5x longer than
    // thread 1 (docs/performance.md "The grid stage on two threads"). A
    // node's result does not depend on the range it is in.
    team_run(G.nodes * std::size_t(G.fields) >= kParallelMinNodes, [&] {
      for_own_field_nodes(own, G.nodes, G.fields, [&](int f, std::size_t b, std::size_t e) {
        std::array<double, 1> none{};
        update_then_hook(f, b, e, none);
      });
    });
    return 0;
  }
  double loss = 0;
  for (const auto& field_loss : owned_field_sums<1>(own, G.nodes, G.fields, update_then_hook))
    loss += field_loss[0];
  return loss;
}

namespace detail {

// The node loop of grid_velocities (CompleteDvel) and
// grid_momentum_velocities on one range [first, last) of a field's nodes:
// selects instead of a branch per node, through restrict pointers, so the
// compiler vectorises it (the branchy loops ran scalar). Every node
// computes its quotient (m = 0 gives 0/0 or inf, which the select drops).
// noinline: inlined, the loop moved between the team's region body and
// for_own_field_nodes' copy as its body changed, and
// tools/check_vectorised.py must find it; out of line it vectorises in
// every unit, as update_deformable does.
template <bool CompleteDvel, int D, class Real>
[[gnu::noinline]] void velocity_range(const GridView<D, Real>& G, const GridVelocity<D, Real>& V,
                                      Real thr, std::size_t first, std::size_t last) {
  const Real* __restrict m_ = G.m;
  const Real* __restrict p_[D];
  Real* __restrict vel_[D];
  Real* __restrict dv_[D];
  for (int d = 0; d < D; ++d) p_[d] = G.p[d], vel_[d] = V.vel[d], dv_[d] = V.dvel[d];
#pragma GCC ivdep
  for (std::size_t i = first; i < last; ++i) {
    const Real m = m_[i];
    const bool heavy = m > thr;
    if constexpr (CompleteDvel) {
      const Real inv_m = Real(1) / m;
#pragma GCC unroll 3
      for (int d = 0; d < D; ++d) {
        // dvel + p/m as an explicit fma (see update_deformable).
        // dv_ holds -v_old (grid_update), plus a light node's left-out force.
        const Real v = p_[d][i] * inv_m, dv = std::fma(p_[d][i], inv_m, dv_[d][i]);
        vel_[d][i] = heavy ? v : Real(0);
        dv_[d][i] = heavy ? dv : dv_[d][i];  // slivers: set by grid_update
      }
    } else {
#pragma GCC unroll 3
      for (int d = 0; d < D; ++d) {
        const Real v = p_[d][i] / m;
        vel_[d][i] = heavy ? v : Real(0);
      }
    }
  }
}

template <bool CompleteDvel, int D, class Real, class After>
void node_velocities(const GridView<D, Real>& G, const GridVelocity<D, Real>& V, Real thr,
                     const NodeOwnership& own, After& after) {
  const auto ranges = [&](int f, std::size_t first, std::size_t last) {
    const std::size_t o = std::size_t(f) * G.nodes;
    velocity_range<CompleteDvel>(G, V, thr, o + first, o + last);
    after(f, first, last);
  };
  team_run(G.nodes * std::size_t(G.fields) >= kParallelMinNodes,
           [&] { for_own_field_nodes(own, G.nodes, G.fields, ranges); });
}

}  // namespace detail

// vel = p/m, dvel += vel (completing v_new - v_old), after pass B; nodes
// with a sliver of mass keep vel = 0 and the increment grid_update gave them.
// Then after(f, first, last) on each range, as grid_update.
template <int D, class Real, class After = NoNodeHook>
void grid_velocities(const GridView<D, Real>& G, const GridVelocity<D, Real>& V, Real thr,
                     const NodeOwnership& own = {}, After&& after = {}) {
  detail::node_velocities<true>(G, V, thr, own, after);
}

// vel = p/m alone (dvel untouched): the velocities of re-extrapolated
// momenta (MUSL's second transfer, USF's first); slivers get vel = 0. The
// quotient is p/m as the Stepper's scalar loop computed it (bitwise), in a
// loop that now vectorises (docs/performance.md "Loops the compiler
// vectorises").
template <int D, class Real, class After = NoNodeHook>
void grid_momentum_velocities(const GridView<D, Real>& G, const GridVelocity<D, Real>& V, Real thr,
                              const NodeOwnership& own = {}, After&& after = {}) {
  detail::node_velocities<false>(G, V, thr, own, after);
}

}  // namespace mmpm
