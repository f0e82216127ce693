// Instantiation: 3D, gimp shape functions, double precision.
#include "solver/instantiations.hpp"
#include "solver/stepper.hpp"

namespace mmpm {
template class Stepper<3, GimpShape, double>;
std::unique_ptr<Simulation> make_stepper_3_gimp_double(const Scene& scene) {
  return std::make_unique<Stepper<3, GimpShape, double>>(scene);
}
}  // namespace mmpm
