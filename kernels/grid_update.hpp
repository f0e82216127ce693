// Grid momentum update (ALGORITHM §2 step 4) and the velocities G2P reads.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "kernels/grid_view.hpp"
#include "kernels/node_ownership.hpp"

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
};

// p <- p + dt (f + f_interface + m g - alpha p); stores -v_old in dvel.
// Returns the energy removed by grid damping this step (deterministic sum).
// Each thread updates the nodes it owns (kernels/node_ownership.hpp).
template <int D, class Real>
double grid_update(const GridView<D, Real>& G, const GridVelocity<D, Real>& V,
                   const GridUpdateParams& q, const NodeOwnership& own = {}) {
  const Real dt = Real(q.dt), alpha = Real(q.damping), thr = Real(q.mass_threshold);
  auto body = [&](int f, std::size_t b, std::size_t e, std::array<double, 1>& acc) {
    const std::size_t o = std::size_t(f) * G.nodes;
    const bool rigid = q.rigid && q.rigid[f];
    Real gacc[D];
    for (int d = 0; d < D; ++d) gacc[d] = rigid ? Real(0) : Real(q.body_accel[d]);
    for (std::size_t n = b; n < e; ++n) {
      const std::size_t i = o + n;
      const Real m = G.m[i];
      if (!(m > thr)) {
        // A sliver of mass (a particle barely reaching the node): its
        // velocity is not trusted (vel = 0 for positions and strain
        // rates), but the force it collects still reaches the particles
        // as a FLIP increment S dt f / m (finite: S ~ m), or momentum
        // would be lost at every uGIMP surface.
        const bool some = m > Real(0) && !rigid;
        for (int d = 0; d < D; ++d) {
          Real force = G.f[d][i] + m * gacc[d];
          if (q.has_interface_force) force += G.fi[d][i];
          V.dvel[d][i] = some ? dt * force / m : Real(0);
        }
        continue;
      }
      const Real inv_m = Real(1) / m;
      double pv = 0;
      for (int d = 0; d < D; ++d) {
        const Real p = G.p[d][i];
        V.dvel[d][i] = -p * inv_m;
        if (rigid) {
          G.p[d][i] = m * Real(q.rigid_velocity[f][d]);
          continue;
        }
        Real force = G.f[d][i] + m * gacc[d] - alpha * p;
        if (q.has_interface_force) force += G.fi[d][i];
        G.p[d][i] = p + dt * force;
        pv += double(p) * double(p) * double(inv_m);
      }
      acc[0] += double(alpha) * double(dt) * pv;
    }
  };
  double loss = 0;
  for (const auto& field_loss : owned_field_sums<1>(own, G.nodes, G.fields, body))
    loss += field_loss[0];
  return loss;
}

// vel = p/m, dvel += vel (completing v_new - v_old), after pass B; nodes
// with a sliver of mass keep vel = 0 and the increment grid_update gave them.
template <int D, class Real>
void grid_velocities(const GridView<D, Real>& G, const GridVelocity<D, Real>& V, Real thr,
                     const NodeOwnership& own = {}) {
#pragma omp parallel if (G.nodes * std::size_t(G.fields) >= kParallelMin)
  for_own_nodes(own, G.nodes, G.fields, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const Real m = G.m[i];
      if (m > thr) {
        const Real inv_m = Real(1) / m;
        for (int d = 0; d < D; ++d) {
          const Real v = G.p[d][i] * inv_m;
          V.vel[d][i] = v;
          V.dvel[d][i] += v;
        }
      } else {
        for (int d = 0; d < D; ++d) V.vel[d][i] = Real(0);  // dvel: set by grid_update
      }
    }
  });
}

}  // namespace mmpm
