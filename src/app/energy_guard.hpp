// A run whose energy grows far past what it was given has gone unstable.
//
// Why: the particle checks (J <= 0, a non-finite stress, a stencil leaving
// the grid) catch a blow-up only once it deforms or throws a particle that
// far. USL with uGIMP above its step limit grew to 800 times its initial
// energy at finite J, and the run ended with exit 0 (docs/validation.md
// §3.5). An exact integrator keeps K + U + U_int = E0 + W - (what damping,
// friction and PIC remove); the guard trips when K + U + U_int exceeds
// kEnergyGrowth times what the run was given, E0 + max(W, 0), plus a floor
// for runs given nothing. The largest excess a sweep of the shipped
// scenes' stable variants showed was 1.46 times (an imperfect interface
// with MVG normals), and a blow-up passes 10 within a few e-foldings.
#pragma once

#include <string>

#include "solver/simulation.hpp"

namespace mmpm {

inline constexpr double kEnergyGrowth = 10;

struct EnergyGuard {
  double initial = 0;  // K + U + U_int at step 0
  // Absolute: the energy of a uniform strain of ~1.4e-6 in every particle
  // (1e-12 x total mass x c^2), so a run at rest that stays at rest is fine.
  double floor = 0;

  // Why e breaks the bound, or empty.
  std::string check(const Energies& e) const;
};

// The guard for a scene from its particles' total mass and the fastest
// wave speed of its materials.
EnergyGuard make_energy_guard(double initial_energy, double total_mass, double wave_speed);

}  // namespace mmpm
