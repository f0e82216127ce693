// Raw views of the particle arrays (SoA). Owned by model/particles.hpp.
// Stress components: 2D xx, yy, xy, zz; 3D xx, yy, zz, yz, xz, xy (Voigt).
// A pointer is null when the scene does not need that array.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace mmpm {

template <int D>
inline constexpr int kStressComponents = D == 2 ? 4 : 6;

// Two particles per cell and direction: a quarter cell.
template <int D, class Real>
constexpr std::array<Real, D> filled_half_widths() {
  std::array<Real, D> l{};
  l.fill(Real(0.25));
  return l;
}

template <int D, class Real>
struct ParticleView {
  std::size_t n = 0;
  std::array<Real*, D> x{};                     // position
  std::array<Real*, D> v{};                     // velocity
  Real* m = nullptr;                            // mass
  Real* V = nullptr;                            // current volume (area * thickness in 2D)
  std::array<Real*, kStressComponents<D>> s{};  // Cauchy stress
  std::array<Real*, D * D> L{};                 // velocity gradient from G2P, row-major dv_a/dx_b
  // Displacement gradient H = F - I, row-major (finite-strain materials
  // only). Stored instead of F so that small strains keep the precision of
  // Real: F's entries are ~1, and a float F lost strain increments below
  // 6e-8 (kernels/constitutive.hpp NeoHookeanPoint).
  std::array<Real*, D * D> H{};
  std::array<Real*, D> x0{};  // initial position (displacement output / separation)
  // uGIMP half-width in cell units (gimp only); null in direction d when
  // every particle has the same one, lp_all[d] (half_width below).
  std::array<Real*, D> lp{};
  std::array<Real, D> lp_all = filled_half_widths<D, Real>();
  std::array<Real*, D> fext{};    // external (traction) force (only with traction loads)
  std::uint8_t* field = nullptr;  // material velocity field (only with > 1 field)
  std::uint8_t* mat = nullptr;    // material index
  std::uint32_t* key = nullptr;   // binning key (tile-major cell index) at the last sort
  // MUSL only: G2P writes the updated positions here, so the second transfer
  // and the velocity gradient still use the shape functions of the step's
  // start (Sulsky's MUSL); the stepper copies them into x afterwards.
  std::array<Real*, D> x_next{};
  // float only: the low part of x, what x could not hold of the moves so far
  // (kernels/position_sum.hpp); the position is x + xlo. Null in double.
  std::array<Real*, D> xlo{};
  // MUSL with an imperfect interface only: what the displacement the
  // separation reads has moved beyond x - x0 (kernels/separation_shift.hpp).
  std::array<Real*, D> sep_shift{};
};

// A column pointer q with q[p] = block[p - first] for p >= first, so a
// kernel that indexes by particle can keep one range's values of a column
// in a block the size of that range (the fused tail's L,
// solver/stepper_impl.hpp). Made through the address, as q lies before the
// block; the flat address space of the targets we build for makes q[p]
// the block's element.
template <class T>
T* offset_for_range(T* block, std::size_t first) {
  return reinterpret_cast<T*>(reinterpret_cast<std::uintptr_t>(block) - first * sizeof(T));
}

// Particle p's uGIMP half-width in direction d (cell units): its column's
// value, or the one all particles share when the view has no column.
template <int D, class Real>
inline Real half_width(const ParticleView<D, Real>& P, int d, std::size_t p) {
  return P.lp[std::size_t(d)] ? P.lp[std::size_t(d)][p] : P.lp_all[std::size_t(d)];
}

}  // namespace mmpm
