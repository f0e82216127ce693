// Hertz line contact (docs/contact_validation.md §19): the elastic disk of
// inputs/hertz_disk.toml at rest on a rigid floor under its own weight,
// against Hertz's half-width b = sqrt(4 P R / (pi E*)) and his elliptic
// pressure. The contact force on the disk at the floor line's nodes is
// what holds the disk's nodal force there in balance at rest:
// c_i = -(f_int,i + m_i g) (grid_snapshot "force" has no gravity in it).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "tests/validation_util.hpp"

namespace mmpm {
namespace {

constexpr double kRadius = 10.0, kFloorTop = 3.0, kCentreX = 12.0;

struct HertzRun {
  double weight = 0;          // P = m g of the disk's particles (N per mm of thickness)
  double line_force = 0;      // sum of c_i on the floor line
  double floor_reaction = 0;  // the rigid floor's reaction (y), last step
  double half_width = 0;      // b from the second moment of c_i
  double hertz_width = 0;     // sqrt(4 P R / (pi E*))
  double central_share = 0;   // share of the line force inside |x| < b_Hertz / 2
};

const std::vector<double>& grid_values(const io::GridSnapshot& g, const std::string& name) {
  for (const io::ParticleField& f : g.fields)
    if (f.name == name) return f.values;
  throw std::runtime_error("no grid field " + name);
}

HertzRun run_hertz(double h, std::vector<std::string> overrides = {}) {
  overrides.push_back("grid.cell=[" + std::to_string(h) + "," + std::to_string(h) + "]");
  const int cells = int(std::lround(24.0 / h));
  overrides.push_back("grid.cells=[" + std::to_string(cells) + "," + std::to_string(cells) + "]");
  const Scene scene =
      parse_scene_file(std::string(MMPM_SOURCE_DIR) + "/inputs/hertz_disk.toml", overrides);
  auto sim = make_simulation(scene);
  testing::run_until(*sim, scene.simulation.end_time);

  const double g = -scene.loads.at(0).acceleration[1];
  const MaterialSpec& disk = scene.materials.at(0);
  const double e_star = disk.E / (1.0 - disk.nu * disk.nu);
  const io::GridSnapshot grid = sim->grid_snapshot({"mass", "force"});
  const std::vector<double>& m = grid_values(grid, "mass.disk");
  const std::vector<double>& f = grid_values(grid, "force.disk");
  const int nx = grid.nodes[0];
  const int row = int(std::lround((kFloorTop - grid.origin[1]) / grid.spacing[1]));

  HertzRun r;
  for (double mi : m) r.weight += mi * g;
  r.hertz_width = std::sqrt(4.0 * r.weight * kRadius / (std::numbers::pi * e_star));
  std::vector<double> c(std::size_t(nx), 0.0), x(std::size_t(nx), 0.0);
  double first = 0, second = 0;
  for (int i = 0; i < nx; ++i) {
    const std::size_t n = std::size_t(row) * std::size_t(nx) + std::size_t(i);
    c[std::size_t(i)] = -(f[2 * n + 1] - m[n] * g);
    x[std::size_t(i)] = grid.origin[0] + i * grid.spacing[0] - kCentreX;
    r.line_force += c[std::size_t(i)];
    first += c[std::size_t(i)] * x[std::size_t(i)];
  }
  const double centre = first / r.line_force;
  for (int i = 0; i < nx; ++i) {
    const double d = x[std::size_t(i)] - centre;
    second += c[std::size_t(i)] * d * d;
    // Nodes on |x| = b_Hertz / 2 count half.
    const double edge = std::abs(x[std::size_t(i)]) - 0.5 * r.hertz_width;
    const double w = edge < -1e-9 * h ? 1.0 : (edge < 1e-9 * h ? 0.5 : 0.0);
    r.central_share += w * c[std::size_t(i)];
  }
  r.central_share /= r.line_force;
  // The semi-ellipse's second moment is b^2 / 4. The nodes see the pressure
  // through the tent S_i, whose spread sum_i S_i(x) (x_i - x)^2 averages h^2 / 6
  // over a cell (docs/contact_validation.md §19.2).
  r.half_width = 2.0 * std::sqrt(second / r.line_force - h * h / 6.0);
  for (const Reaction& q : sim->reactions())
    if (q.name == "rigid:floor") r.floor_reaction = q.force[1];
  std::printf(
      "[ hertz    ] h %.4g: P %.5f N, floor line %.5f, floor reaction %.5f, b %.4f "
      "(Hertz %.4f, ratio %.4f), share inside b/2 %.4f (Hertz 0.6090)\n",
      h, r.weight, r.line_force, r.floor_reaction, r.half_width, r.hertz_width,
      r.half_width / r.hertz_width, r.central_share);
  return r;
}

// Share of an elliptic pressure inside |x| < b/2: (2/pi)(pi/6 + sin(pi/6) cos(pi/6)).
double hertz_central_share() {
  const double t = std::numbers::pi / 6.0;
  return 2.0 / std::numbers::pi * (t + std::sin(t) * std::cos(t));
}

// The disk's particles form a staircase whose steps stand up to half a
// particle spacing off the circle, and which nodes its step edges load
// depends on where the disk lies against the particle lattice. b / b_Hertz
// is therefore averaged over four places of the disk's centre, 0, 1/4, 1/2
// and 3/4 of a particle spacing (h / 2) along x (§19.3). Every place's floor
// line and rigid reaction must carry the weight (0.5 %).
std::vector<HertzRun> runs_over_places(double h, const std::vector<std::string>& overrides = {}) {
  std::vector<HertzRun> runs;
  for (int k = 0; k < 4; ++k) {
    std::vector<std::string> at = overrides;
    at.push_back("body[1].center=[" + std::to_string(kCentreX + 0.125 * k * h) + ",13.0]");
    runs.push_back(run_hertz(h, at));
    EXPECT_NEAR(runs.back().line_force / runs.back().weight, 1.0, 0.005) << "h " << h << ", " << k;
    EXPECT_NEAR(-runs.back().floor_reaction / runs.back().weight, 1.0, 0.005)
        << "h " << h << ", " << k;
  }
  return runs;
}

double mean_width_ratio(const std::vector<HertzRun>& runs) {
  double sum = 0;
  for (const HertzRun& r : runs) sum += r.half_width / r.hertz_width;
  std::printf("[ hertz    ] mean b / b_Hertz %.4f\n", sum / double(runs.size()));
  return sum / double(runs.size());
}

// The disk at rest (uGIMP, MUSL, position separation; the scene's
// defaults): at every place the floor line carries the weight and the rigid
// floor's reaction is the weight (0.5 %), and the half-width converges on
// Hertz's as h falls. Measured 2026-12-06, b / b_Hertz over the four places
// at 1 ms: h = 0.5 mm (4 cells per half-width) 1.080-1.151, mean 1.124;
// h = 0.25 (8 cells) 1.043-1.052, mean 1.049; h = 0.125 (long test, 1.5 ms)
// 1.003-1.027, mean 1.019. Asserted: the mean within 25 % at h = 0.5 and within 6 % at
// h = 0.25, and its error at h = 0.25 below half that at h = 0.5.
TEST(ValidationHertz, DiskOnRigidFloorHalfWidthConvergesOnHertz) {
  EXPECT_NEAR(run_hertz(0.25).hertz_width, 2.0, 0.01) << "the scene is built for b = 2 mm";
  const double err_coarse = std::abs(mean_width_ratio(runs_over_places(0.5)) - 1.0);
  const double err_fine = std::abs(mean_width_ratio(runs_over_places(0.25)) - 1.0);
  EXPECT_LT(err_coarse, 0.25);
  EXPECT_LT(err_fine, 0.06);
  EXPECT_LT(err_fine, 0.5 * err_coarse) << "refining must bring b toward Hertz's";
}

// USL and USF at h = 0.25, the scene's place: b within 6 % (measured 1.041
// and 1.044, MUSL 1.043).
TEST(ValidationHertz, HalfWidthUnderUslAndUsf) {
  for (const char* set : {"simulation.scheme=\"USL\"", "simulation.scheme=\"USF\""}) {
    const HertzRun r = run_hertz(0.25, {set});
    EXPECT_NEAR(r.line_force / r.weight, 1.0, 0.005) << set;
    EXPECT_NEAR(r.half_width / r.hertz_width, 1.0, 0.06) << set;
  }
}

// h = 0.125 mm (16 cells per half-width, 92 000 particles, ~20 s a run on 2
// threads), run to 1.5 ms (at 1 ms b still reads 1.008 at the scene's place,
// 1.003 from 1.5 to 3 ms): the mean over the four places within 3 % of
// Hertz's (measured 1.019) and, at each place, the share of the load inside
// |x| < b/2 within 0.02 of the ellipse's 0.609 (measured 0.604-0.613; at
// h = 0.25 the staircase puts 0.68-0.73 there).
TEST(ValidationHertzLong, DiskOnRigidFloorRefined) {
  MMPM_LONG_TEST();
  const std::vector<HertzRun> runs = runs_over_places(0.125, {"simulation.end_time=1.5"});
  EXPECT_NEAR(mean_width_ratio(runs), 1.0, 0.03);
  for (const HertzRun& r : runs) EXPECT_NEAR(r.central_share, hertz_central_share(), 0.02);
}

// Linear shapes do not converge with 2 x 2 particles per cell: mean
// b / b_Hertz 1.058 (h = 0.5), 1.043 (0.25), 1.092 (0.125; 1.089-1.096 over
// the places). With more particles in the disk at h = 0.125 it falls:
// 3 x 3 1.046, 4 x 4 1.026 (§19.4). Asserted as for uGIMP: within 3 % at
// h = 0.125.
TEST(ValidationHertzLong, LinearShapesAtTheFinestGrid) {
  MMPM_LONG_TEST();
  MMPM_KNOWN_LIMITATION(
      "with linear shapes and 2 x 2 particles per cell the Hertz half-width reads "
      "1.089-1.096 of Hertz's at h = 0.125 mm, against 1.019-1.064 at 0.25 "
      "(docs/contact_validation.md §19.4)");
  EXPECT_NEAR(mean_width_ratio(
                  runs_over_places(0.125, {"simulation.end_time=1.5", "grid.shape=\"linear\""})),
              1.0, 0.03);
}

}  // namespace
}  // namespace mmpm
