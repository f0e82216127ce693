// Short fixed-width vectors (GCC/Clang vector extensions) for the window
// kernels: one vector holds the W nodes of a window row along x
// (kernels/window.hpp), so a row's weights, accumulators and grid values are
// each one register (W = 4 doubles: 256 bits). Arithmetic between a vector
// and a scalar broadcasts the scalar; comparisons give lane masks that ?:
// selects with. Loads and stores go through memcpy: grid rows start at any
// node, so they are unaligned.
#pragma once

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

template <class V>
inline V lanes_load(const void* p) {
  V v;
  std::memcpy(&v, p, sizeof(V));
  return v;
}
template <class V>
inline void lanes_store(void* p, const V& v) {
  std::memcpy(p, &v, sizeof(V));
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
// max/min in the operand order of the x86 instructions, so they compile to
// one vmaxp/vminp each.
template <class V>
inline V lanes_max(const V& a, const V& b) {
  return a > b ? a : b;
}
template <class V>
inline V lanes_min(const V& a, const V& b) {
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

}  // namespace mmpm
