// One (dimension, shape function, real type) combination for typed tests
// over the kernels, and the readable test names gtest prints for it.
#pragma once

#include <string>

namespace mmpm_test {

template <int Dim, class S, class R>
struct Cfg {
  static constexpr int D = Dim;
  using Shape = S;
  using Real = R;
};

struct CfgNames {
  template <class C>
  static std::string GetName(int) {
    return std::to_string(C::D) + "D_" + C::Shape::name + "_" +
           (sizeof(typename C::Real) == 8 ? "double" : "float");
  }
};

}  // namespace mmpm_test
