// Tensor-product weights and gradients of one particle (ALGORITHM §1: S_ip,
// G_ip) on its stencil of Shape::S nodes per direction.
#pragma once

#include <array>
#include <cstddef>

#include "kernels/grid_view.hpp"
#include "kernels/particle_view.hpp"
#include "kernels/shape.hpp"

namespace mmpm {

template <int D, class Shape, class Real>
struct Stencil {
  static constexpr int S = Shape::S;
  static constexpr int count = D == 2 ? S * S : S * S * S;
  // Filled by build (no default initialisers, as kernels/window.hpp Window).
  std::size_t base;                          // node index of the lowest corner (field 0)
  std::array<Real, count> w;                 // S_ip, x fastest
  std::array<std::array<Real, D>, count> g;  // G_ip
  std::array<std::size_t, count> node;       // node offsets relative to base

  // Returns false when the stencil leaves the grid.
  bool build(const ParticleView<D, Real>& P, const GridView<D, Real>& G,
             const std::array<Real, 3>& inv_h, std::size_t p) {
    Real w1[D][S], d1[D][S];
    int b[D];
    for (int d = 0; d < D; ++d) {
      const Real xi = (P.x[d][p] - G.origin[d]) * inv_h[d];
      const Real l = uses_half_width<Shape> ? half_width(P, d, p) : Real(0);
      b[d] = Shape::eval(xi, l, w1[d], d1[d]);
      if (b[d] < 0 || b[d] + S > G.nodes_per_dim[d]) return false;
    }
    const std::size_t nx = std::size_t(G.nodes_per_dim[0]);
    if constexpr (D == 2) {
      base = std::size_t(b[0]) + nx * std::size_t(b[1]);
      int k = 0;
      for (int j = 0; j < S; ++j)
        for (int i = 0; i < S; ++i, ++k) {
          w[k] = w1[0][i] * w1[1][j];
          g[k][0] = d1[0][i] * inv_h[0] * w1[1][j];
          g[k][1] = w1[0][i] * d1[1][j] * inv_h[1];
          node[k] = std::size_t(i) + nx * std::size_t(j);
        }
    } else {
      const std::size_t nxy = nx * std::size_t(G.nodes_per_dim[1]);
      base = std::size_t(b[0]) + nx * std::size_t(b[1]) + nxy * std::size_t(b[2]);
      int k = 0;
      for (int l = 0; l < S; ++l)
        for (int j = 0; j < S; ++j)
          for (int i = 0; i < S; ++i, ++k) {
            const Real wyz = w1[1][j] * w1[2][l];
            w[k] = w1[0][i] * wyz;
            g[k][0] = d1[0][i] * inv_h[0] * wyz;
            g[k][1] = w1[0][i] * d1[1][j] * inv_h[1] * w1[2][l];
            g[k][2] = w1[0][i] * w1[1][j] * d1[2][l] * inv_h[2];
            node[k] = std::size_t(i) + nx * std::size_t(j) + nxy * std::size_t(l);
          }
    }
    return true;
  }
};

}  // namespace mmpm
