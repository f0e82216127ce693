// The displacement an imperfect interface reads under MUSL
// (docs/interface_validation.md Finding 14).
//
// Why: MUSL moves a particle with the updated grid velocity v^L but takes
// its strain from the re-extrapolated velocity v* (Sulsky's MUSL). The
// interface's opening δ (ALGORITHM §3.2) is built from the displacements
// x - x0, so the bulk and the interface spring read two different motions,
// and they differ by the part of v^L the FLIP particles do not carry. An
// undamped vibration across the spring then gains energy exponentially
// (two bars at Dn = 100: 3.19 E0 after 3 ms; tools/interface_step_map.py:
// a growing mode of the frozen-weight step, 0.19 per ms). Moving the
// separation's displacement with v*, the motion the strain reads, keeps
// it (the same map: spectral radius 1; the bars 1.03 E0). The shift holds
// the difference, sum over the steps of dt S v* - (x_next - x), so x - x0
// itself (the displacement output) stays the particles' own, and in float
// the shift stays small where x - x0 would not. Used only where every
// spring is under the force limit (Stepper::shifts_separation says why).
//
// The solver advances the shift inside MUSL's gradient pass (G2PWhat
// kSeparationShift, detail::advance_shift), whose windows already hold S
// and v*: the separate pass below read the two-layer scene's multimaterial
// stage at 2.23 ms per step against 0.15 without it (163 840 particles).
// It stays as the reference the fused pass is tested and benchmarked
// against (tests/test_separation_shift.cpp, bench/bench_separation_shift.cpp).
#pragma once

#include <array>
#include <cstddef>

#include "kernels/g2p_particle.hpp"
#include "kernels/grid_view.hpp"
#include "kernels/particle_view.hpp"
#include "kernels/xpic.hpp"

namespace mmpm {

// Particles [begin, end): shift += dt S v* - (x_next - x), with S at the
// step's starting positions x and v* the nodal velocities `vstar` of each
// particle's field, in the interpolation's own pass (no scratch arrays);
// a rigid field's particles (rigid[field] != 0) keep their shift (their
// x - x0 is the prescribed motion itself). Returns the first particle
// whose stencil leaves the grid (its shift untouched), or end.
template <int D, class Shape, class Real>
std::size_t advance_separation_shift(const ParticleView<D, Real>& P, const GridView<D, Real>& G,
                                     const std::array<const Real*, D>& vstar,
                                     const unsigned char* rigid, Real dt, std::size_t begin,
                                     std::size_t end) {
  const ParticleView<D, Real> Pl = P;  // a local copy: the stores cannot alias it
  auto advance = [&](std::size_t p, const Real* sums) __attribute__((always_inline)) {
    detail::advance_shift(Pl, rigid, dt, p, sums);
  };
  return interpolate_to_particles_into<D, Shape, Real>(Pl, G, vstar, advance, begin, end);
}

}  // namespace mmpm
