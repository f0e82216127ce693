// Short fixed-width vectors (GCC/Clang vector extensions) for the window
// kernels: one vector holds the W nodes of a window row along x
// (kernels/window.hpp), so a row's weights, accumulators and grid values are
// each one register (W = 4 doubles: 256 bits). Arithmetic between a vector
// and a scalar broadcasts the scalar; comparisons give lane masks that ?:
// selects with. Loads and stores go through memcpy: grid rows start at any
// node, so they are unaligned.
#pragma once

#include <cstddef>
#include <cstring>
#include <type_traits>
#include <utility>

namespace mmpm {

template <class Real, int W>
struct LanesOf {
  typedef Real type __attribute__((vector_size(sizeof(Real) * W)));
};
template <class Real, int W>
using Lanes = typename LanesOf<Real, W>::type;

// The scalar type of a vector's lanes.
template <class V>
using LaneReal = std::remove_cvref_t<decltype(std::declval<V>()[0])>;

// Bytes of the widest vector register the target has.
#if defined(__AVX512F__)
inline constexpr std::size_t kRegisterVectorBytes = 64;
#elif defined(__AVX__)
inline constexpr std::size_t kRegisterVectorBytes = 32;
#else
inline constexpr std::size_t kRegisterVectorBytes = 16;
#endif

// Loads and stores of a vector wider than the target's registers (a row of
// 4 doubles, 32 bytes, under SSE2) go register-sized half by half. Why: GCC
// has no machine mode for such a vector, so a whole-vector memcpy went
// through a stack copy (a row's read-modify-write: two 16-byte stores to
// the stack and two loads back before the two stores to the grid; a
// 64-byte vector under AVX2: 32-byte stores read back by 16-byte loads,
// which the store buffer cannot forward; docs/performance.md "Targets
// without AVX-512"). The halves are the same bytes, so the results are too.
template <class V>
inline V lanes_load(const void* p) {
  if constexpr (sizeof(V) > kRegisterVectorBytes) {
    using Real = LaneReal<V>;
    constexpr int n = int(sizeof(V) / sizeof(Real));
    using H = Lanes<Real, n / 2>;
    const H lo = lanes_load<H>(p);
    const H hi = lanes_load<H>(static_cast<const char*>(p) + sizeof(H));
    return [&]<std::size_t... I>(std::index_sequence<I...>) {
      return __builtin_shufflevector(lo, hi, int(I)...);
    }
    (std::make_index_sequence<std::size_t(n)>{});
  } else {
    V v;
    std::memcpy(&v, p, sizeof(V));
    return v;
  }
}
template <class V>
inline void lanes_store(void* p, const V& v) {
  if constexpr (sizeof(V) > kRegisterVectorBytes) {
    using Real = LaneReal<V>;
    constexpr int n = int(sizeof(V) / sizeof(Real));
    using H = Lanes<Real, n / 2>;
    const auto half = [&]<std::size_t... I>(auto first, std::index_sequence<I...>) {
      return __builtin_shufflevector(v, v, decltype(first)::value + int(I)...);
    };
    lanes_store(p, half(std::integral_constant<int, 0>{}, std::make_index_sequence<n / 2>{}));
    lanes_store(static_cast<char*>(p) + sizeof(H),
                half(std::integral_constant<int, n / 2>{}, std::make_index_sequence<n / 2>{}));
  } else {
    std::memcpy(p, &v, sizeof(V));
  }
}
// Lanes 0, 1, ..., W-1.
template <class V, int W>
inline V lanes_iota() {
  V v{};
  for (int k = 0; k < W; ++k) v[k] = k;
  return v;
}
// |a| by clearing the sign bit (one instruction; a select would be two).
template <class V>
inline V lanes_abs(const V& a) {
  using Bits = decltype(a < a);         // same-width integer lanes
  return (V)((Bits)a & ~(Bits)(-V{}));  // -V{}: lanes of -0.0, the sign bit alone
}
// max/min in the operand order of the x86 instructions (a > b ? a : b is
// vmaxp a, b: b when they compare equal or either is a NaN). Written as
// those instructions for 512-bit vectors: GCC 12 compiled the selects to a
// compare into a mask and a blend (two instructions, the compare on the
// one port that also shuffles) once the bounds were constants, as in the
// uGIMP clamps (kernels/shape.hpp). By inline assembly: _mm512_max_pd
// drew -Wmaybe-uninitialized (its undefined pass-through), and the masked
// builtin with a zero pass-through crashed GCC 12's SLP vectoriser on
// tests/test_p2g.cpp.
template <class V>
inline V lanes_max(const V& a, const V& b) {
#if defined(__AVX512F__)
  if constexpr (sizeof(V) == 64) {
    V r;
    if constexpr (std::is_same_v<LaneReal<V>, double>)
      asm("vmaxpd %2, %1, %0" : "=v"(r) : "v"(a), "v"(b));
    else
      asm("vmaxps %2, %1, %0" : "=v"(r) : "v"(a), "v"(b));
    return r;
  }
#endif
  return a > b ? a : b;
}
template <class V>
inline V lanes_min(const V& a, const V& b) {
#if defined(__AVX512F__)
  if constexpr (sizeof(V) == 64) {
    V r;
    if constexpr (std::is_same_v<LaneReal<V>, double>)
      asm("vminpd %2, %1, %0" : "=v"(r) : "v"(a), "v"(b));
    else
      asm("vminps %2, %1, %0" : "=v"(r) : "v"(a), "v"(b));
    return r;
  }
#endif
  return a < b ? a : b;
}
template <class V>
inline V lanes_clamp(const V& a, const V& lo, const V& hi) {
  return lanes_min(lanes_max(a, lo), hi);
}
template <class Real, int W, class V>
inline Real lanes_sum(const V& a) {
  Real s = 0;
  for (int k = 0; k < W; ++k) s += a[k];
  return s;
}

// N lanes picked from a: lane k of the result is a[pick(k)], pick a
// captureless index function (the window kernels' lane layouts).
template <class V, class F, std::size_t... I>
[[gnu::always_inline]] inline Lanes<LaneReal<V>, int(sizeof...(I))> lanes_pick_of(
    const V& a, F, std::index_sequence<I...>) {
  return __builtin_shufflevector(a, a, F{}(int(I))...);
}
template <int N, class V, class F>
[[gnu::always_inline]] inline Lanes<LaneReal<V>, N> lanes_pick(const V& a, F pick) {
  return lanes_pick_of(a, pick, std::make_index_sequence<std::size_t(N)>{});
}

// Halves added until 4 lanes remain (a vector of 4, 8 or 16 lanes).
template <class Real, int n, class V>
inline Lanes<Real, 4> lanes_fold4(const V& v) {
  if constexpr (n == 4) {
    return v;
  } else {
    const auto halves = []<std::size_t... I>(const V& a, std::index_sequence<I...>) {
      return __builtin_shufflevector(a, a, int(I)...) +
             __builtin_shufflevector(a, a, int(I + n / 2)...);
    };
    return lanes_fold4<Real, n / 2>(halves(v, std::make_index_sequence<n / 2>{}));
  }
}

// The lane sums of four 4-lane vectors, as one vector {sum a, sum b, sum c, sum d}.
template <class V>
inline V lanes_sum4(const V& a, const V& b, const V& c, const V& d) {
  const V ab =
      __builtin_shufflevector(a, b, 0, 4, 2, 6) + __builtin_shufflevector(a, b, 1, 5, 3, 7);
  const V cd =
      __builtin_shufflevector(c, d, 0, 4, 2, 6) + __builtin_shufflevector(c, d, 1, 5, 3, 7);
  return __builtin_shufflevector(ab, cd, 0, 1, 4, 5) + __builtin_shufflevector(ab, cd, 2, 3, 6, 7);
}

namespace detail {

// One level of lanes_sum8's tree on two m-lane vectors p and q whose
// segments of s lanes each hold the partial sums of one source: lane t of
// the result (p's segments in its lower half, q's in its upper half, each
// now s / 2 lanes long) adds two lanes of one segment. Halves = true pairs
// lane k with lane k + s/2 (lanes_fold4's halves), false pairs lanes 2k and
// 2k + 1 (lanes_sum4's pairs). First = true gives the first operand's lane.
template <int m, int s, bool Halves, bool First>
constexpr int sum8_lane(int t) {
  const int from = t >= m / 2 ? m : 0;  // q's lanes follow p's in a shuffle
  const int h = s / 2, j = (t % (m / 2)) / h, k = t % h;
  return from + j * s + (Halves ? k + (First ? 0 : h) : 2 * k + (First ? 0 : 1));
}
template <int m, int s, class V, std::size_t... I>
[[gnu::always_inline]] inline V sum8_level(const V& p, const V& q, std::index_sequence<I...>) {
  constexpr bool halves = s > 4;
  return __builtin_shufflevector(p, q, sum8_lane<m, s, halves, true>(int(I))...) +
         __builtin_shufflevector(p, q, sum8_lane<m, s, halves, false>(int(I))...);
}
template <int m, int s, std::size_t K, class V>
[[gnu::always_inline]] inline V sum8_tree(const V (&a)[K]) {
  if constexpr (K == 1) {
    return a[0];
  } else {
    V b[K / 2];
    for (std::size_t k = 0; k < K / 2; ++k)
      b[k] = sum8_level<m, s>(a[2 * k], a[2 * k + 1], std::make_index_sequence<m>{});
    return sum8_tree<m, s / 2>(b);
  }
}

}  // namespace detail

// The lane sums of eight n-lane vectors (n = 8 or 16), {sum v[0], ...,
// sum v[7]}, each bitwise lanes_sum4's sum of lanes_fold4 of it: the same
// additions (halves down to 4 lanes, then (l0 + l1) + (l2 + l3)), done as
// one shuffle tree across the eight vectors, so each shuffle and add works
// on whole registers (2D G2P: 8 sums per particle; in float, 16 lanes,
// 23 shuffles and adds where lanes_fold4 + lanes_sum4 took 50).
template <class Real, int n, class V>
[[gnu::always_inline]] inline Lanes<Real, 8> lanes_sum8(const V (&v)[8]) {
  static_assert(n == 8 || n == 16, "lanes_sum8 takes vectors of 8 or 16 lanes");
  const V t = detail::sum8_tree<n, n>(v);
  if constexpr (n == 8) {
    return t;
  } else {
    // 8 segments of 2 lanes left: (l0 + l1) + (l2 + l3)'s last add.
    return __builtin_shufflevector(t, t, 0, 2, 4, 6, 8, 10, 12, 14) +
           __builtin_shufflevector(t, t, 1, 3, 5, 7, 9, 11, 13, 15);
  }
}

}  // namespace mmpm
