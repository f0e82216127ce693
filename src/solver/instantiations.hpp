// One factory per compiled instantiation; each lives in its own translation
// unit (solver/inst/*.cpp) so the 16 variants build in parallel.
#pragma once

#include <memory>

#include "solver/simulation.hpp"

namespace mmpm {

#define MMPM_DECLARE(DIM, SHAPE)                                                         \
  std::unique_ptr<Simulation> make_stepper_##DIM##_##SHAPE##_double(const Scene& scene); \
  std::unique_ptr<Simulation> make_stepper_##DIM##_##SHAPE##_float(const Scene& scene);
MMPM_DECLARE(2, linear)
MMPM_DECLARE(2, gimp)
MMPM_DECLARE(2, bspline2)
MMPM_DECLARE(2, bspline3)
MMPM_DECLARE(3, linear)
MMPM_DECLARE(3, gimp)
MMPM_DECLARE(3, bspline2)
MMPM_DECLARE(3, bspline3)
#undef MMPM_DECLARE

}  // namespace mmpm
