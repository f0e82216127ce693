// Traction loads act at the loaded face (kernels/face_traction.hpp,
// docs/validation.md §3.6): the nodal forces of one particle's load against
// their resultant and moment, and a bar in tension against its exact static
// solution, sigma = t everywhere and u = t x / E.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <type_traits>
#include <vector>

#include "kernels/face_traction.hpp"
#include "kernels/shape.hpp"
#include "tests/validation_util.hpp"

namespace mmpm {
namespace {

using testing::field;
using testing::make_from_text;
using testing::run_until;

// One particle's face load on a 12^D grid: the nodal forces add up to F and
// their moment about the origin is that of F at the face point, for random
// positions, offsets up to the particle's half-width and every shape.
template <int D, class Shape>
void check_resultant_and_moment() {
  constexpr int N = 12;
  GridView<D, double> G;
  G.nodes = 1;
  for (int d = 0; d < D; ++d) {
    G.nodes_per_dim[d] = N + 1;
    G.h[d] = 0.5 + 0.25 * d;
    G.origin[d] = -1.0 + d;
    G.nodes *= std::size_t(N + 1);
  }
  std::array<std::vector<double>, D> f;
  for (int d = 0; d < D; ++d) {
    f[d].assign(G.nodes, 0.0);
    G.f[d] = f[d].data();
  }
  std::array<double, D> x{}, o{}, F{}, lp{};
  std::array<double*, D> xp{}, lpp{}, Fp{};
  std::array<const double*, D> op{};
  for (int d = 0; d < D; ++d) {
    xp[d] = &x[d], lpp[d] = &lp[d], Fp[d] = &F[d], op[d] = &o[d];
  }
  ParticleView<D, double> P;
  P.n = 1;
  P.x = xp, P.lp = lpp, P.fext = Fp;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const std::uint32_t list[1] = {0};
  for (int trial = 0; trial < 200; ++trial) {
    for (int d = 0; d < D; ++d) {
      f[d].assign(G.nodes, 0.0);
      lp[d] = 0.25;  // 2 particles per cell
      x[d] = G.origin[d] + (3.0 + 6.0 * u01(rng)) * G.h[d];
      F[d] = u01(rng) - 0.5;
    }
    const int axis = trial % D;  // the face normal, either sign
    for (int d = 0; d < D; ++d) o[d] = 0;
    o[axis] = (trial % 2 ? 1.0 : -1.0) * lp[axis] * G.h[axis];
    const std::size_t done = scatter_face_tractions<D, Shape>(P, G, op, list, 1);
    ASSERT_EQ(done, 1u);
    std::array<double, D> sum{}, moment_x{};  // sum f_d, sum x_a f_a (a = axis)
    for (std::size_t n = 0; n < G.nodes; ++n) {
      const auto xn = G.position(n);
      for (int d = 0; d < D; ++d) {
        sum[d] += f[d][n];
        moment_x[d] += xn[d] * f[d][n];
      }
    }
    // The face point clamped to where the particle's stencil holds the
    // basis (kernels/face_traction.hpp, grid_basis_at), in cells: linear
    // shapes to the particle's cell, the quadratic B-spline to within half
    // a cell of its middle node, the cubic to the particle's cell; uGIMP's
    // face point (within l <= h/2 of the particle) never leaves its stencil.
    // Particles seeded on a lattice never need it.
    const double xi = (x[axis] - G.origin[axis]) / G.h[axis];
    const double face = (x[axis] + o[axis] - G.origin[axis]) / G.h[axis];
    double lo = -1e300, hi = 1e300;
    if constexpr (std::is_same_v<Shape, LinearShape>) {
      lo = std::floor(xi), hi = lo + 1;
    } else if constexpr (std::is_same_v<Shape, BSpline2Shape>) {
      lo = std::floor(xi - 0.5) + 0.5, hi = lo + 1;
    } else if constexpr (std::is_same_v<Shape, BSpline3Shape>) {
      lo = std::floor(xi), hi = lo + 1;
    }
    const double at_axis = G.origin[axis] + G.h[axis] * std::clamp(face, lo, hi);
    for (int d = 0; d < D; ++d) {
      EXPECT_NEAR(sum[d], F[d], 1e-14) << Shape::name << " trial " << trial;
      const double at = d != axis ? x[d] : at_axis;
      EXPECT_NEAR(moment_x[d], at * F[d], 1e-13) << Shape::name << " trial " << trial;
    }
  }
}

TEST(FaceTraction, ResultantAndMomentOfTheNodalForces) {
  check_resultant_and_moment<2, LinearShape>();
  check_resultant_and_moment<2, GimpShape>();
  check_resultant_and_moment<2, BSpline2Shape>();
  check_resultant_and_moment<2, BSpline3Shape>();
  check_resultant_and_moment<3, LinearShape>();
  check_resultant_and_moment<3, GimpShape>();
  check_resultant_and_moment<3, BSpline3Shape>();
}

// Bar 0 < x < 10 mm, 1 mm deep, fixed in x at x = 0 (and in y along y = 0),
// traction t = 1 MPa on x = 10, plane stress with nu = 0 (uniaxial stress),
// ramped over 0.1 ms and settled by grid damping: exact sigma_xx = 1 and
// u_x = x / E everywhere. Resolution: h = 0.5 mm, 2 particles per cell
// (20 particles along the bar).
std::string bar_in_tension(const std::string& shape, const std::string& scheme, double x_max) {
  return R"(
[simulation]
dimension = 2
plane = "stress"
thickness = 1.0
end_time = 3.0
cfl = 0.5
scheme = ")" +
         scheme + R"("
[grid]
origin = [-1.0, -1.0]
cell = [0.5, 0.5]
cells = [26, 6]
shape = ")" +
         shape + R"("
damping = 20.0
[[material]]
name = "m"
type = "isotropic"
density = 1.0e-3
E = 1000.0
nu = 0.0
[[body]]
name = "bar"
material = "m"
shape = "box"
min = [0.0, 0.0]
max = [)" +
         std::to_string(x_max) + R"(, 1.0]
particles_per_cell = 2
[[boundary]]
where = { x = 0.0 }
fix = ["x"]
[[boundary]]
where = { y = 0.0 }
fix = ["y"]
[[load]]
kind = "traction"
where = { body = "bar", face = "x_max" }
traction = [1.0, 0.0]
ramp = 0.1
)";
}

struct BarResult {
  double worst_stress = 0;        // max |sigma_xx - 1| over the particles of full cells
  double worst_lone_row = 0;      // the same over a row alone in its cell (x0 > 10)
  double worst_displacement = 0;  // max |u_x - x0 / E| / (L / E)
  double energy_balance = 0;      // (W - U - K - damping) / W
};

BarResult run_bar(const std::string& shape, const std::string& scheme, double x_max) {
  auto sim = make_from_text(bar_in_tension(shape, scheme, x_max));
  run_until(*sim, 3.0);
  const auto pos = field(*sim, "position"), u = field(*sim, "displacement"),
             s = field(*sim, "stress");
  BarResult r;
  for (std::size_t p = 0; p < sim->particle_count(); ++p) {
    const double x0 = pos.at(p, 0) - u.at(p, 0);
    double& worst = x0 > 10.0 ? r.worst_lone_row : r.worst_stress;
    worst = std::max(worst, std::abs(s.at(p, 0) - 1.0));
    r.worst_displacement =
        std::max(r.worst_displacement, std::abs(u.at(p, 0) - x0 / 1000.0) / (x_max / 1000.0));
  }
  const Energies e = sim->energies();
  r.energy_balance = (e.external_work - e.strain - e.kinetic - e.damping) / e.external_work;
  return r;
}

// Before the loads acted at the faces the last two particle rows read
// sigma_xx = 0.32 and 1.18 (uGIMP, MUSL) and the end moved 1.4 % short.
// Tolerance: 0.5 % of the applied stress (in full cells) and of the end displacement, for
// the face on a grid line (x = 10) and between grid lines (x = 10.2: the
// outer particles' domains end at 10.25, where the load then acts).
// At x = 10.2 the outer particle row is alone in its cell (the cell's other
// half is empty), which costs that row 3.9 % of stress with linear shapes
// and 0.4-0.6 % with uGIMP whatever the load's point: 5 % there; B-splines
// are not in the test: this
// bar's support at x = 0 already gives sigma_xx = 0 and 2.34 in the first
// two rows (docs/validation.md §3.6, §7).
TEST(FaceTraction, BarInTensionIsUniformToTheLoadedRow) {
  for (const char* shape : {"gimp", "linear"})
    for (const char* scheme : {"MUSL", "USL"})
      for (double x_max : {10.0, 10.2}) {
        const BarResult r = run_bar(shape, scheme, x_max);
        EXPECT_LT(r.worst_stress, 5e-3) << shape << " " << scheme << " L " << x_max;
        EXPECT_LT(r.worst_lone_row, 0.05) << shape << " " << scheme << " L " << x_max;
        EXPECT_LT(r.worst_displacement, 5e-3) << shape << " " << scheme << " L " << x_max;
        // The traction's work against the stored, kinetic and damped energy.
        EXPECT_LT(std::abs(r.energy_balance), 5e-3) << shape << " " << scheme << " L " << x_max;
      }
}

// The same bar turned by rotate = 90 degrees about its centre (standing on
// y = -4.5, loaded on its body-frame face x_max, now the top): the load's
// direction and its face offset turn with the body. Same tolerances.
TEST(FaceTraction, RotatedBarLoadsItsFace) {
  auto sim = make_from_text(bar_in_tension("gimp", "MUSL", 10.0),
                            {"grid.origin=[3.0,-5.5]", "grid.cells=[8,24]", "body[0].rotate=90.0",
                             "boundary[0].where={ y = -4.5 }", "boundary[0].fix=[\"x\",\"y\"]",
                             "boundary[1].where={ y = -4.5 }"});
  run_until(*sim, 3.0);
  const auto pos = field(*sim, "position"), u = field(*sim, "displacement"),
             s = field(*sim, "stress");
  double worst_stress = 0, worst_u = 0;
  for (std::size_t p = 0; p < sim->particle_count(); ++p) {
    const double height = pos.at(p, 1) - u.at(p, 1) + 4.5;
    worst_stress = std::max(worst_stress, std::abs(s.at(p, 1) - 1.0));
    worst_u = std::max(worst_u, std::abs(u.at(p, 1) - height / 1000.0) / (10.0 / 1000.0));
  }
  EXPECT_LT(worst_stress, 5e-3);
  EXPECT_LT(worst_u, 5e-3);
  const Energies e = sim->energies();
  EXPECT_LT(std::abs(e.external_work - e.strain - e.kinetic - e.damping), 5e-3 * e.external_work);
}

// A bar turned by 30 degrees, free, pulled by t = 1 MPa at both ends
// (body-frame faces x_min and x_max): the particles fill the grid's lattice,
// so its faces are staircases and each load acts on the declared face
// (src/model/bodies.cpp). h = 0.25 mm, 2 ppc, 1.5 ms. Axial stress averaged
// over the last 0.5 mm at each end within 5 % of t (0.969 here; 0.925 with
// the loads at the particles, 1.07 with every load at its domain's edge),
// over the whole bar within 1 % (1.002). The staircase sides leave ±4 % in
// the 0.5 mm bins in between and 12 % in the strain energy either way.
TEST(FaceTraction, TiltedBarLoadedAtBothEnds) {
  auto sim = make_from_text(R"(
[simulation]
dimension = 2
plane = "stress"
end_time = 1.5
cfl = 0.5
[grid]
origin = [-2.0, -5.0]
cell = [0.25, 0.25]
cells = [56, 40]
shape = "gimp"
damping = 20.0
[[material]]
name = "m"
type = "isotropic"
density = 1.0e-3
E = 1000.0
nu = 0.0
[[body]]
name = "bar"
material = "m"
shape = "box"
min = [0.0, 0.0]
max = [10.0, 1.0]
rotate = 30.0
particles_per_cell = 2
[[load]]
kind = "traction"
where = { body = "bar", face = "x_max" }
traction = [1.0, 0.0]
ramp = 0.1
[[load]]
kind = "traction"
where = { body = "bar", face = "x_min" }
traction = [-1.0, 0.0]
ramp = 0.1
)");
  run_until(*sim, 1.5);
  const auto pos = field(*sim, "position"), u = field(*sim, "displacement"),
             s = field(*sim, "stress");
  const double c = std::cos(std::numbers::pi / 6), sn = std::sin(std::numbers::pi / 6);
  double all = 0, lo = 0, hi = 0;
  int n_lo = 0, n_hi = 0;
  for (std::size_t p = 0; p < sim->particle_count(); ++p) {
    // Axial stress n.sigma.n (2D order xx, yy, xy) at the axial coordinate
    // about the bar's centre (5, 0.5) in the initial configuration.
    const double axial = s.at(p, 0) * c * c + s.at(p, 1) * sn * sn + 2 * s.at(p, 2) * c * sn;
    const double a = (pos.at(p, 0) - u.at(p, 0) - 5.0) * c + (pos.at(p, 1) - u.at(p, 1) - 0.5) * sn;
    all += axial;
    if (a > 4.5) hi += axial, ++n_hi;
    if (a < -4.5) lo += axial, ++n_lo;
  }
  ASSERT_GT(n_lo, 10);
  ASSERT_GT(n_hi, 10);
  EXPECT_NEAR(hi / n_hi, 1.0, 0.05);
  EXPECT_NEAR(lo / n_lo, 1.0, 0.05);
  EXPECT_NEAR(all / double(sim->particle_count()), 1.0, 0.01);
}

}  // namespace
}  // namespace mmpm
