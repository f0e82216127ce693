// A particle keeps its row in every output for the whole run: the solver
// stores particles in tile order and re-sorts them whenever one changes
// tile, but particle_field (and so every snapshot) writes them in seed
// order, and an unstable run names the particle by that row.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "validation_util.hpp"

namespace mmpm::testing {
namespace {

// A stress-free block in free flight, 16 x 12 cells with 2 x 2 particles per
// cell, crossing four 4-cell tiles along x ([grid] tile = 4): every particle
// changes tile, so the columns are re-sorted several times.
std::string flying_block(const char* shape, const char* precision) {
  return std::string(R"(
[simulation]
dimension = 2
end_time = 1.0
cfl = 0.5
precision = ")") +
         precision + R"("
[grid]
origin = [0.0, 0.0]
cell = [1.0, 1.0]
cells = [48, 24]
tile = 4
shape = ")" +
         shape +
         R"("
[[material]]
name = "m"
type = "isotropic"
density = 1.0e-3
E = 1.0
nu = 0.3
[[body]]
name = "a"
material = "m"
shape = "box"
min = [4.0, 4.0]
max = [12.0, 16.0]
velocity = [2.0, 0.25]
[[body]]
name = "b"
material = "m"
shape = "box"
min = [12.0, 4.0]
max = [20.0, 16.0]
velocity = [2.0, 0.25]
)";
}

// Row k of position at time t is row k at t = 0 moved by v t, and the
// body of row k never changes; a row that followed the storage order would
// jump by whole tiles at the first re-sort. Tolerance: the positions sum
// ~100 increments of v dt (round-off ~1e-12 mm in double, ~1e-5 in float
// with compensated positions), far below the 0.5 mm particle spacing.
TEST(ParticleRows, RowsFollowTheParticlesThroughResorts) {
  for (const char* shape : {"linear", "gimp"})
    for (const char* precision : {"double", "float"}) {
      SCOPED_TRACE(std::string(shape) + " " + precision);
      auto sim = make_from_text(flying_block(shape, precision));
      const Column x0 = field(*sim, "position"), body0 = field(*sim, "body");
      run_until(*sim, 8.0);  // 16 mm along x: four tiles
      const Column x = field(*sim, "position"), body = field(*sim, "body");
      ASSERT_EQ(x.values.size(), x0.values.size());
      const double t = sim->time(), tol = 1e-4;
      double worst = 0;
      for (std::size_t p = 0; p < sim->particle_count(); ++p) {
        worst = std::max(worst, std::abs(x.at(p, 0) - (x0.at(p, 0) + 2.0 * t)));
        worst = std::max(worst, std::abs(x.at(p, 1) - (x0.at(p, 1) + 0.25 * t)));
        ASSERT_EQ(body.at(p), body0.at(p)) << "row " << p;
      }
      EXPECT_LT(worst, tol);
    }
}

// set_particle_field takes its values in the same rows: a velocity set by
// row comes back by row after the particles were re-sorted.
TEST(ParticleRows, VelocitySetByRowReadsBackByRow) {
  auto sim = make_from_text(flying_block("linear", "double"));
  run_until(*sim, 4.0);  // re-sorted: storage order is no longer seed order
  const Column x = field(*sim, "position");
  std::vector<double> v(x.values.size());
  for (std::size_t p = 0; p < sim->particle_count(); ++p)
    v[2 * p] = 1e-3 * double(p), v[2 * p + 1] = -1e-3 * double(p);
  sim->set_particle_field("velocity", v);
  EXPECT_EQ(field(*sim, "velocity").values, v);
}

// The block leaves the grid at +x; the message names row N and its
// position. The block does not deform, so that position is row N's seed
// position moved along x only: the y coordinates must agree.
TEST(ParticleRows, UnstableRunNamesTheParticleByItsRow) {
  auto sim = make_from_text(flying_block("gimp", "double"));
  const Column x0 = field(*sim, "position");
  try {
    run_until(*sim, 100.0);
    FAIL() << "the block should have left the grid";
  } catch (const SimulationError& e) {
    const std::string m = e.what();
    const auto at = m.find("particle ");
    ASSERT_NE(at, std::string::npos) << m;
    unsigned long row = 0;
    double px = 0, py = 0;
    ASSERT_EQ(
        std::sscanf(m.c_str() + at, "particle %lu (material 'm', x = [%lf, %lf", &row, &px, &py), 3)
        << m;
    ASSERT_LT(row, sim->particle_count()) << m;
    const double t = sim->time();
    // Within the 6 significant digits the message prints (and one step of
    // motion: the failing stage may have moved the particle already).
    EXPECT_NEAR(py, x0.at(row, 1) + 0.25 * t, 0.25 * sim->dt() + 1e-4 * std::abs(py)) << m;
    EXPECT_NEAR(px, x0.at(row, 0) + 2.0 * t, 2.0 * sim->dt() + 1e-4 * std::abs(px)) << m;
  }
}

}  // namespace
}  // namespace mmpm::testing
