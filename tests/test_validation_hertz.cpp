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

#include "tests/test_util.hpp"
#include "tests/validation_util.hpp"

namespace mmpm {
namespace {

constexpr double kRadius = 10.0, kFloorTop = 3.0, kCentreX = 12.0;

struct HertzRun {
  double unresolved = 0;      // kinetic_unresolved / strain energy at the end
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

// A scene run to its end_time, and what the runners read of it: the
// body's field's nodal mass and force (grid_snapshot), gravity's size along
// the vertical axis, E* = E / (1 - nu^2) of material 0, the unresolved
// kinetic energy over the strain energy, and the rigid floor's vertical
// reaction.
struct AtRest {
  io::GridSnapshot grid;
  std::vector<double> m, f;
  double g = 0, e_star = 0, unresolved = 0, floor_reaction = 0;
};

AtRest run_to_rest(const Scene& scene, const std::string& material, int vertical) {
  auto sim = make_simulation(scene);
  testing::run_until(*sim, scene.simulation.end_time);
  AtRest a;
  a.g = -scene.loads.at(0).acceleration[std::size_t(vertical)];
  const MaterialSpec& body = scene.materials.at(0);
  a.e_star = body.E / (1.0 - body.nu * body.nu);
  a.grid = sim->grid_snapshot({"mass", "force"});
  a.m = grid_values(a.grid, "mass." + material);
  a.f = grid_values(a.grid, "force." + material);
  const Energies e = sim->energies();
  a.unresolved = e.kinetic_unresolved / e.strain;
  for (const Reaction& q : sim->reactions())
    if (q.name == "rigid:floor") a.floor_reaction = q.force[std::size_t(vertical)];
  return a;
}

// The half model: the disk cut at its centre line x = 12 and the floor
// starting there, on a symmetry plane (a support on the grid plane x = 12
// fixing u_x, which mirrors the disk: kernels/mirror_supports.hpp).
const char* const kHalfModel = R"(
[[boundary]]
where = { x = 12.0 }
fix   = ["x"]
)";

HertzRun run_hertz(double h, std::vector<std::string> overrides = {}, bool half = false) {
  overrides.push_back("grid.cell=[" + std::to_string(h) + "," + std::to_string(h) + "]");
  const int cells = int(std::lround(24.0 / h));
  overrides.push_back("grid.cells=[" + std::to_string(cells) + "," + std::to_string(cells) + "]");
  if (half) {
    overrides.push_back("body[0].min=[12.0,1.0]");
    overrides.push_back("body[1].clip={min=[12.0,0.0],max=[24.0,24.0]}");
  }
  const std::string file = std::string(MMPM_SOURCE_DIR) + "/inputs/hertz_disk.toml";
  const Scene scene =
      half ? parse_scene_text(mmpm_test::read_text(file) + kHalfModel, file, overrides)
           : parse_scene_file(file, overrides);
  const AtRest a = run_to_rest(scene, "disk", 1);
  const io::GridSnapshot& grid = a.grid;
  const std::vector<double>&m = a.m, &f = a.f;
  const double g = a.g, e_star = a.e_star;
  const int nx = grid.nodes[0];
  const int row = int(std::lround((kFloorTop - grid.origin[1]) / grid.spacing[1]));

  HertzRun r;
  for (double mi : m) r.weight += mi * g;
  const double whole = half ? 2.0 * r.weight : r.weight;
  r.hertz_width = std::sqrt(4.0 * whole * kRadius / (std::numbers::pi * e_star));
  std::vector<double> c(std::size_t(nx), 0.0), x(std::size_t(nx), 0.0);
  double first = 0, second = 0;
  for (int i = 0; i < nx; ++i) {
    const std::size_t n = std::size_t(row) * std::size_t(nx) + std::size_t(i);
    c[std::size_t(i)] = -(f[2 * n + 1] - m[n] * g);
    x[std::size_t(i)] = grid.origin[0] + i * grid.spacing[0] - kCentreX;
    r.line_force += c[std::size_t(i)];
    first += c[std::size_t(i)] * x[std::size_t(i)];
  }
  // The half model's second moment is about the symmetry plane (x = 0
  // here): its nodes there carry their one-sided share, so its sums are
  // half the whole disk's.
  const double centre = half ? 0.0 : first / r.line_force;
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
  r.unresolved = a.unresolved;
  r.floor_reaction = a.floor_reaction;
  std::printf(
      "[ hertz    ] h %.4g: P %.5f N, floor line %.5f, floor reaction %.5f, b %.4f "
      "(Hertz %.4f, ratio %.4f), share inside b/2 %.4f (Hertz 0.6090), unresolved KE / U %.2e\n",
      h, r.weight, r.line_force, r.floor_reaction, r.half_width, r.hertz_width,
      r.half_width / r.hertz_width, r.central_share, r.unresolved);
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
  const std::vector<HertzRun> coarse = runs_over_places(0.5), fine = runs_over_places(0.25);
  EXPECT_NEAR(fine[0].hertz_width, 2.0, 0.01) << "the scene is built for b = 2 mm";
  const double err_coarse = std::abs(mean_width_ratio(coarse) - 1.0);
  const double err_fine = std::abs(mean_width_ratio(fine) - 1.0);
  EXPECT_LT(err_coarse, 0.25);
  EXPECT_LT(err_fine, 0.06);
  EXPECT_LT(err_fine, 0.5 * err_coarse) << "refining must bring b toward Hertz's";
}

// The disk cut in half on a symmetry plane, the floor ending on the plane.
// There the floor has a corner and its domain gradient leaned across the
// plane, and so did the rigid normal; pass B's approach along it
// was half undone by the support, and the particles took the rest as
// velocities the grid cannot see, growing without bound: unresolved kinetic
// energy 0.65 -> 1.08 of the strain energy from 0.82 to 1 ms at h = 0.5
// (docs/contact_validation.md §20). The plane's nodes now drop the gradient
// across it. Asserted at h = 0.5: unresolved kinetic energy below 2 % of
// the strain energy, b within 0.1 % of the whole disk's and the half weight
// on the floor line (0.5 %). Measured: the half model reads the whole
// disk's b (2.3025 mm, 1.151 of Hertz's) and unresolved energy (6.21e-3) to
// the digits printed.
TEST(ValidationHertz, HalfDiskOnAMirrorPlaneMatchesTheWholeDisk) {
  const HertzRun whole = run_hertz(0.5), half = run_hertz(0.5, {}, true);
  EXPECT_LT(half.unresolved, 0.02);
  EXPECT_NEAR(half.line_force / half.weight, 1.0, 0.005);
  EXPECT_NEAR(half.half_width / whole.half_width, 1.0, 0.001);
  EXPECT_NEAR(half.hertz_width / whole.hertz_width, 1.0, 0.001);
}

// The 3D twin (inputs/hertz_ball_3d.toml): a hemisphere, flat face up, on a
// rigid floor, as a quarter model on the mirror planes x = 0 and y = 0 with
// the floor ending on them. Hertz: a = (3 P R / (4 E*))^(1/3) for the whole
// weight P, and the second moment of the pressure over the contact is
// 2 a^2 / 5 (§19.5). The quarter's nodal sums are a quarter of the whole
// body's (the planes' nodes carry their one-sided share), and the tent's
// spread adds h^2 / 6 per axis in the floor plane.
struct HertzRun3D {
  double weight = 0;       // the quarter's m g
  double plane_force = 0;  // sum of c_i on the floor plane z = 3
  double floor_reaction = 0;
  double radius = 0, hertz_radius = 0, unresolved = 0;
};

HertzRun3D run_hertz_3d(double h, double end_time) {
  const int nxy = int(std::lround(12.0 / h)), nz = int(std::lround(14.0 / h));
  const Scene scene = parse_scene_file(
      std::string(MMPM_SOURCE_DIR) + "/inputs/hertz_ball_3d.toml",
      {"grid.cell=[" + std::to_string(h) + "," + std::to_string(h) + "," + std::to_string(h) + "]",
       "grid.cells=[" + std::to_string(nxy) + "," + std::to_string(nxy) + "," + std::to_string(nz) +
           "]",
       "simulation.end_time=" + std::to_string(end_time)});
  const AtRest a = run_to_rest(scene, "ball", 2);
  const io::GridSnapshot& grid = a.grid;
  const std::vector<double>&m = a.m, &f = a.f;
  const double g = a.g, e_star = a.e_star;
  const std::size_t nx = std::size_t(grid.nodes[0]), ny = std::size_t(grid.nodes[1]);
  const std::size_t k = std::size_t(std::lround((kFloorTop - grid.origin[2]) / grid.spacing[2]));
  HertzRun3D r;
  for (double mi : m) r.weight += mi * g;
  r.hertz_radius = std::cbrt(3.0 * 4.0 * r.weight * kRadius / (4.0 * e_star));
  double second = 0;
  for (std::size_t j = 0; j < ny; ++j)
    for (std::size_t i = 0; i < nx; ++i) {
      const std::size_t n = i + nx * (j + ny * k);
      const double c = -(f[3 * n + 2] - m[n] * g);
      const double x = grid.origin[0] + double(i) * grid.spacing[0];
      const double y = grid.origin[1] + double(j) * grid.spacing[1];
      r.plane_force += c;
      second += c * (x * x + y * y);
    }
  r.radius = std::sqrt(2.5 * (second / r.plane_force - h * h / 3.0));
  r.unresolved = a.unresolved;
  r.floor_reaction = a.floor_reaction;
  std::printf(
      "[ hertz 3D ] h %.4g: quarter weight %.4f N, floor plane %.4f, floor reaction %.4f, "
      "a %.4f (Hertz %.4f, ratio %.4f), unresolved KE / U %.2e\n",
      h, r.weight, r.plane_force, r.floor_reaction, r.radius, r.hertz_radius,
      r.radius / r.hertz_radius, r.unresolved);
  return r;
}

void expect_at_rest_on_the_floor(const HertzRun3D& r) {
  EXPECT_NEAR(r.plane_force / r.weight, 1.0, 0.005);
  EXPECT_NEAR(-r.floor_reaction / r.weight, 1.0, 0.005);
  EXPECT_LT(r.unresolved, 0.02);
}

// h = 0.5 mm (4 cells per contact radius, 33 500 particles): a within 12 %
// of Hertz's (measured 1.073; with the floor's gradient leaning across the
// mirror planes, before §20, 1.268 with unresolved kinetic energy 0.75 of
// the strain energy), the floor plane and the rigid reaction carrying the
// quarter's weight (0.5 %), unresolved kinetic energy below 2 % of the
// strain energy (measured 6.9e-3).
TEST(ValidationHertz, HemisphereOnRigidFloorQuarterModel3D) {
  const HertzRun3D r = run_hertz_3d(0.5, 1.0);
  expect_at_rest_on_the_floor(r);
  EXPECT_NEAR(r.hertz_radius, 2.0, 0.01) << "the scene is built for a = 2 mm";
  EXPECT_NEAR(r.radius / r.hertz_radius, 1.0, 0.12);
}

// h = 0.25 (8 cells per contact radius, 268 000 particles, ~80 s on 2
// threads), to 1.5 ms: a within 4 % (measured 1.021) and its error below
// half that at h = 0.5.
TEST(ValidationHertzLong, HemisphereOnRigidFloorRefined3D) {
  MMPM_LONG_TEST();
  const HertzRun3D coarse = run_hertz_3d(0.5, 1.5), fine = run_hertz_3d(0.25, 1.5);
  expect_at_rest_on_the_floor(fine);
  const double err_coarse = std::abs(coarse.radius / coarse.hertz_radius - 1.0);
  const double err_fine = std::abs(fine.radius / fine.hertz_radius - 1.0);
  EXPECT_LT(err_fine, 0.04);
  EXPECT_LT(err_fine, 0.5 * err_coarse);
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

// USF with linear shapes on the Hertz disk (docs/validation.md §3.11): the
// energy must stay what the loads put in, K + U + damping = W within 5 %,
// through 1 ms. It does not: rows of particles crossing grid lines under
// the load start a growth at 0.55 ms (cfl 0.5), and a block at rest on a
// support does the same at every cfl from 0.1 to 0.5. The cause, shown in 1D
// by tools/usf_cell_crossing.py: USF reads the strain of a motion at the
// weights of where the particle ended, across the gradient's jump at a line.
TEST(ValidationHertz, UsfWithLinearShapesStaysStableUnderLoad) {
  MMPM_KNOWN_LIMITATION(
      "USF with linear shapes goes unstable where rows of particles cross grid lines "
      "under load: the Hertz disk at 0.55 ms (docs/validation.md §3.11)");
  const Scene scene = parse_scene_file(std::string(MMPM_SOURCE_DIR) + "/inputs/hertz_disk.toml",
                                       {"grid.shape=\"linear\"", "simulation.scheme=\"USF\""});
  auto sim = make_simulation(scene);
  testing::run_until(*sim, scene.simulation.end_time);
  const Energies e = sim->energies();
  EXPECT_NEAR((e.kinetic + e.strain + e.damping) / e.external_work, 1.0, 0.05);
}

}  // namespace
}  // namespace mmpm
