// A particle's position in float carries its own rounding error.
//
// Why: x is the sum of every step's move dt v. Near equilibrium a move is a
// few ulps of x or less (float at x = 10 mm: ulp 9.5e-7 mm), so each step
// rounds away up to half of it, and a move under half an ulp does not
// happen at all: the particle stops short of its static position. The
// series bars of docs/validation.md §1 at h = 0.25 mm (17 000 steps) then
// measured a compliance 19.5 % low in float against 0.43 % in double
// (docs/performance.md "Positions in float"). Kept here: lo, the part of
// each sum that x could not hold, added back into the next move
// (compensated summation, Kahan 1965; the error term is exact by
// Dekker's Fast2Sum when |x| >= |move + lo|, Knuth TAOCP vol. 2 §4.2.2).
// x + lo then holds the sum of the moves with an error of at most
// eps (|move| + ulp(x)) per step, the rounding of move + lo, instead of up
// to half an ulp of x; the cost is one array per axis, read and written
// where x is. Double needs
// none of it (ulp 1.8e-15 mm at 10 mm), so the double kernels never see
// lo (ParticleView::xlo null).
#pragma once

#include <cstddef>
#include <type_traits>

#include "kernels/particle_view.hpp"

namespace mmpm {

// x + move, returned rounded; lo: in, the error left by the last sum; out,
// the error of this one. T: a Real or a vector of Reals (Lanes).
template <class T>
[[gnu::always_inline]] inline T compensated_add(const T& x, T& lo, const T& move) {
  const T y = move + lo;
  const T s = x + y;
  lo = y - (s - x);
  return s;
}

// Particle p's coordinate d that the multimaterial separation is built from
// (ALGORITHM §1, w_p of mx): x with the position method, else the displacement
// x - x0, which in float also takes xlo (x - x0 of two nearby floats is
// exact, so the displacement is then as precise as the position sum), and
// under MUSL with an interface the shift of kernels/separation_shift.hpp.
template <int D, class Real>
[[gnu::always_inline]] inline Real separation_coordinate(const ParticleView<D, Real>& P,
                                                         bool position, int d, std::size_t p) {
  if (position) return P.x[d][p];
  Real u = P.x[d][p] - P.x0[d][p];
  if constexpr (std::is_same_v<Real, float>)
    if (P.xlo[0]) u += P.xlo[d][p];
  if (P.sep_shift[0]) u += P.sep_shift[d][p];
  return u;
}

}  // namespace mmpm
