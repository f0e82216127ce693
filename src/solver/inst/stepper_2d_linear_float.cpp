// Instantiation: 2D, linear shape functions, float precision.
#include "solver/instantiations.hpp"
#include "solver/stepper.hpp"

namespace mmpm {
template class Stepper<2, LinearShape, float>;
std::unique_ptr<Simulation> make_stepper_2_linear_float(const Scene& scene) {
  return std::make_unique<Stepper<2, LinearShape, float>>(scene);
}
}  // namespace mmpm
