// The energy guard's bound (app/energy_guard.hpp): K + U + U_int above 10
// times the initial energy plus the positive external work, plus a floor of
// 1e-12 x mass x c^2.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "app/energy_guard.hpp"

namespace {

mmpm::Energies energies(double kinetic, double strain, double interface, double work) {
  mmpm::Energies e;
  e.kinetic = kinetic;
  e.strain = strain;
  e.interface = interface;
  e.external_work = work;
  return e;
}

TEST(EnergyGuard, TripsAboveTenTimesWhatTheRunWasGiven) {
  // Initial 1.0, mass 2, c 1000: floor 2e-6.
  const mmpm::EnergyGuard g = mmpm::make_energy_guard(1.0, 2.0, 1000.0);
  EXPECT_DOUBLE_EQ(g.floor, 2e-6);
  EXPECT_TRUE(g.check(energies(5.0, 5.0, 0.0, 0.0)).empty());    // 10 = the bound - floor
  EXPECT_FALSE(g.check(energies(5.0, 5.0, 1e-5, 0.0)).empty());  // past it
  EXPECT_TRUE(g.check(energies(20.0, 0.0, 9.0, 2.0)).empty());   // work counts: bound 30
  EXPECT_FALSE(g.check(energies(20.0, 0.0, 11.0, 2.0)).empty());
  EXPECT_TRUE(g.check(energies(10.0, 0.0, 0.0, -5.0)).empty());  // negative work: not less
  const std::string why = g.check(energies(100.0, 0.0, 0.0, 0.0));
  EXPECT_NE(why.find("reached 100, 100 times what the run was given (initial energy 1, "
                     "external work 0)"),
            std::string::npos)
      << why;
}

TEST(EnergyGuard, NonFiniteEnergyTrips) {
  const mmpm::EnergyGuard g = mmpm::make_energy_guard(1.0, 1.0, 1.0);
  EXPECT_FALSE(g.check(energies(std::nan(""), 0.0, 0.0, 0.0)).empty());
  EXPECT_FALSE(g.check(energies(std::numeric_limits<double>::infinity(), 0, 0, 0)).empty());
}

TEST(EnergyGuard, ARunGivenNothingMayHoldRoundOffButNotMore) {
  // A body at rest with no load: initial 0, work 0; only the floor bounds it.
  const mmpm::EnergyGuard g = mmpm::make_energy_guard(0.0, 1.0, 100.0);  // floor 1e-8
  EXPECT_TRUE(g.check(energies(0.0, 0.0, 0.0, 0.0)).empty());
  EXPECT_TRUE(g.check(energies(1e-20, 0.0, 0.0, 0.0)).empty());
  const std::string why = g.check(energies(1e-6, 0.0, 0.0, 0.0));
  EXPECT_FALSE(why.empty());
  EXPECT_EQ(why.find("times"), std::string::npos) << why;  // no ratio to a zero input
  EXPECT_NE(why.find("reached 1e-06 while the run was given none (initial energy 0, external "
                     "work 0)"),
            std::string::npos)
      << why;
}

}  // namespace
