// Instantiation: 2D, linear shape functions, double precision.
#include "solver/instantiations.hpp"
#include "solver/stepper.hpp"

namespace mmpm {
template class Stepper<2, LinearShape, double>;
std::unique_ptr<Simulation> make_stepper_2_linear_double(const Scene& scene) {
  return std::make_unique<Stepper<2, LinearShape, double>>(scene);
}
}  // namespace mmpm
