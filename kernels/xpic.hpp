// XPIC(m) particle velocities (Hammerquist & Nairn 2017; docs/validation.md
// §3.12). FLIP keeps in the particle velocities a part the grid cannot see
// (the null space of the particle-to-grid map); on long runs of bodies that
// move across cells while they vibrate it grows (Brackbill's ringing: two
// disks with linear shapes gained 19 % of their energy after their
// collision by t = 3.5 at h = 1/160, 130 % by t = 6; uGIMP 1.7 % and
// 8.8 %). PIC removes it with everything the lumped projection smooths. XPIC(m) replaces the
// particle velocities, before the FLIP increment, by S v*, with v* the first m terms of the series
// for the projection onto the grid's velocity fields with the consistent mass matrix M_c = S^T M_p
// S:
//   M_c^-1 S^T M_p v_p = sum_{k=0}^{m-1} (I - A)^k v,   A = M_L^-1 S^T M_p S,
// v = M_L^-1 S^T M_p v_p the grid velocity of the step's P2G (M_L the lumped
// masses). m = 1 is PIC; each further term costs one interpolation to the
// particles and one mass-weighted scatter back (A). The last interpolation,
// S v*, rides on the step's FLIP G2P: its increment v_L - v takes v* more
// and the particles start from 0. Momentum is kept:
// sum_i m_i (A u)_i = sum_i m_i u_i, so every term after the first carries
// no momentum.
#pragma once

#include <array>
#include <cstddef>

#include "kernels/grid_view.hpp"
#include "kernels/particle_view.hpp"
#include "kernels/weight_batch.hpp"
#include "kernels/weights.hpp"
#include "kernels/window.hpp"

namespace mmpm {

// out_p = sum_i S_ip u_i over the nodes of particle p's field, for the
// particles [begin, end), node by node on each particle's stencil: the
// reference, and the path for grids too small for a window. Returns the
// first particle whose stencil leaves the grid (its out_p untouched), or end.
template <int D, class Shape, class Real, class Sink>
std::size_t interpolate_to_particles_pointwise(const ParticleView<D, Real>& P,
                                               const GridView<D, Real>& G,
                                               const std::array<const Real*, D>& u, Sink&& sink,
                                               std::size_t begin, std::size_t end) {
  const std::array<Real, 3> inv_h{Real(1) / G.h[0], Real(1) / G.h[1], Real(1) / G.h[2]};
  Stencil<D, Shape, Real> st{};
  for (std::size_t p = begin; p < end; ++p) {
    if (!st.build(P, G, inv_h, p)) return p;
    const std::size_t b = st.base + (P.field ? std::size_t(P.field[p]) * G.nodes : 0);
    Real s[D] = {};
    for (int k = 0; k < st.count; ++k)
      for (int d = 0; d < D; ++d) s[d] += st.w[k] * u[d][b + st.node[k]];
    sink(p, s);
  }
  return end;
}

// The same sums on the transfers' windows (kernels/window.hpp), weights a
// batch at a time: per unit A += Y(u) u_unit, then out = sum(X A), the
// G2P's velocity sum without its FLIP and gradient terms. Why: the
// stencil's per-particle build (weights and gradients, node by node) made
// the uGIMP interpolation ~6x a colored P2G of momenta, 40 % of an
// XPIC(4) step (2D disks at h = 1/160, docs/validation.md §3.12). bench
// xpic_interpolation, 1 thread, ns/particle, windowed against the stencil:
// 2D linear 3.0 / 3.2, uGIMP 4.9 / 16.2, quadratic B-spline 4.5 / 7.6, 3D
// linear 6.2 / 8.1, 3D uGIMP 11.5 / 117. The G2P's own gather (held
// windows, two particles per vector), tried through a velocity-and-change
// gather of u twice, was 6-16 % slower: it sums the change too. Holding a
// window's grid values for the particles that share it gained nothing
// (4.92 -> 5.01 ns, uGIMP).
template <int D, class Shape, class Real, class Sink>
std::size_t interpolate_to_particles_windowed(const ParticleView<D, Real>& P,
                                              const GridView<D, Real>& G,
                                              const std::array<const Real*, D>& u, Sink&& sink,
                                              std::size_t begin, std::size_t end) {
  using Win = Window<D, Shape, Real>;
  using Vec = typename Win::V;
  const WindowBuilder<D, Shape, Real> builder(G);
  const typename Win::Offsets off = Win::offsets(G);
  const ParticleView<D, Real> Pl = P;  // a local copy: the stores to out cannot alias it
  auto build = [&](std::size_t first, std::size_t n, Win * w, bool* ok)
      __attribute__((always_inline)) {
    builder.build_batch(Pl, first, n, w, ok);
  };
  auto body = [&](std::size_t p, const Win* w) __attribute__((always_inline)) {
    if (!w) return false;
    const std::size_t b = w->base + (Pl.field ? std::size_t(Pl.field[p]) * G.nodes : 0);
    Vec A[D] = {};
    static_for<Win::units>([&](auto uc) __attribute__((always_inline)) {
      constexpr int k = decltype(uc)::value;
      const Vec Yk = w->template Y<k>();
      for (int d = 0; d < D; ++d) A[d] += Yk * Win::template load<k>(u[d] + b, off);
    });
    const Vec X = w->X();
    if constexpr (Win::L >= 4) {
      // The D dot products in one shuffle tree, not D serial lane sums.
      using V4 = Lanes<Real, 4>;
      V4 f[3] = {};
      for (int d = 0; d < D; ++d) f[d] = lanes_fold4<Real, Win::L>(X * A[d]);
      const V4 sums = lanes_sum4(f[0], f[1], f[2], V4{});
      Real s[D];
      for (int d = 0; d < D; ++d) s[d] = sums[d];
      sink(p, s);
    } else {
      Real s[D];
      for (int d = 0; d < D; ++d) s[d] = lanes_sum<Real, Win::L>(X * A[d]);
      sink(p, s);
    }
    return true;
  };
  return for_each_weighted<Win>(begin, end, build, body);
}

// The solver's interpolation: windowed where the grid holds a window.
// sink(p, sums) takes particle p's D sums (sums[d] = out_p along d).
template <int D, class Shape, class Real, class Sink>
std::size_t interpolate_to_particles_into(const ParticleView<D, Real>& P,
                                          const GridView<D, Real>& G,
                                          const std::array<const Real*, D>& u, Sink&& sink,
                                          std::size_t begin, std::size_t end) {
  if (Window<D, Shape, Real>::fits(G))
    return interpolate_to_particles_windowed<D, Shape, Real>(P, G, u, sink, begin, end);
  return interpolate_to_particles_pointwise<D, Shape, Real>(P, G, u, sink, begin, end);
}

// A sink that stores the sums in D particle arrays: out[d][p] = sums[d].
template <class Real, std::size_t D>
auto into_arrays(const std::array<Real*, D>& out) {
  return [out](std::size_t p, const Real* sums) __attribute__((always_inline)) {
    for (std::size_t d = 0; d < D; ++d) out[d][p] = sums[d];
  };
}

// The same into D particle arrays.
template <int D, class Shape, class Real>
std::size_t interpolate_to_particles(const ParticleView<D, Real>& P, const GridView<D, Real>& G,
                                     const std::array<const Real*, D>& u,
                                     const std::array<Real*, D>& out, std::size_t begin,
                                     std::size_t end) {
  return interpolate_to_particles_into<D, Shape, Real>(P, G, u, into_arrays(out), begin, end);
}

// One more term of the series at nodes [begin, end): with q = S^T M_p S term
// (the scatter of the interpolated term), term <- term - q / m where the
// node holds mass above the threshold (A term = q / m), and sum += term.
// q is left zero for the next term's scatter (one node pass fewer).
template <int D, class Real>
void add_xpic_term(const Real* m, const std::array<Real*, D>& q, const std::array<Real*, D>& term,
                   const std::array<Real*, D>& sum, Real mass_threshold, std::size_t begin,
                   std::size_t end) {
  for (std::size_t i = begin; i < end; ++i) {
    const bool heavy = m[i] > mass_threshold;
    for (int d = 0; d < D; ++d) {
      term[d][i] -= heavy ? q[d][i] / m[i] : Real(0);
      sum[d][i] += term[d][i];
      q[d][i] = Real(0);
    }
  }
}

}  // namespace mmpm
