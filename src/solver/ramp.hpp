// The linear load ramp shared by tractions, gravity and moving supports
// (SCENE.md `ramp`): the fraction of the full value reached at time t.
#pragma once

#include <algorithm>

namespace mmpm {

inline double ramp_fraction(double t, double ramp) {
  return ramp > 0 ? std::min(1.0, t / ramp) : 1.0;
}

}  // namespace mmpm
