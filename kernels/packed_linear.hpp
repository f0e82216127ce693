// K particles of one 2D linear window in one 64-byte vector (K = 2 in
// double, 4 in float): the lane layout the packed scatter
// (kernels/p2g_packed.hpp) and the packed gather (kernels/g2p_packed.hpp)
// share. Lane k * 4 + l is particle slot k, window lane l (x node l % 2,
// row l / 2), the one-particle window's layout (kernels/window.hpp) once
// per slot.
//
// Why: a 2D linear window is 4 lanes, half an AVX-512 register in double
// and a quarter in float, so the one-particle kernels ran every vector
// operation at that fraction of the register (docs/performance.md "Two or
// four particles per vector").
#pragma once

#include <immintrin.h>

#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <utility>

#include "kernels/shape.hpp"
#include "kernels/window.hpp"
#include "kernels/window_block.hpp"

namespace mmpm {

// Particles per vector of the packed kernels (1: they do not apply). Needs
// AVX-512 (PackedLinearLanes' widening); elsewhere the one-particle kernels
// run.
template <int D, class Shape, class Real>
constexpr int packed_particles() {
#ifdef __AVX512F__
  if constexpr (D != 2 || !std::is_same_v<Shape, LinearShape>)
    return 1;
  else
    return 64 / int(sizeof(typename Window<D, Shape, Real>::V));
#else
  return 1;
#endif
}

// The window lanes of K particles: weights X (x factor), Y (y factor) and
// the derivatives GX, GY (already divided by h), bitwise the lanes of
// WindowBuilder::shape with LinearShape::lanes (weight 1 - |d|, derivative
// sign(-d) / h, d = r - node), plus the shuffles between K-lane,
// 4-lane and K x 4-lane vectors.
template <class Real, int K>
struct PackedLinearLanes {
  using Win = Window<2, LinearShape, Real>;
  static constexpr int L = Win::L;  // 4
  static constexpr int N = K * L;   // lanes of a packed vector
  using V = typename Win::V;
  using VW = Lanes<Real, N>;
  using S = Lanes<Real, K>;
  static_assert(L == 4 && sizeof(VW) == 64);

  VW X, Y, GX, GY;

  // From the distances rx, ry of K particles to their window base (cell
  // units, as locate_batch stores them).
  [[gnu::always_inline]] static PackedLinearLanes of(const S& rx, const S& ry, Real inv_hx,
                                                     Real inv_hy) {
    const VW dx = spread(rx) + node_offsets([](int l) { return l % 2; });
    const VW dy = spread(ry) + node_offsets([](int l) { return l / 2; });
    PackedLinearLanes w;
    w.X = Real(1) - lanes_abs(dx);
    w.Y = Real(1) - lanes_abs(dy);
    w.GX = dx < Real(0) ? inv_hx + VW{} : -inv_hx + VW{};
    w.GY = dy < Real(0) ? inv_hy + VW{} : -inv_hy + VW{};
    return w;
  }

  // Lane k * L + l = s[k]: a particle's value over its 4 lanes.
  [[gnu::always_inline]] static VW spread(const S& s) {
    return pick(widen(s), [](int j) { return j / L; });
  }
  // Lane k * L + l = v[l]: one window's values in every slot (v is 32
  // bytes in double, 16 in float: one broadcast; the zero-masking form, as
  // the plain one reads an "undefined" vector, see widen).
  [[gnu::always_inline]] static VW repeat(const V& v) {
    if constexpr (std::is_same_v<Real, double>)
      return VW(_mm512_maskz_broadcast_f64x4(__mmask8(0xff), __m256d(v)));
    else
      return VW(_mm512_maskz_broadcast_f32x4(__mmask16(0xffff), __m128(v)));
  }

  // Per slot k, the lane sums of a, b, c, d in lanes k * L .. k * L + 3,
  // each added as lanes_sum4 adds one window's: (l0 + l1) + (l2 + l3), so
  // the same bits as the one-particle gather.
  [[gnu::always_inline]] static VW sum4(const VW& a, const VW& b, const VW& c, const VW& d) {
    // Within each slot, lanes_sum4's shuffles (second operand: lane + N).
    // ab = {a0 + a1, b0 + b1, a2 + a3, b2 + b3} per slot, then
    // {ab0 + ab2, ab1 + ab3, cd0 + cd2, cd1 + cd3}.
    constexpr auto lo = [](int j) { return slot(j) + (j % 2 == 0 ? j % 4 : N + j % 4 - 1); };
    constexpr auto hi = [](int j) { return slot(j) + (j % 2 == 0 ? j % 4 : N + j % 4 - 1) + 1; };
    constexpr auto first = [](int j) { return slot(j) + (j % 4 < 2 ? j % 4 : N + j % 4 - 2); };
    constexpr auto second = [](int j) { return slot(j) + (j % 4 < 2 ? j % 4 : N + j % 4 - 2) + 2; };
    const VW ab = pick2(a, b, lo) + pick2(a, b, hi);
    const VW cd = pick2(c, d, lo) + pick2(c, d, hi);
    return pick2(ab, cd, first) + pick2(ab, cd, second);
  }

 private:
  static constexpr int slot(int j) { return j / L * L; }

  // x (16 bytes) in the low lanes of a 64-byte vector, the rest 0.
  // (GCC 12 widens a short vector extension through the stack, a store and
  // a wider load that cannot be forwarded: 30 instead of 5.5 ns/particle in
  // the scatter. Hence the zero-extending intrinsics; the casting ones and
  // _mm512_permutexvar read an "undefined" vector that GCC 12 reports as
  // uninitialised.)
  [[gnu::always_inline]] static VW widen(const S& x) {
    static_assert(sizeof(S) == 16);
    if constexpr (std::is_same_v<Real, double>)
      return VW(_mm512_zextpd128_pd512(__m128d(x)));
    else
      return VW(_mm512_zextps128_ps512(__m128(x)));
  }
  template <class F, std::size_t... I>
  [[gnu::always_inline]] static VW pick_of(const VW& w, F, std::index_sequence<I...>) {
    return __builtin_shufflevector(w, w, F{}(int(I))...);
  }
  template <class F>
  [[gnu::always_inline]] static VW pick(const VW& w, F f) {
    return pick_of(w, f, std::make_index_sequence<N>{});
  }
  template <class F, std::size_t... I>
  [[gnu::always_inline]] static VW pick2_of(const VW& a, const VW& b, F,
                                            std::index_sequence<I...>) {
    return __builtin_shufflevector(a, b, F{}(int(I))...);
  }
  template <class F>
  [[gnu::always_inline]] static VW pick2(const VW& a, const VW& b, F f) {
    return pick2_of(a, b, f, std::make_index_sequence<N>{});
  }
  // Lane k * L + l = -node(l), the offset WindowBuilder adds to the distance.
  template <class F>
  static VW node_offsets(F node) {
    VW v{};
    for (int j = 0; j < N; ++j) v[j] = Real(-node(j % L));  // +0 for node 0, as there
    return v;
  }
};

// One batch of the packed kernels, located: each particle's distances to
// its window base (cell units), the base and whether its stencil stays on
// the grid (WindowBuilder::locate_batch), plus K zero distances past the
// batch so that a group of K read at a run's end stays finite. Particles
// come in runs of one window and field (consecutive in tile order).
template <class Real, int K, bool MultiField>
struct PackedBatch {
  static constexpr std::size_t N = kWeightBatch + K;
  using S = Lanes<Real, K>;
  Real dist[2][N];
  std::uint64_t base[N];
  int inside[N];
  std::size_t first = 0;  // the batch's first particle

  // Particles first_particle .. first_particle + n - 1 (n <= kWeightBatch).
  [[gnu::always_inline]] void locate(const WindowBuilder<2, LinearShape, Real>& builder,
                                     const ParticleView<2, Real>& P, std::size_t first_particle,
                                     std::size_t n) {
    first = first_particle;
    builder.locate_batch(P, first, n, dist, base, inside);
    for (int d = 0; d < 2; ++d)
      for (int k = 0; k < K; ++k) dist[d][n + std::size_t(k)] = Real(0);
  }
  // Window base of batch particle i, with its field's offset.
  [[gnu::always_inline]] std::size_t window(const ParticleView<2, Real>& P,
                                            const GridView<2, Real>& G, std::size_t i) const {
    return base[i] + field_offset<MultiField>(P, G, first + i);
  }
  // One past the last particle of the run that starts at i (inside, window
  // b), at most n.
  [[gnu::always_inline]] std::size_t run_end(const ParticleView<2, Real>& P,
                                             const GridView<2, Real>& G, std::size_t i,
                                             std::size_t b, std::size_t n) const {
    std::size_t j = i + 1;
    while (j < n && inside[j] && window(P, G, j) == b) ++j;
    return j;
  }
  // Distances of batch particles k .. k + K - 1, one lane each.
  [[gnu::always_inline]] S dx(std::size_t k) const { return lanes_load<S>(&dist[0][k]); }
  [[gnu::always_inline]] S dy(std::size_t k) const { return lanes_load<S>(&dist[1][k]); }
};

}  // namespace mmpm
