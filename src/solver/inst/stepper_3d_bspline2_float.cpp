// Instantiation: 3D, bspline2 shape functions, float precision.
#include "solver/instantiations.hpp"
#include "solver/stepper.hpp"

namespace mmpm {
template class Stepper<3, BSpline2Shape, float>;
std::unique_ptr<Simulation> make_stepper_3_bspline2_float(const Scene& scene) {
  return std::make_unique<Stepper<3, BSpline2Shape, float>>(scene);
}
}  // namespace mmpm
