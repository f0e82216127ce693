// Picks the compiled instantiation (dimension × shape × precision) for a scene.
#include "scene/error.hpp"
#include "solver/instantiations.hpp"
#include "solver/simulation.hpp"

namespace mmpm {

std::unique_ptr<Simulation> make_simulation(const Scene& scene) {
  const int d = scene.simulation.dimension;
  const bool dbl = scene.simulation.precision == Precision::float64;
  const ShapeKind s = scene.grid.shape;
#ifdef MMPM_FAST_DEV
  if (d == 2 && s == ShapeKind::linear && dbl) return make_stepper_2_linear_double(scene);
  if (d == 2 && s == ShapeKind::gimp)
    return dbl ? make_stepper_2_gimp_double(scene) : make_stepper_2_gimp_float(scene);
  if (d == 3 && s == ShapeKind::gimp && dbl) return make_stepper_3_gimp_double(scene);
  throw InputError(
      scene.source_file +
      ": this developer build (MMPM_FAST_DEV) lacks the instantiation the scene needs");
#else
#define MMPM_PICK(DIM, SHAPE, KIND)                           \
  if (d == DIM && s == ShapeKind::KIND)                       \
    return dbl ? make_stepper_##DIM##_##SHAPE##_double(scene) \
               : make_stepper_##DIM##_##SHAPE##_float(scene);
  MMPM_PICK(2, linear, linear)
  MMPM_PICK(2, gimp, gimp)
  MMPM_PICK(2, bspline2, bspline2)
  MMPM_PICK(2, bspline3, bspline3)
  MMPM_PICK(3, linear, linear)
  MMPM_PICK(3, gimp, gimp)
  MMPM_PICK(3, bspline2, bspline2)
  MMPM_PICK(3, bspline3, bspline3)
#undef MMPM_PICK
  throw InputError(scene.source_file + ": no instantiation for this dimension and shape function");
#endif
}

}  // namespace mmpm
