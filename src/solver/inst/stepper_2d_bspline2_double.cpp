// Instantiation: 2D, bspline2 shape functions, double precision.
#include "solver/instantiations.hpp"
#include "solver/stepper.hpp"

namespace mmpm {
template class Stepper<2, BSpline2Shape, double>;
std::unique_ptr<Simulation> make_stepper_2_bspline2_double(const Scene& scene) {
  return std::make_unique<Stepper<2, BSpline2Shape, double>>(scene);
}
}  // namespace mmpm
