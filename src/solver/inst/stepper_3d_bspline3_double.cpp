// Instantiation: 3D, bspline3 shape functions, double precision.
#include "solver/instantiations.hpp"
#include "solver/stepper.hpp"

namespace mmpm {
template class Stepper<3, BSpline3Shape, double>;
std::unique_ptr<Simulation> make_stepper_3_bspline3_double(const Scene& scene) {
  return std::make_unique<Stepper<3, BSpline3Shape, double>>(scene);
}
}  // namespace mmpm
