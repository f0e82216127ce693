// Raw views of the per-material grid fields (SoA, field-major: entry
// [f * nodes + i] is field f at node i). Owned by model/grid.hpp; kernels
// see only these pointers. A pointer is null when the scene does not need
// that quantity (ARCHITECTURE "model only what the scene requires").
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace mmpm {

template <int D, class Real>
struct GridView {
  std::array<int, 3> nodes_per_dim{1, 1, 1};  // cells + 1 per direction
  std::array<Real, 3> h{1, 1, 1};             // cell size per direction
  std::array<Real, 3> origin{0, 0, 0};
  std::size_t nodes = 0;  // product of nodes_per_dim[0..D)
  int fields = 1;         // material velocity fields

  Real* m = nullptr;          // mass                      (P-5)
  std::array<Real*, D> p{};   // momentum                  (P-6)
  std::array<Real*, D> f{};   // internal + external force
  std::array<Real*, D> mx{};  // mass-weighted position / displacement (P-10, P-13)
  Real* vol = nullptr;        // nodal domain Omega        (P-19)
  std::array<Real*, D> g{};   // domain gradient           (P-33)
  std::array<Real*, D> fi{};  // interface force           (P-17)

  std::size_t at(int field, std::size_t node) const { return std::size_t(field) * nodes + node; }
  // Node coordinates from the flat index (x fastest).
  std::array<Real, 3> position(std::size_t node) const {
    std::array<Real, 3> x{0, 0, 0};
    std::size_t r = node;
    for (int d = 0; d < D; ++d) {
      const std::size_t k = r % std::size_t(nodes_per_dim[d]);
      r /= std::size_t(nodes_per_dim[d]);
      x[d] = origin[d] + Real(k) * h[d];
    }
    return x;
  }
};

}  // namespace mmpm
