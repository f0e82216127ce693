// USL's light nodes (update_deformable, kernels/grid_update.hpp): a field
// lighter than m_L at a node takes keep = m / m_L of its force into the
// momentum and the rest, the left-out velocity
//
//     dt (f + m g + f_interface) (1 − keep) / m,
//
// into dvel alone. What acts on the node after the update and holds its
// velocity (a support, a stuck partner, a rigid body) must take that part
// too, or the particles keep receiving it every step: the supports
// (kernels/supports.hpp) and pass B (kernels/mm_left_out.hpp) form it again
// here, with the update's formula.
#pragma once

#include <cmath>
#include <cstddef>

#include "kernels/grid_view.hpp"

namespace mmpm {

// Component d of field entry i's left-out velocity; 0 at a node heavier
// than light (every node when light = 0: MUSL, USF).
template <int D, class Real>
Real light_left_out(const GridView<D, Real>& G, std::size_t i, int d, Real m, Real light,
                    Real gravity, Real dt) {
  if (!(m <= light)) return Real(0);
  const Real keep = m * (Real(1) / light);
  Real force = std::fma(m, gravity, G.f[d][i]);
  if (G.fi[0]) force += G.fi[d][i];  // zero where no interface acted
  return dt * force * (Real(1) - keep) * (Real(1) / m);
}

}  // namespace mmpm
