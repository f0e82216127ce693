// End-of-run timing table in the manner of LAMMPS's: one row per stage,
// `other` = wall time minus the timed stages.
#pragma once

#include <array>
#include <iosfwd>

#include "solver/simulation.hpp"

namespace mmpm {

void print_timing_table(std::ostream& os, const std::array<double, kStageCount>& seconds,
                        const std::array<long, kStageCount>& calls, double wall_s, long steps,
                        std::size_t particles);

}  // namespace mmpm
