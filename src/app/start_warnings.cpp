#include "app/start_warnings.hpp"

#include <sstream>

#include "scene/interaction_warning.hpp"
#include "solver/contact_gap.hpp"
#include "solver/simulation.hpp"

namespace mmpm {

namespace {

// kernels/separation_extrapolation.hpp: with 1 particle per cell the
// extrapolation has too little spread to work with at a curved interface
// (docs/interface_validation.md, "Extrapolated separation").
std::vector<std::string> extrapolated_separation_warnings(const Scene& scene) {
  std::vector<std::string> out;
  for (std::size_t k = 0; k < scene.interactions.size(); ++k) {
    const InteractionSpec& it = scene.interactions[k];
    if (it.separation != Separation::extrapolated) continue;
    for (const BodySpec& b : scene.bodies) {
      if (b.particles_per_cell >= 2 ||
          (b.material != it.materials[0] && b.material != it.materials[1]))
        continue;
      std::ostringstream m;
      m << interaction_warning(scene, k, "separation")
        << "\"extrapolated\" needs 2 or more particles per cell per direction; "
        << "body '" << b.name << "' has " << b.particles_per_cell
        << " (a sphere in a cube seeded 1 per cell blew up at D = 1e6 MPa/mm where "
        << "\"displacement\" only crept)";
      out.push_back(m.str());
    }
  }
  return out;
}

}  // namespace

std::vector<std::string> start_warnings(const Scene& scene, const Simulation& sim, double dt) {
  std::vector<std::string> out;
  if (std::string w = usl_time_step_warning(scene, dt); !w.empty()) out.push_back(std::move(w));
  for (std::string& w : stiff_interface_warnings(scene, dt)) out.push_back(std::move(w));
  for (std::string& w : open_contact_warnings(scene, sim)) out.push_back(std::move(w));
  for (std::string& w : bonded_position_interface_warnings(scene, sim)) out.push_back(std::move(w));
  for (std::string& w : extrapolated_separation_warnings(scene)) out.push_back(std::move(w));
  return out;
}

}  // namespace mmpm
