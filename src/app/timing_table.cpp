#include "app/timing_table.hpp"

#include <cstdio>
#include <ostream>

namespace mmpm {

void print_timing_table(std::ostream& os, const std::array<double, kStageCount>& seconds,
                        const std::array<long, kStageCount>& calls, double wall_s, long steps,
                        std::size_t particles) {
  char line[160];
  const double per_step = steps > 0 ? 1e3 / double(steps) : 0.0;
  std::snprintf(line, sizeof line, "%-14s|%10s |%11s |%10s |%8s\n", "Stage", "calls", "total (s)",
                "ms/step", "%total");
  os << line << "--------------+-----------+------------+-----------+--------\n";
  double timed = 0;
  for (int s = 0; s < kStageCount; ++s) {
    timed += seconds[s];
    std::snprintf(line, sizeof line, "%-14s|%10ld |%11.4f |%10.4f |%7.2f%%\n", kStageNames[s],
                  calls[s], seconds[s], seconds[s] * per_step,
                  wall_s > 0 ? 100 * seconds[s] / wall_s : 0.0);
    os << line;
  }
  const double other = wall_s - timed;
  std::snprintf(line, sizeof line, "%-14s|%10s |%11.4f |%10.4f |%7.2f%%\n", "other", "", other,
                other * per_step, wall_s > 0 ? 100 * other / wall_s : 0.0);
  os << line;
  std::snprintf(
      line, sizeof line, "Wall %.4f s, %ld steps, %zu particles: %.1f ns per particle-step\n",
      wall_s, steps, particles,
      steps > 0 && particles > 0 ? wall_s * 1e9 / (double(steps) * double(particles)) : 0.0);
  os << line;
}

}  // namespace mmpm
