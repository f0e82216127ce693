// Grid supports (SCENE.md [[boundary]]): the fixed velocity components of a
// support's nodes get the support's velocity, and the momentum this takes
// is the support's reaction force (what a load cell would read).
//
// Applied node range by node range, by the thread that has just computed
// those nodes' velocities (grid_update, node_velocities), so the supports
// run in parallel on lines the thread owns and has just touched. Why: as a
// serial loop after the node pass (half its nodes in the other core's
// cache on 2 threads), the grid stage of the 2D linear and 3D bench steps
// took a quarter to a third longer on 1 and on 2 threads
// (docs/performance.md "Supports applied by the nodes' owners").
//
// The reaction stays bitwise that of the serial loop: each node writes its
// term m (v_target - v) / dt to its own slot, and sum_support_reaction adds
// the slots in the serial loop's order (field, node, axis).
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>

#include "kernels/grid_update.hpp"
#include "kernels/grid_view.hpp"
#include "kernels/light_nodes.hpp"

namespace mmpm {

template <class Real>
struct SupportView {
  const std::uint32_t* nodes = nullptr;  // node indices within a field, ascending
  std::size_t count = 0;
  bool fix[3] = {false, false, false};
  Real velocity[3] = {0, 0, 0};  // of the fixed components, over this step
  // fields x count x D slots: m (v_target - v) / dt of each node and axis,
  // +0 for free axes and sliver nodes. Written only by calls with dvel.
  double* reaction_terms = nullptr;
};

template <class Real>
struct Supports {
  const SupportView<Real>* list = nullptr;
  std::size_t count = 0;
  const unsigned char* rigid = nullptr;  // per field; supports hold deformable fields only
  Real mass_threshold = 0;
  double dt = 0;
  // After the momentum update: also complete dvel and record the reaction
  // terms (only that application is the support's impulse for the step;
  // USF and MUSL also enforce the supports on their other transfers).
  bool with_dvel = false;
  // USL (with_dvel only; null otherwise): per field the light-node mass m_L
  // and the step's gravity. A fixed component also takes a light node's
  // left-out velocity out of dvel (kernels/light_nodes.hpp), into the
  // reaction: left there, the support held the node while its particles
  // took that part every step (a velocity mode at the symmetry planes of
  // a static sphere in a cube).
  const double* light = nullptr;
  Real gravity[3] = {0, 0, 0};
};

// The supports on nodes [b, e) of field f (indices within the field).
template <int D, class Real>
void apply_supports(const GridView<D, Real>& G, const GridVelocity<D, Real>& V,
                    const Supports<Real>& S, int f, std::size_t b, std::size_t e) {
  if (S.count == 0 || (S.rigid && S.rigid[f])) return;
  const std::size_t o = std::size_t(f) * G.nodes;
  const Real light = S.with_dvel && S.light ? Real(S.light[f]) : Real(0);
  for (std::size_t s = 0; s < S.count; ++s) {
    const SupportView<Real>& bc = S.list[s];
    const std::uint32_t* first = std::lower_bound(bc.nodes, bc.nodes + bc.count, b);
    const std::uint32_t* last = std::lower_bound(first, bc.nodes + bc.count, e);
    double* terms = bc.reaction_terms + std::size_t(f) * bc.count * D;
    for (const std::uint32_t* it = first; it != last; ++it) {
      const std::size_t k = std::size_t(it - bc.nodes);
      const std::size_t i = o + *it;
      const Real m = G.m[i];
      if (!(m > S.mass_threshold)) {
        // A sliver node on a support: the support absorbs its increment.
        if (S.with_dvel)
          for (int d = 0; d < D; ++d) {
            if (!bc.fix[d]) continue;
            V.dvel[d][i] = Real(0);
            terms[k * D + d] = 0.0;
          }
        continue;
      }
      for (int d = 0; d < D; ++d) {
        if (!bc.fix[d]) continue;
        const Real v_target = bc.velocity[d];
        const Real change = v_target - V.vel[d][i];
        V.vel[d][i] = v_target;
        G.p[d][i] = m * v_target;
        if (S.with_dvel) {
          const Real held =
              change - light_left_out<D, Real>(G, i, d, m, light, S.gravity[d], Real(S.dt));
          V.dvel[d][i] += held;
          terms[k * D + d] = double(m) * double(held) / S.dt;
        }
      }
    }
  }
}

// Support s's reaction from the terms the last call with dvel wrote, added
// in field, node, axis order (the serial loop's). The +0 slots of slivers
// leave the sum's bits alone: it starts at +0, so it is never -0, and
// x + (+0) = x for every other x.
template <int D, class Real>
std::array<double, 3> sum_support_reaction(const SupportView<Real>& bc, int fields,
                                           const unsigned char* rigid) {
  std::array<double, 3> reaction{0, 0, 0};
  for (int f = 0; f < fields; ++f) {
    if (rigid && rigid[f]) continue;
    const double* terms = bc.reaction_terms + std::size_t(f) * bc.count * D;
    for (std::size_t k = 0; k < bc.count; ++k)
      for (int d = 0; d < D; ++d)
        if (bc.fix[d]) reaction[std::size_t(d)] += terms[k * D + d];
  }
  return reaction;
}

}  // namespace mmpm
