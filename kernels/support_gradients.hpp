// Domain gradients at the nodes of a symmetry plane (a support on a grid
// plane that fixes the plane's normal component; docs/contact_validation.md
// §20).
//
// In the mirrored, whole body every field's domain gradient (P-33) at the
// plane's nodes lies in the plane: the images' contributions cancel the
// normal component. The model holds one side only, so the gradient there
// leans across the plane wherever a body ends on it (the quarter model's
// rigid floor, say, which has a corner on the plane). The gradient normals
// (mvg, avg, rigid) then lean too; pass B removes the approach
// along the leaning normal, the support takes the component across the
// plane back, and the normal part is left half done. The particles' FLIP
// increments carried the difference into velocities the grid cannot see: a
// disk resting on a rigid floor that ends on a mirror plane gained them
// without bound (unresolved kinetic energy 2.0 → 11.3 mJ from 0.72 to
// 0.92 ms, the strain energy 3.5 mJ).
//
// So at those nodes each field's gradient loses the plane's normal
// component, as the mirrored body's has none. Only where the gradient lies
// mostly in the plane (|g_in_plane| ≥ |g| / 2): a gradient mostly across
// the plane marks a face lying on it (two bodies meeting on the plane),
// where the component left would be noise, so it is left alone. A node on
// planes along every axis (a 2D corner) is left alone too.
//
// Supports given as boxes of nodes are not read as planes: a box's face
// need not be a symmetry plane (the shear stack's sides fix u_y, along the
// interface's normal, and its gradient area needs that component).
#pragma once

#include <cstddef>
#include <cstdint>

#include "kernels/grid_view.hpp"
#include "kernels/mm_normals.hpp"

namespace mmpm {

// fixed[node]: bit d set where the node lies on a plane support normal to
// axis d that fixes axis d. mirror_side (or null): bit 2d set where such a
// plane is a mirror (kernels/mirror_supports.hpp) with the body on its +d
// side, bit 2d + 1 with it on the -d side. nodes: the multimaterial nodes.
//
// On a mirror the model's image is known: a field on the body's side that
// reaches the plane has the plane as a cut, not a face, and its image
// cancels the normal component there whatever its size. So its gradient
// loses that component wherever it points out through the plane (toward the
// ghost side), however much of the gradient it is: an interface crossing the
// plane at 90 degrees left a node half a cell off the interface on the plane
// with a gradient 85 degrees across it (bspline2), which the rule for other
// planes kept (docs/contact_validation.md §22). A component pointing into
// the body's side belongs to a material past the plane whose face lies on it
// (a rigid floor below the body's plane) and stays. A corner of two mirrors
// loses both.
template <int D, class Real>
void drop_gradients_across_planes(GridView<D, Real>& grid, const std::uint32_t* nodes,
                                  std::size_t count, const unsigned char* fixed,
                                  const unsigned char* mirror_side = nullptr) {
  if (grid.g[0] == nullptr || fixed == nullptr) return;
  constexpr unsigned kAll = (1u << D) - 1u;
  for (std::size_t k = 0; k < count; ++k) {
    const std::uint32_t node = nodes[k];
    const unsigned mask = fixed[node];
    if (mask == 0) continue;
    const unsigned side = mirror_side ? mirror_side[node] : 0u;
    unsigned mirrored = 0;  // axes with a mirror here
    for (int d = 0; d < D; ++d)
      if ((side >> (2 * d)) & 3u) mirrored |= 1u << d;
    const unsigned other = mask & ~mirrored;
    for (int f = 0; f < grid.fields; ++f) {
      const std::size_t i = grid.at(f, node);
      for (int d = 0; d < D; ++d) {
        if (!((mirrored >> d) & 1u)) continue;
        const Real c = Real(kDomainGradientOutward) * grid.g[std::size_t(d)][i];
        // The ghost side is -d for a body on +d: the outward gradient of the
        // body's cut points there.
        const bool out_through = (side >> (2 * d)) & 1u ? c < Real(0) : c > Real(0);
        if (out_through) grid.g[std::size_t(d)][i] = Real(0);
      }
      if (other == 0 || mask == kAll) continue;
      Real across = 0, along = 0;
      for (int d = 0; d < D; ++d) {
        const Real c = grid.g[std::size_t(d)][i];
        ((other >> d) & 1u ? across : along) += c * c;
      }
      // |g_in_plane| >= |g| / 2, squared: 4 along >= along + across.
      if (Real(3) * along < across) continue;
      for (int d = 0; d < D; ++d)
        if ((other >> d) & 1u) grid.g[std::size_t(d)][i] = Real(0);
    }
  }
}

}  // namespace mmpm
