// Constitutive updates, one kernel per material type over that type's
// particles (ARCHITECTURE "one constitutive kernel per type"). Small-strain
// materials integrate sigma += C : d_eps with d_eps = dt sym(L); the
// finite-strain neo-Hookean material updates F and evaluates sigma(F).
// Volumes follow det(I + dt L) (small strain) or J V0 (finite strain).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "kernels/particle_view.hpp"
#include "kernels/reduce.hpp"

namespace mmpm {

// Material constants prepared once by model/material.cpp.
struct ElasticKernelConstants {
  double lambda = 0, mu = 0;  // isotropic / neo-Hookean (plane strain & 3D)
  double Ep = 0, nu = 0;      // plane stress isotropic: E/(1-nu^2), nu
  double density = 1;
  bool plane_stress = false;
  // General small-strain stiffness in the global frame. 2D: rows
  // (d_sxx, d_syy, d_sxy, d_szz) from columns (d_exx, d_eyy, d_gxy) — plane
  // strain or plane stress reduced; zz_strain gives d_ezz (plane stress).
  // 3D: 6x6 Voigt (xx, yy, zz, yz, xz, xy) with engineering shear strains.
  double C2[4][3] = {};
  double zz_strain[3] = {};
  double C3[6][6] = {};
};

template <int D, class Real>
inline Real volume_ratio(const ParticleView<D, Real>& P, std::size_t p, Real dt) {
  if constexpr (D == 2) {
    const Real a = Real(1) + dt * P.L[0][p], b = dt * P.L[1][p];
    const Real c = dt * P.L[2][p], d = Real(1) + dt * P.L[3][p];
    return a * d - b * c;
  } else {
    Real A[9];
    for (int i = 0; i < 9; ++i) A[i] = dt * P.L[i][p] + ((i % 4) == 0 ? Real(1) : Real(0));
    return A[0] * (A[4] * A[8] - A[5] * A[7]) - A[1] * (A[3] * A[8] - A[5] * A[6]) +
           A[2] * (A[3] * A[7] - A[4] * A[6]);
  }
}

// Lame's lambda and 2 mu of one particle.
template <class Real>
struct Moduli {
  Real lam, mu2;
};

// 2D plane stress: E/(1 - nu^2), nu, and nu/(1 - nu) for the thickness
// strain's share of the volume change.
template <class Real>
struct PlaneStress {
  Real Ep, nu, zz;
};

// The small-strain isotropic update of particles [first, last), the
// moduli of particle p from moduli(p): the loop shared by
// IsotropicPoint::range (one material; plane stress through `ps` when
// PlaneStressLaw) and IsotropicByMaterial (a lookup by material). Restrict
// pointers, no branch: it vectorises. Same arithmetic as
// IsotropicPoint::operator().
template <int D, class Real, bool PlaneStressLaw = false, class ModuliOf>
[[gnu::always_inline]] inline void isotropic_strain_loop(const ParticleView<D, Real>& P, Real dt,
                                                         std::size_t first, std::size_t last,
                                                         const ModuliOf& moduli,
                                                         const PlaneStress<Real>& ps = {}) {
  static_assert(D == 2 || !PlaneStressLaw, "plane stress is a 2D law");
  Real* __restrict V = P.V;
  if constexpr (D == 2) {
    const Real* __restrict L0 = P.L[0];
    const Real* __restrict L1 = P.L[1];
    const Real* __restrict L2 = P.L[2];
    const Real* __restrict L3 = P.L[3];
    Real* __restrict s0 = P.s[0];
    Real* __restrict s1 = P.s[1];
    Real* __restrict s2 = P.s[2];
    Real* __restrict s3 = P.s[3];
#pragma GCC ivdep
    for (std::size_t p = first; p < last; ++p) {
      const Moduli<Real> k = moduli(p);
      const Real exx = dt * L0[p], eyy = dt * L3[p];
      const Real exy = Real(0.5) * dt * (L1[p] + L2[p]);
      const Real a = Real(1) + exx, b = dt * L1[p], c = dt * L2[p], d = Real(1) + eyy;
      if constexpr (PlaneStressLaw) {
        s0[p] += ps.Ep * (exx + ps.nu * eyy);
        s1[p] += ps.Ep * (eyy + ps.nu * exx);
        s2[p] += k.mu2 * exy;
        V[p] *= (a * d - b * c) * (Real(1) - ps.zz * (exx + eyy));
      } else {
        const Real tr = k.lam * (exx + eyy);
        s0[p] += tr + k.mu2 * exx;
        s1[p] += tr + k.mu2 * eyy;
        s2[p] += k.mu2 * exy;
        s3[p] += tr;
        V[p] *= a * d - b * c;
      }
    }
  } else {
    const Real* __restrict L[9];
    Real* __restrict s[6];
    for (int i = 0; i < 9; ++i) L[i] = P.L[i];
    for (int i = 0; i < 6; ++i) s[i] = P.s[i];
#pragma GCC ivdep
    for (std::size_t p = first; p < last; ++p) {
      const Moduli<Real> k = moduli(p);
      Real A[9];
      for (int i = 0; i < 9; ++i) A[i] = dt * L[i][p] + ((i % 4) == 0 ? Real(1) : Real(0));
      const Real e0 = dt * L[0][p], e1 = dt * L[4][p], e2 = dt * L[8][p];
      const Real tr = k.lam * (e0 + e1 + e2);
      s[0][p] += tr + k.mu2 * e0;
      s[1][p] += tr + k.mu2 * e1;
      s[2][p] += tr + k.mu2 * e2;
      s[3][p] += Real(0.5) * k.mu2 * dt * (L[5][p] + L[7][p]);  // yz
      s[4][p] += Real(0.5) * k.mu2 * dt * (L[2][p] + L[6][p]);  // xz
      s[5][p] += Real(0.5) * k.mu2 * dt * (L[1][p] + L[3][p]);  // xy
      V[p] *= A[0] * (A[4] * A[8] - A[5] * A[7]) - A[1] * (A[3] * A[8] - A[5] * A[6]) +
              A[2] * (A[3] * A[7] - A[4] * A[6]);
    }
  }
}

// Per-particle updates: one functor per material type, applied to particle
// p. The Stepper's constitutive pass runs them over each thread's block of
// particles (update_particles); with fuse_constitutive the G2P gradient
// pass runs the isotropic one straight after L (kernels/g2p.hpp
// kStressUpdate; docs/performance.md measured no gain).
template <int D, class Real>
struct IsotropicPoint {
  Real dt = 0, lam = 0, mu2 = 0, Ep = 0, nu = 0;
  bool pstress = false;
  IsotropicPoint() = default;
  IsotropicPoint(const ElasticKernelConstants& c, double dt_in)
      : dt(Real(dt_in)),
        lam(Real(c.lambda)),
        mu2(Real(2 * c.mu)),
        Ep(Real(c.Ep)),
        nu(Real(c.nu)),
        pstress(c.plane_stress) {}
  void operator()(const ParticleView<D, Real>& P, std::size_t p) const {
    if constexpr (D == 2) {
      const Real exx = dt * P.L[0][p], eyy = dt * P.L[3][p];
      const Real exy = Real(0.5) * dt * (P.L[1][p] + P.L[2][p]);
      Real J = volume_ratio(P, p, dt);
      if (pstress) {
        P.s[0][p] += Ep * (exx + nu * eyy);
        P.s[1][p] += Ep * (eyy + nu * exx);
        P.s[2][p] += mu2 * exy;
        J *= Real(1) - nu / (Real(1) - nu) * (exx + eyy);
      } else {
        const Real tr = lam * (exx + eyy);
        P.s[0][p] += tr + mu2 * exx;
        P.s[1][p] += tr + mu2 * eyy;
        P.s[2][p] += mu2 * exy;
        P.s[3][p] += tr;
      }
      P.V[p] *= J;
    } else {
      const Real e0 = dt * P.L[0][p], e1 = dt * P.L[4][p], e2 = dt * P.L[8][p];
      const Real tr = lam * (e0 + e1 + e2);
      P.s[0][p] += tr + mu2 * e0;
      P.s[1][p] += tr + mu2 * e1;
      P.s[2][p] += tr + mu2 * e2;
      P.s[3][p] += Real(0.5) * mu2 * dt * (P.L[5][p] + P.L[7][p]);  // yz
      P.s[4][p] += Real(0.5) * mu2 * dt * (P.L[2][p] + P.L[6][p]);  // xz
      P.s[5][p] += Real(0.5) * mu2 * dt * (P.L[1][p] + P.L[3][p]);  // xy
      P.V[p] *= volume_ratio(P, p, dt);
    }
  }
  // Particles [first, last): the same arithmetic as operator(), as a loop
  // the compiler vectorises. Why: called per particle, the update stayed a
  // scalar call (GCC did not inline it, and the view's arrays may alias for
  // all it knows); this loop reads the arrays through restrict pointers
  // with the plane-stress branch hoisted (docs/performance.md "Loops the
  // compiler vectorises").
  void range(const ParticleView<D, Real>& P, std::size_t first, std::size_t last) const {
    const auto moduli = [this](std::size_t) { return Moduli<Real>{lam, mu2}; };
    if constexpr (D == 2) {
      if (pstress) {
        isotropic_strain_loop<D, Real, true>(P, dt, first, last, moduli,
                                             PlaneStress<Real>{Ep, nu, nu / (Real(1) - nu)});
        return;
      }
    }
    isotropic_strain_loop(P, dt, first, last, moduli);
  }
};

// The isotropic update of several isotropic materials in one contiguous
// loop: each particle's constants are looked up by its material byte, so
// no per-material particle lists are needed and the loop vectorises (the
// lists made it a gather loop of per-particle calls). Same arithmetic as
// IsotropicPoint. Plane strain only (plane stress keeps the lists).
template <int D, class Real>
struct IsotropicByMaterial {
  Real dt = 0;
  std::array<Real, 256> lam{}, mu2{};  // by material index (P.mat)

  void range(const ParticleView<D, Real>& P, std::size_t first, std::size_t last) const {
    if (first >= last) return;
    const std::uint8_t* __restrict mat = P.mat;
    // One material in the whole range (a tile inside one body, the common
    // case): its constants as scalars. The looked-up loop gathers them per
    // particle, and measured 4.3 against 2.8 ns/particle for one material
    // (2D uGIMP two-layer scene, bench/RESULTS.md §5). Same arithmetic.
    const std::uint8_t m0 = mat[first];
    unsigned other = 0;
#pragma omp simd reduction(| : other)
    for (std::size_t p = first; p < last; ++p) other |= unsigned(mat[p] != m0);
    if (!other) {
      const Moduli<Real> k{lam[m0], mu2[m0]};
      isotropic_strain_loop(P, dt, first, last, [k](std::size_t) { return k; });
      return;
    }
    isotropic_strain_loop(P, dt, first, last, [&](std::size_t p) {
      return Moduli<Real>{lam[mat[p]], mu2[mat[p]]};
    });
  }
};

template <int D, class Real>
struct AnisotropicPoint {
  Real dt = 0, C2[4][3] = {}, Z[3] = {}, C3[6][6] = {};
  bool pstress = false;
  AnisotropicPoint() = default;
  AnisotropicPoint(const ElasticKernelConstants& c, double dt_in)
      : dt(Real(dt_in)), pstress(c.plane_stress) {
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 3; ++j) C2[i][j] = Real(c.C2[i][j]);
    for (int j = 0; j < 3; ++j) Z[j] = Real(c.zz_strain[j]);
    for (int i = 0; i < 6; ++i)
      for (int j = 0; j < 6; ++j) C3[i][j] = Real(c.C3[i][j]);
  }
  void operator()(const ParticleView<D, Real>& P, std::size_t p) const {
    if constexpr (D == 2) {
      const Real e[3] = {dt * P.L[0][p], dt * P.L[3][p], dt * (P.L[1][p] + P.L[2][p])};
      for (int i = 0; i < 4; ++i) P.s[i][p] += C2[i][0] * e[0] + C2[i][1] * e[1] + C2[i][2] * e[2];
      Real J = volume_ratio(P, p, dt);
      if (pstress) J *= Real(1) + Z[0] * e[0] + Z[1] * e[1] + Z[2] * e[2];
      P.V[p] *= J;
    } else {
      const Real e[6] = {dt * P.L[0][p],
                         dt * P.L[4][p],
                         dt * P.L[8][p],
                         dt * (P.L[5][p] + P.L[7][p]),
                         dt * (P.L[2][p] + P.L[6][p]),
                         dt * (P.L[1][p] + P.L[3][p])};
      for (int i = 0; i < 6; ++i) {
        Real ds = 0;
        for (int j = 0; j < 6; ++j) ds += C3[i][j] * e[j];
        P.s[i][p] += ds;
      }
      P.V[p] *= volume_ratio(P, p, dt);
    }
  }
};

// Compressible neo-Hookean: sigma = mu/J (B - I) + lambda ln(J)/J I,
// F <- (I + dt L) F. Plane strain in 2D (F_zz = 1).
//
// Written in H = F - I (ParticleView::H): H <- H + dt L (I + H), and
// B - I = H + H^T + H H^T, J - 1 = tr H + (sum of H's principal 2x2
// minors) + det H, ln J = log1p(J - 1). Why: in F itself a strain is the
// small difference of entries ~1, so float kept it to ~1e-7 absolute and
// lost every increment below half that; near a static state the strain
// then stopped short and the particles kept moving. The series bars in
// neo-Hookean (plane strain, h = 0.25 mm, Dn = 10, float positions
// compensated) measured the top displacement 3.7x the double run's
// (docs/performance.md "Strains in float"). In H no term is 1 + small - 1.
template <int D, class Real>
struct NeoHookeanPoint {
  Real dt = 0, lam = 0, mu = 0, inv_rho = 0;
  NeoHookeanPoint() = default;
  NeoHookeanPoint(const ElasticKernelConstants& c, double dt_in)
      : dt(Real(dt_in)), lam(Real(c.lambda)), mu(Real(c.mu)), inv_rho(Real(1 / c.density)) {}
  void operator()(const ParticleView<D, Real>& P, std::size_t p) const {
    Real A[D * D], H[D * D], Hn[D * D];
    for (int i = 0; i < D * D; ++i) {
      A[i] = dt * P.L[i][p];
      H[i] = P.H[i][p];
    }
    // Hn = H + A + A H, i.e. (I + A)(I + H) - I
    for (int i = 0; i < D; ++i)
      for (int j = 0; j < D; ++j) {
        Real s = A[i * D + j];
        for (int k = 0; k < D; ++k) s += A[i * D + k] * H[k * D + j];
        Hn[i * D + j] = H[i * D + j] + s;
      }
    for (int i = 0; i < D * D; ++i) P.H[i][p] = Hn[i];
    auto h = [&](int i, int j) { return Hn[i * D + j]; };
    Real Jm1;  // J - 1 = det(I + Hn) - 1
    if constexpr (D == 2) {
      Jm1 = (h(0, 0) + h(1, 1)) + (h(0, 0) * h(1, 1) - h(0, 1) * h(1, 0));
    } else {
      const Real minors = (h(0, 0) * h(1, 1) - h(0, 1) * h(1, 0)) +
                          (h(0, 0) * h(2, 2) - h(0, 2) * h(2, 0)) +
                          (h(1, 1) * h(2, 2) - h(1, 2) * h(2, 1));
      const Real det = h(0, 0) * (h(1, 1) * h(2, 2) - h(1, 2) * h(2, 1)) -
                       h(0, 1) * (h(1, 0) * h(2, 2) - h(1, 2) * h(2, 0)) +
                       h(0, 2) * (h(1, 0) * h(2, 1) - h(1, 1) * h(2, 0));
      Jm1 = (h(0, 0) + h(1, 1) + h(2, 2)) + minors + det;
    }
    // J <= 0 (Jm1 <= -1) is caught by the finiteness check through
    // log1p = -inf or NaN.
    const Real J = Real(1) + Jm1;
    const Real lnJ = std::log1p(Jm1), inv_J = Real(1) / J;
    // B - I, entry (i, j)
    auto bm = [&](int i, int j) {
      Real s = h(i, j) + h(j, i);
      for (int k = 0; k < D; ++k) s += h(i, k) * h(j, k);
      return s;
    };
    const Real pr = lam * lnJ * inv_J, c = mu * inv_J;
    if constexpr (D == 2) {
      P.s[0][p] = c * bm(0, 0) + pr;
      P.s[1][p] = c * bm(1, 1) + pr;
      P.s[2][p] = c * bm(0, 1);
      P.s[3][p] = pr;
    } else {
      P.s[0][p] = c * bm(0, 0) + pr;
      P.s[1][p] = c * bm(1, 1) + pr;
      P.s[2][p] = c * bm(2, 2) + pr;
      P.s[3][p] = c * bm(1, 2);
      P.s[4][p] = c * bm(0, 2);
      P.s[5][p] = c * bm(0, 1);
    }
    P.V[p] = P.m[p] * inv_rho * J;
  }
};

// Entries [first, last) of a particle list (idx) or, without a list,
// particles [first, last), on the calling thread.
template <int D, class Real, class Update>
inline void update_particles(const ParticleView<D, Real>& P, const std::uint32_t* idx,
                             std::size_t first, std::size_t last, const Update& f) {
  if (idx) {
    for (std::size_t k = first; k < last; ++k) f(P, std::size_t(idx[k]));
  } else if constexpr (requires { f.range(P, first, last); }) {
    f.range(P, first, last);
  } else {
    for (std::size_t k = first; k < last; ++k) f(P, k);
  }
}

// A stressed particle is sound when its volume is positive and finite and
// its stress finite (an inverted or blown-up particle fails this).
template <int D, class Real>
inline bool particle_sound(const ParticleView<D, Real>& P, std::size_t p) {
  return P.V[p] > Real(0) && std::isfinite(P.V[p]) && std::isfinite(P.s[0][p]);
}

// The first particle of [lo, hi) that is not sound, or SIZE_MAX. The test
// runs as a vectorised flag over chunks (x - x == 0 holds exactly for finite
// x); only a chunk that holds a bad particle is searched particle by particle.
template <int D, class Real>
inline std::size_t first_unsound(const ParticleView<D, Real>& P, std::size_t lo, std::size_t hi) {
  constexpr std::size_t kChunk = 512;
  const Real* __restrict V = P.V;
  const Real* __restrict s0 = P.s[0];
  for (std::size_t b = lo; b < hi; b += kChunk) {
    const std::size_t e = std::min(hi, b + kChunk);
    int good = 1;
    for (std::size_t p = b; p < e; ++p) {
      const Real v = V[p], s = s0[p];
      good &= int(v > Real(0)) & int(v - v == Real(0)) & int(s - s == Real(0));
    }
    const bool bad = good == 0;
    if (bad)
      for (std::size_t p = b; p < e; ++p)
        if (!particle_sound(P, p)) return p;
  }
  return SIZE_MAX;
}

// The fused update (kernels/g2p.hpp kStressUpdate) for scenes whose
// stressed materials are all isotropic, the common case. The isotropic
// update is a dozen multiply-adds with no calls; a per-particle switch
// over every model (the neo-Hookean one calls log) made the fused 2D linear
// step slower than two passes (docs/performance.md), so the other types
// keep their own pass.
template <int D, class Real>
struct IsotropicStressUpdate {
  struct Entry {
    IsotropicPoint<D, Real> update;
    bool stressed = false;  // false: rigid (no stress, no volume change)
  };
  const Entry* table = nullptr;  // per material
  // Updates sigma and V of particle p from its L; false when the particle
  // is no longer sound.
  [[gnu::always_inline]] bool operator()(const ParticleView<D, Real>& P, std::size_t p) const {
    const Entry& e = table[P.mat[p]];
    if (e.stressed) e.update(P, p);
    return particle_sound(P, p);
  }
};

// No stress update (G2P passes without kStressUpdate).
struct NoStressUpdate {
  template <class View>
  bool operator()(const View&, std::size_t) const {
    return true;
  }
};

}  // namespace mmpm
