// Two runs that must agree bit for bit: every particle field the solver
// reports, the energies and the support reactions. For settings that change
// only how the work is done (fused passes, skipped empty nodes).
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "solver/simulation.hpp"
#include "validation_util.hpp"

namespace mmpm::testing {

inline void expect_bitwise_same(const Simulation& a, const Simulation& b, const std::string& what) {
  for (const char* name : {"position", "displacement", "velocity", "stress", "strain", "volume"})
    EXPECT_EQ(differing_values(a, b, name), 0u) << what << " " << name << ": values differing";
  const Energies e = a.energies(), g = b.energies();
  EXPECT_EQ(e.kinetic, g.kinetic) << what;
  EXPECT_EQ(e.strain, g.strain) << what;
  EXPECT_EQ(e.interface, g.interface) << what;
  EXPECT_EQ(e.external_work, g.external_work) << what;
  EXPECT_EQ(e.damping, g.damping) << what;
  EXPECT_EQ(e.kinetic_unresolved, g.kinetic_unresolved) << what;
  const auto ra = a.reactions(), rb = b.reactions();
  ASSERT_EQ(ra.size(), rb.size()) << what;
  for (std::size_t r = 0; r < ra.size(); ++r)
    for (int d = 0; d < 3; ++d) EXPECT_EQ(ra[r].force[d], rb[r].force[d]) << what << " " << r;
}

}  // namespace mmpm::testing
