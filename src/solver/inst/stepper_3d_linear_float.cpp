// Instantiation: 3D, linear shape functions, float precision.
#include "solver/instantiations.hpp"
#include "solver/stepper.hpp"

namespace mmpm {
template class Stepper<3, LinearShape, float>;
std::unique_ptr<Simulation> make_stepper_3_linear_float(const Scene& scene) {
  return std::make_unique<Stepper<3, LinearShape, float>>(scene);
}
}  // namespace mmpm
