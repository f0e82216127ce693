#include "app/start_warnings.hpp"

#include "solver/contact_gap.hpp"
#include "solver/simulation.hpp"

namespace mmpm {

std::vector<std::string> start_warnings(const Scene& scene, const Simulation& sim, double dt) {
  std::vector<std::string> out;
  if (std::string w = usl_time_step_warning(scene, dt); !w.empty()) out.push_back(std::move(w));
  for (std::string& w : stiff_interface_warnings(scene, dt)) out.push_back(std::move(w));
  for (std::string& w : open_contact_warnings(scene, sim)) out.push_back(std::move(w));
  return out;
}

}  // namespace mmpm
