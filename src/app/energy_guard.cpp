#include "app/energy_guard.hpp"

#include <algorithm>
#include <sstream>

namespace mmpm {

EnergyGuard make_energy_guard(double initial_energy, double total_mass, double wave_speed) {
  EnergyGuard g;
  g.initial = initial_energy;
  g.floor = 1e-12 * total_mass * wave_speed * wave_speed;
  return g;
}

std::string EnergyGuard::check(const Energies& e) const {
  const double now = e.kinetic + e.strain + e.interface;
  const double given = initial + std::max(e.external_work, 0.0);
  const double bound = kEnergyGrowth * given + floor;
  if (now <= bound) return {};  // also false for NaN: a non-finite energy trips it
  std::ostringstream m;
  m.precision(4);
  m << "the energy K + U + U_int reached " << now;
  if (given > 0)
    m << ", " << now / given << " times what the run was given";
  else
    m << " while the run was given none";
  m << " (initial energy " << initial << ", external work " << e.external_work << ")";
  return m.str();
}

}  // namespace mmpm
