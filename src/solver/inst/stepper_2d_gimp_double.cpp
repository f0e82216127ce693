// Instantiation: 2D, gimp shape functions, double precision.
#include "solver/instantiations.hpp"
#include "solver/stepper.hpp"

namespace mmpm {
template class Stepper<2, GimpShape, double>;
std::unique_ptr<Simulation> make_stepper_2_gimp_double(const Scene& scene) {
  return std::make_unique<Stepper<2, GimpShape, double>>(scene);
}
}  // namespace mmpm
