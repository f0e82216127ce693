// Instantiation: 3D, bspline3 shape functions, float precision.
#include "solver/instantiations.hpp"
#include "solver/stepper.hpp"

namespace mmpm {
template class Stepper<3, BSpline3Shape, float>;
std::unique_ptr<Simulation> make_stepper_3_bspline3_float(const Scene& scene) {
  return std::make_unique<Stepper<3, BSpline3Shape, float>>(scene);
}
}  // namespace mmpm
