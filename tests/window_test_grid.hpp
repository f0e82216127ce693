// The kernel tests' small grid whose cells, spacing and origin differ per
// direction (so a swapped index or spacing shows), and the shape
// configurations they sweep: every shape in 2D and 3D, double and float.
#pragma once

#include <gtest/gtest.h>

#include <cstddef>

#include "kernels/grid_view.hpp"
#include "kernels/shape.hpp"
#include "tests/shape_configs.hpp"

namespace mmpm_test {

constexpr int kGridCells[3] = {12, 9, 7};
constexpr double kGridH[3] = {0.5, 0.25, 0.75}, kGridOrigin[3] = {-1.0, 2.0, 0.5};

template <int D, class Real>
mmpm::GridView<D, Real> skewed_grid() {
  mmpm::GridView<D, Real> G;
  G.nodes = 1;
  for (int d = 0; d < D; ++d) {
    G.nodes_per_dim[std::size_t(d)] = kGridCells[d] + 1;
    G.h[std::size_t(d)] = Real(kGridH[d]);
    G.origin[std::size_t(d)] = Real(kGridOrigin[d]);
    G.nodes *= std::size_t(kGridCells[d] + 1);
  }
  return G;
}

using WindowConfigs =
    ::testing::Types<Cfg<2, mmpm::LinearShape, double>, Cfg<2, mmpm::LinearShape, float>,
                     Cfg<2, mmpm::GimpShape, double>, Cfg<2, mmpm::GimpShape, float>,
                     Cfg<2, mmpm::BSpline2Shape, double>, Cfg<2, mmpm::BSpline3Shape, float>,
                     Cfg<3, mmpm::LinearShape, double>, Cfg<3, mmpm::GimpShape, double>,
                     Cfg<3, mmpm::GimpShape, float>, Cfg<3, mmpm::BSpline2Shape, double>,
                     Cfg<3, mmpm::BSpline3Shape, double>>;

}  // namespace mmpm_test
