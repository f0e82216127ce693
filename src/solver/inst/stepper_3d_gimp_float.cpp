// Instantiation: 3D, gimp shape functions, float precision.
#include "solver/instantiations.hpp"
#include "solver/stepper.hpp"

namespace mmpm {
template class Stepper<3, GimpShape, float>;
std::unique_ptr<Simulation> make_stepper_3_gimp_float(const Scene& scene) {
  return std::make_unique<Stepper<3, GimpShape, float>>(scene);
}
}  // namespace mmpm
