// Instantiation: 2D, gimp shape functions, float precision.
#include "solver/instantiations.hpp"
#include "solver/stepper.hpp"

namespace mmpm {
template class Stepper<2, GimpShape, float>;
std::unique_ptr<Simulation> make_stepper_2_gimp_float(const Scene& scene) {
  return std::make_unique<Stepper<2, GimpShape, float>>(scene);
}
}  // namespace mmpm
