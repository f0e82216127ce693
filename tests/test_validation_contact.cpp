// Contact validation: whole-solver runs of the scenes inputs/collision.toml,
// inputs/incline_block.toml and inputs/incline_disk.toml against exact
// solutions (docs/contact_validation.md derives every number used here and
// lists the values measured). Every test states its resolution and tolerance.
//
//   head-on impact of two identical blocks (§2): momentum every step, velocity
//     exchange, kinetic energy, independence of where the contact plane lies;
//   block on a rigid incline with Coulomb friction (§3): sliding acceleration,
//     sticking, reaction on the rigid floor, contact plane on a grid line or
//     at cell mid-height;
//   disk on a rigid incline (§4): rolling without slipping, sliding.
//
// The scenes are loaded from inputs/ (the same physics `mmpm run` runs), with
// --set style overrides for the variants.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <numbers>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "tests/test_util.hpp"
#include "tests/validation_util.hpp"

namespace mmpm {
namespace {

using testing::field;

std::string input(const std::string& name) {
  return std::string(MMPM_SOURCE_DIR) + "/inputs/" + name;
}

std::string num(double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.17g", x);
  std::string s = buf;
  if (s.find_first_of(".e") == std::string::npos) s += ".0";
  return s;
}

// Mass, centre of mass, its velocity, and the spin (angular momentum about the
// centre of mass / polar moment of inertia) of the particles of one material.
struct BodyState {
  double m = 0, x = 0, y = 0, vx = 0, vy = 0, omega = 0, I = 0;
  double min_x = std::numeric_limits<double>::infinity();
  double max_x = -std::numeric_limits<double>::infinity();
};

std::vector<BodyState> body_states(const Simulation& sim, std::size_t materials) {
  const auto v = field(sim, "velocity"), m = field(sim, "mass"), mat = field(sim, "material"),
             x = field(sim, "position");
  std::vector<BodyState> b(materials);
  const std::size_t n = sim.particle_count();
  for (std::size_t p = 0; p < n; ++p) {
    BodyState& s = b[std::size_t(mat.at(p))];
    const double mp = m.at(p);
    s.m += mp;
    s.x += mp * x.at(p, 0), s.y += mp * x.at(p, 1);
    s.vx += mp * v.at(p, 0), s.vy += mp * v.at(p, 1);
    s.min_x = std::min(s.min_x, x.at(p, 0)), s.max_x = std::max(s.max_x, x.at(p, 0));
  }
  for (auto& s : b)
    if (s.m > 0) s.x /= s.m, s.y /= s.m, s.vx /= s.m, s.vy /= s.m;
  std::vector<double> L(materials, 0.0);
  for (std::size_t p = 0; p < n; ++p) {
    BodyState& s = b[std::size_t(mat.at(p))];
    const double rx = x.at(p, 0) - s.x, ry = x.at(p, 1) - s.y;
    L[std::size_t(mat.at(p))] += m.at(p) * (rx * (v.at(p, 1) - s.vy) - ry * (v.at(p, 0) - s.vx));
    s.I += m.at(p) * (rx * rx + ry * ry);
  }
  for (std::size_t j = 0; j < materials; ++j)
    if (b[j].I > 0) b[j].omega = L[j] / b[j].I;
  return b;
}

// One line of measured values per check, for the CI log and the tables of
// docs/contact_validation.md.
template <class... A>
void note(const char* fmt, A... args) {
  std::printf("[ measured ] ");
  std::printf(fmt, args...);
  std::printf("\n");
}

// Least-squares slope of y(t).
double slope(const std::vector<double>& t, const std::vector<double>& y) {
  double st = 0, sy = 0, stt = 0, sty = 0;
  const double n = double(t.size());
  for (std::size_t k = 0; k < t.size(); ++k) {
    st += t[k], sy += y[k], stt += t[k] * t[k], sty += t[k] * y[k];
  }
  return (n * sty - st * sy) / (n * stt - st * st);
}

// The energy balance K + U + U_int + D - W: zero but for the scheme's error.
double energy_balance(const Energies& e) {
  return e.kinetic + e.strain + e.interface + e.damping - e.external_work;
}

// ---------------------------------------------------------------------------
// §2 Head-on impact of two identical blocks (inputs/collision.toml)
// ---------------------------------------------------------------------------
// Blocks 10 x 4 mm, E = 100 MPa, nu = 0, rho = 1e-3 (c = 316.2 mm/ms), plane
// stress, A at +4 mm/ms, B at -2 mm/ms, 0.5 mm apart; h = 0.5 mm, 2 x 2
// particles per cell, uGIMP, MUSL, FLIP. Exact (1D bar impact, §2): the
// velocities exchange (A -> -2, B -> +4) after a contact of 2L/c = 0.0632 ms.

struct CollisionRun {
  double max_momentum_error = 0;  // max over steps of |P(t) - P(0)| / |P(0)|
  double vA0 = 0, vB0 = 0;        // initial centre-of-mass velocities
  double vA = 0, vB = 0;          // at the end
  double velocity_change = 0;     // |v(end) - v(end - 0.02 ms)| of A and B: 0 once apart
  double kinetic0 = 0;            // initial kinetic energy
  double total_end = 0;           // kinetic + strain at the end
  double rigid_motion_end = 0;    // sum of 1/2 M v_cm^2 at the end
  double max_overlap = 0;         // max over steps of -(surface gap), in mm
  double h = 0;
};

CollisionRun run_collision(const std::vector<std::string>& overrides, double t_end) {
  const Scene scene = parse_scene_file(input("collision.toml"), overrides);
  auto sim = make_simulation(scene);
  CollisionRun r;
  r.h = scene.grid.cell[0];
  // Particle centres sit half a particle spacing inside the surfaces.
  const double spacing = scene.grid.cell[0] / scene.bodies[0].particles_per_cell;
  auto momentum = [&](const std::vector<BodyState>& b) {
    return std::array<double, 2>{b[0].m * b[0].vx + b[1].m * b[1].vx,
                                 b[0].m * b[0].vy + b[1].m * b[1].vy};
  };
  std::vector<BodyState> b = body_states(*sim, 2);
  const auto P0 = momentum(b);
  const double P0n = std::hypot(P0[0], P0[1]);
  r.vA0 = b[0].vx, r.vB0 = b[1].vx;
  r.kinetic0 = sim->energies().kinetic;
  double vA_before = 0, vB_before = 0;
  bool marked = false;
  while (sim->time() < t_end - 1e-9 * sim->dt()) {
    sim->step();
    b = body_states(*sim, 2);
    const auto P = momentum(b);
    r.max_momentum_error =
        std::max(r.max_momentum_error, std::hypot(P[0] - P0[0], P[1] - P0[1]) / P0n);
    r.max_overlap = std::max(r.max_overlap, -(b[1].min_x - b[0].max_x - spacing));
    if (!marked && sim->time() >= t_end - 0.02) {
      vA_before = b[0].vx, vB_before = b[1].vx;
      marked = true;
    }
  }
  r.vA = b[0].vx, r.vB = b[1].vx;
  r.velocity_change = std::max(std::abs(r.vA - vA_before), std::abs(r.vB - vB_before));
  const Energies e = sim->energies();
  r.total_end = e.kinetic + e.strain;
  r.rigid_motion_end = 0.5 * b[0].m * b[0].vx * b[0].vx + 0.5 * b[1].m * b[1].vx * b[1].vx;
  return r;
}

// Exchange error: how far each block's final velocity is from the other's
// initial one, as a fraction of the approach speed.
double exchange_error(const CollisionRun& r) {
  return std::max(std::abs(r.vA - r.vB0), std::abs(r.vB - r.vA0)) / std::abs(r.vA0 - r.vB0);
}

std::string law_override(const std::string& law) {
  return "interaction[0].law=\"" + law + "\"";
}

// Total momentum of the particles after every step, for stick, frictionless
// and separate (the blocks pass through each other). Contact momentum changes
// are equal and opposite at each node and internal forces sum to zero, so the
// momentum is conserved to round-off: tolerance 1e-12 relative to |P(0)|
// (h = 0.5 mm, 0.2 ms = 257 steps, through the whole impact).
TEST(ValidationContact, HeadOnImpactConservesMomentumEveryStep) {
  for (const char* law : {"stick", "frictionless", "separate"}) {
    const CollisionRun r = run_collision({law_override(law)}, 0.2);
    note("%s: max |P - P0| / |P0| = %.3e", law, r.max_momentum_error);
    EXPECT_LT(r.max_momentum_error, 1e-12) << "law " << law;
  }
}

// Frictionless and stick contact (identical for a head-on impact): the blocks
// exchange their velocities within 5 % of the approach speed; the total
// (kinetic + strain) energy after separation is within 5 % of the initial
// kinetic energy; the kinetic energy of the blocks' rigid motion keeps at
// least 83 % of it (what a 5 % exchange error allows, §2.3); the surfaces
// never overlap by more than a quarter cell. h = 0.5 mm, contact plane at 2/3
// of a cell, 0.25 ms (separation at ~0.15 ms).
TEST(ValidationContact, HeadOnImpactExchangesVelocities) {
  for (const char* law : {"frictionless", "stick"}) {
    const CollisionRun r = run_collision({law_override(law)}, 0.25);
    ASSERT_LT(r.velocity_change, 1e-6) << law << ": the blocks must have separated";
    note(
        "%s: vA %.4f vB %.4f, exchange error %.4f, (K+U)/K0 %.4f, rigid-motion K/K0 %.4f, overlap "
        "%.4f mm",
        law, r.vA, r.vB, exchange_error(r), r.total_end / r.kinetic0,
        r.rigid_motion_end / r.kinetic0, r.max_overlap);
    EXPECT_LT(exchange_error(r), 0.05) << law << ": vA " << r.vA << " (exact " << r.vB0 << "), vB "
                                       << r.vB << " (exact " << r.vA0 << ")";
    EXPECT_NEAR(r.total_end / r.kinetic0, 1.0, 0.05) << law;
    EXPECT_GT(r.rigid_motion_end / r.kinetic0, 0.83) << law;
    EXPECT_LT(r.max_overlap, 0.25 * r.h) << law;
  }
}

// The same impact under USF, whose pass A holds the pairs the last pass B
// held (§13): the hold must let the blocks part when the stress waves
// return (they do: pass B stops holding once the updated momenta part), and
// the exchange keeps the tolerances above. Measured 2026-12-05: exchange
// error 2.70 / 2.78 %, (K+U)/K0 1.0006 / 1.0010 (frictionless / stick;
// before the hold 2.60 / 2.62 % and 1.0080 / 1.0109).
TEST(ValidationContact, HeadOnImpactUnderUsfExchangesVelocities) {
  for (const char* law : {"frictionless", "stick"}) {
    const CollisionRun r = run_collision({law_override(law), "simulation.scheme=\"USF\""}, 0.25);
    ASSERT_LT(r.velocity_change, 1e-6) << law << ": the blocks must have separated";
    note("USF %s: vA %.4f vB %.4f, exchange error %.4f, (K+U)/K0 %.4f, overlap %.4f mm", law, r.vA,
         r.vB, exchange_error(r), r.total_end / r.kinetic0, r.max_overlap);
    EXPECT_LT(exchange_error(r), 0.05) << law;
    EXPECT_NEAR(r.total_end / r.kinetic0, 1.0, 0.05) << law;
    EXPECT_LT(r.max_overlap, 0.25 * r.h) << law;
  }
}

// USL with linear shape functions (docs/validation.md §3.5, "Linear
// shapes"): a particle entering a cell reaches the node ahead with weight
// S -> 0 while its force there does not vanish, and USL's strain read
// that force over a mass S m_p; the impact stopped at step 100 (energy 16
// times the initial), the incline block at step 397 and the rolling disk
// at step 101 (J <= 0). With the light-node mass m_L the same impact
// keeps its momentum to round-off every step (the force a light node
// leaves out reaches the particles through dvel) and exchanges the
// velocities within 5 % as MUSL does. USL dissipates the impact's
// grid-scale modes (docs/validation.md §3.5): (K+U)/K0 must not grow and
// may fall by up to 15 %. h = 0.5 mm, frictionless, 0.25 ms. Measured
// 2026-12-06: momentum error 5.7e-15, exchange error 3.8 %, (K+U)/K0
// 0.899 (USL with uGIMP 0.939 and 2.7 %, with quadratic B-splines 0.791
// and 7.6 %; MUSL with linear shapes 1.024 and 3.1 %), overlap 0.
TEST(ValidationContact, HeadOnImpactUnderUslWithLinearShapes) {
  const CollisionRun r = run_collision(
      {law_override("frictionless"), "simulation.scheme=\"USL\"", "grid.shape=\"linear\""}, 0.25);
  ASSERT_LT(r.velocity_change, 1e-6) << "the blocks must have separated";
  note(
      "USL linear: max |P - P0| / |P0| %.3e, vA %.4f vB %.4f, exchange error %.4f, (K+U)/K0 "
      "%.4f, overlap %.4f mm",
      r.max_momentum_error, r.vA, r.vB, exchange_error(r), r.total_end / r.kinetic0, r.max_overlap);
  EXPECT_LT(r.max_momentum_error, 1e-12);
  EXPECT_LT(exchange_error(r), 0.05);
  EXPECT_LT(r.total_end / r.kinetic0, 1.0);
  EXPECT_GT(r.total_end / r.kinetic0, 0.85);
  EXPECT_LT(r.max_overlap, 0.25 * r.h);
}

// Without contact ("separate") the blocks pass through each other untouched:
// both keep their velocities (to round-off, 1e-12 relative) and overlap by
// more than 1 mm at the end. h = 0.5 mm, 0.25 ms.
TEST(ValidationContact, HeadOnSeparateLawPassesThrough) {
  const CollisionRun r = run_collision({law_override("separate")}, 0.25);
  note("separate: vA %.15g vB %.15g, overlap %.4f mm, (K+U)/K0 - 1 = %.3e", r.vA, r.vB,
       r.max_overlap, r.total_end / r.kinetic0 - 1.0);
  EXPECT_NEAR(r.vA, r.vA0, 1e-12 * std::abs(r.vA0));
  EXPECT_NEAR(r.vB, r.vB0, 1e-12 * std::abs(r.vB0));
  EXPECT_GT(r.max_overlap, 1.0);
  EXPECT_NEAR(r.total_end / r.kinetic0, 1.0, 1e-12);
}

// Where the contact plane lies in the cell must not matter: block B starts
// 0.5, 0.75 or 1.0 mm from A, so the blocks meet at x = 12.33, 12.5 and
// 12.67 mm, i.e. 2/3, 0 and 1/3 of a cell past a grid line. Frictionless,
// h = 0.5 mm; each run within the 5 % exchange error of the test above, and
// the three within 5 % of each other.
// The frictionless impact with block B starting `gap` = 0.5, 0.75 and 1.0 mm
// from A (the contact plane at 2/3, 0 and 1/3 of a cell past a grid line),
// `extra` on top: each run's exchange error under 5 %, and the three within 5 %
// of each other. The runs go to `runs` for the caller's own checks.
void expect_impact_independent_of_contact_plane(const std::vector<std::string>& extra,
                                                const char* label,
                                                std::vector<CollisionRun>& runs) {
  std::vector<double> errors;
  for (double gap : {0.5, 0.75, 1.0}) {
    const double bmin = 12.0 + gap;
    std::vector<std::string> overrides{law_override("frictionless"),
                                       "body[1].min=[" + num(bmin) + ",2.0]",
                                       "body[1].max=[" + num(bmin + 10.0) + ",6.0]"};
    overrides.insert(overrides.end(), extra.begin(), extra.end());
    const CollisionRun r = run_collision(overrides, 0.3);
    ASSERT_LT(r.velocity_change, 1e-6) << "gap " << gap << ": the blocks must have separated";
    errors.push_back(exchange_error(r));
    note(
        "%s, gap %.2f: vA %.4f vB %.4f, exchange error %.4f, (K+U)/K0 %.4f, rigid-motion K/K0 "
        "%.4f",
        label, gap, r.vA, r.vB, errors.back(), r.total_end / r.kinetic0,
        r.rigid_motion_end / r.kinetic0);
    EXPECT_LT(errors.back(), 0.05)
        << label << ", gap " << gap << " (contact plane at x = " << 12.0 + 4.0 * gap / 6.0
        << "): vA " << r.vA << ", vB " << r.vB;
    runs.push_back(r);
  }
  const auto [lo, hi] = std::minmax_element(errors.begin(), errors.end());
  EXPECT_LT(*hi - *lo, 0.05) << label;
}

TEST(ValidationContact, HeadOnImpactIndependentOfContactPlaneInCell) {
  MMPM_KNOWN_LIMITATION(
      "position separation uses the paper's fixed offset 0.8 h; the exchange error is "
      "2.5 / 4.3 / 10.4 % with the contact plane at 2/3, 0, 1/3 of a cell");
  std::vector<CollisionRun> runs;
  expect_impact_independent_of_contact_plane({}, "position separation", runs);
}

// The same three gaps under the displacement separation (the method for
// bodies that touch; here they meet when the 0.5-1.0 mm gap closes). A
// partner under kContactPresentFraction of a cell is absent at a node
// (docs/contact_validation.md §15). Before the rule, the uGIMP blocks 0.5 mm
// apart exchanged velocities with a 7.5 % error (a sliver of B's domain,
// reaching A's face row early, stopped B's last particles before contact);
// measured 2026-12-05: 1.8 / 2.1 / 1.7 %. Same tolerances as above.
TEST(ValidationContact, HeadOnImpactUnderDisplacementSeparationIndependentOfContactPlaneInCell) {
  std::vector<CollisionRun> runs;
  expect_impact_independent_of_contact_plane({"interaction[0].separation=\"displacement\""},
                                             "displacement separation", runs);
  for (const CollisionRun& r : runs) EXPECT_NEAR(r.total_end / r.kinetic0, 1.0, 0.05);
}

// ---------------------------------------------------------------------------
// §3 Block on a rigid incline, §4 disk on a rigid incline
// ---------------------------------------------------------------------------
// Flat rigid floor, gravity G = 200 mm/ms^2 tilted by theta = 30 degrees and
// ramped in over 0.05 ms. The fits use 0.07 ms <= t <= 0.2 ms.

struct InclineRun {
  double G = 0, theta = 0, mu = 0, mass = 0, radius = 0;
  double accel = 0;             // fitted d v_cm,x / dt (along the slope)
  double spin_accel = 0;        // fitted d omega / dt
  double slide = 0;             // centre-of-mass displacement along the slope at the end
  double sink = 0;              // largest downward centre-of-mass displacement
  double reaction[2] = {0, 0};  // mean force on the rigid floor over the fit window
  double mode = 0;              // velocity_mode_ratio at the end
};

// Kinetic energy of material `body`'s particles about their centre-of-mass
// velocity, over the bulk 1/2 M |v_cm|^2: a velocity mode that the body's
// sliding does not explain.
double velocity_mode_ratio(const Simulation& sim, std::size_t materials, int body = 0) {
  const BodyState b = body_states(sim, materials)[std::size_t(body)];
  const auto v = field(sim, "velocity"), m = field(sim, "mass"), mat = field(sim, "material");
  double internal = 0;
  for (std::size_t p = 0; p < sim.particle_count(); ++p)
    if (mat.at(p) == body) {
      const double dx = v.at(p, 0) - b.vx, dy = v.at(p, 1) - b.vy;
      internal += m.at(p) * (dx * dx + dy * dy);
    }
  return internal / (b.m * (b.vx * b.vx + b.vy * b.vy));
}

InclineRun run_incline(const std::string& file, const std::vector<std::string>& overrides,
                       double t_fit = 0.07) {
  const Scene scene = parse_scene_file(input(file), overrides);
  auto sim = make_simulation(scene);
  InclineRun r;
  const Vec3 g = scene.loads.at(0).acceleration;
  r.G = std::hypot(g[0], g[1]);
  r.theta = std::atan2(g[0], -g[1]);
  r.mu = scene.interactions.at(0).friction;
  int body = -1;
  for (std::size_t m = 0; m < scene.materials.size(); ++m)
    if (scene.materials[m].type != MaterialType::rigid) body = int(m);
  const std::string floor = "rigid:floor";
  const std::size_t nm = scene.materials.size();
  const BodyState s0 = body_states(*sim, nm)[std::size_t(body)];
  r.mass = s0.m;
  r.radius = std::sqrt(2.0 * s0.I / s0.m);  // a uniform disk: I = m R^2 / 2
  std::vector<double> t, v, w;
  double rx = 0, ry = 0;
  BodyState s = s0;
  while (sim->time() < scene.simulation.end_time - 1e-9 * sim->dt()) {
    sim->step();
    s = body_states(*sim, nm)[std::size_t(body)];
    r.sink = std::max(r.sink, s0.y - s.y);
    if (sim->time() < t_fit) continue;
    t.push_back(sim->time()), v.push_back(s.vx), w.push_back(s.omega);
    for (const Reaction& q : sim->reactions())
      if (q.name == floor) rx += q.force[0], ry += q.force[1];
  }
  r.accel = slope(t, v);
  r.spin_accel = slope(t, w);
  r.slide = s.x - s0.x;
  r.reaction[0] = rx / double(t.size());
  r.reaction[1] = ry / double(t.size());
  r.mode = velocity_mode_ratio(*sim, nm, body);
  note(
      "%s mu %.2f: a %.4f (sliding %.4f, rolling %.4f), alpha %.4f, slide %.5f mm, sink %.5f mm, "
      "floor reaction (%.5f, %.5f) N, m G = %.5f N",
      file.c_str(), r.mu, r.accel, r.G * (std::sin(r.theta) - r.mu * std::cos(r.theta)),
      2.0 / 3.0 * r.G * std::sin(r.theta), r.spin_accel, r.slide, r.sink, r.reaction[0],
      r.reaction[1], r.mass * r.G);
  return r;
}

double sliding_accel(const InclineRun& r) {
  return r.G * (std::sin(r.theta) - r.mu * std::cos(r.theta));
}

const std::string kMidCell = "grid.origin=[0.0,-0.25]";  // floor top at cell mid-height
const std::string kSticking = "interaction[0].friction=0.7";

// mu = 0.2 < tan 30 deg: the block slides with a = G (sin theta - mu cos theta)
// = 65.36 mm/ms^2. Block 6 x 2 mm, E = 1000 MPa, h = 0.5 mm, 2 x 2 ppc,
// "displacement" separation, contact plane on a grid line. Tolerance 1 %.
TEST(ValidationContact, BlockSlidesDownInclineWithCoulombFriction) {
  const InclineRun r = run_incline("incline_block.toml", {});
  EXPECT_NEAR(r.accel / sliding_accel(r), 1.0, 0.01)
      << "a = " << r.accel << ", exact " << sliding_accel(r);
  EXPECT_LT(r.sink, 0.01 * 0.5) << "the block must stay on the floor";
}

// The same block under USL with linear shapes, which stopped at step 397
// with J <= 0 (a bottom particle crossing into the floor's cell row) before
// USL's light-node mass (docs/validation.md §3.5); the rolling disk of
// DiskRollsWithoutSlipping, which stopped at step 101. Same tolerances as
// those tests. Measured 2026-12-06: block a = 65.419 (+0.09 %), disk a =
// 61.52 (-7.7 %; MUSL with uGIMP 61.59) and alpha R / a within 5 % of -1.
TEST(ValidationContact, BlockAndDiskOnInclineUnderUslWithLinearShapes) {
  const std::vector<std::string> usl = {"simulation.scheme=\"USL\"", "grid.shape=\"linear\""};
  const InclineRun block = run_incline("incline_block.toml", usl);
  EXPECT_NEAR(block.accel / sliding_accel(block), 1.0, 0.01)
      << "a = " << block.accel << ", exact " << sliding_accel(block);
  EXPECT_LT(block.sink, 0.01 * 0.5) << "the block must stay on the floor";
  const InclineRun disk = run_incline("incline_disk.toml", usl);
  const double roll = 2.0 / 3.0 * disk.G * std::sin(disk.theta);
  EXPECT_NEAR(disk.accel / roll, 1.0, 0.10) << "a = " << disk.accel << ", rolling " << roll;
  EXPECT_NEAR(disk.spin_accel * disk.radius / disk.accel, -1.0, 0.05);
}

// mu = 0.7 >= tan 30 deg = 0.577: the block must not slide. Tolerances: fitted
// acceleration below 1 % of G sin theta; displacement along the slope below
// 1 % of a cell (the elastic shear of the block alone is ~5e-4 mm).
TEST(ValidationContact, BlockSticksWhenFrictionExceedsSlope) {
  const InclineRun r = run_incline("incline_block.toml", {kSticking});
  EXPECT_LT(std::abs(r.accel), 0.01 * r.G * std::sin(r.theta));
  EXPECT_LT(std::abs(r.slide), 0.01 * 0.5);
}

// The force on the rigid floor (reactions() "rigid:floor", averaged over the
// fit window) is what the block presses on it: sliding, (mu, -1) m G cos theta;
// sticking, (sin theta, -cos theta) m G. Momentum balance of the block makes
// this exact once its acceleration is right (§3.3). Tolerance 1 %.
TEST(ValidationContact, RigidFloorReactionEqualsBlockLoad) {
  {
    const InclineRun r = run_incline("incline_block.toml", {});
    const double n = r.mass * r.G * std::cos(r.theta);
    EXPECT_NEAR(r.reaction[0] / (r.mu * n), 1.0, 0.01)
        << "sliding: tangential " << r.reaction[0] << ", exact " << r.mu * n;
    EXPECT_NEAR(r.reaction[1] / -n, 1.0, 0.01)
        << "sliding: normal " << r.reaction[1] << ", exact " << -n;
  }
  {
    const InclineRun r = run_incline("incline_block.toml", {kSticking});
    const double W = r.mass * r.G;
    EXPECT_NEAR(r.reaction[0] / (W * std::sin(r.theta)), 1.0, 0.01)
        << "sticking: tangential " << r.reaction[0] << ", exact " << W * std::sin(r.theta);
    EXPECT_NEAR(r.reaction[1] / (-W * std::cos(r.theta)), 1.0, 0.01)
        << "sticking: normal " << r.reaction[1] << ", exact " << -W * std::cos(r.theta);
  }
}

// 3D bodies on a rigid floor (ALGORITHM §3.1 in 3D), gravity tilted by
// 30 degrees towards d = (2, 1, 0) / sqrt 5, so that the motion lies along
// no grid axis and no diagonal: the Coulomb law must take the tangent t from
// the tangential momentum change in the plane, not from the axes (friction
// capped per axis would be off in size and turn the motion off d). Same
// physics as incline_block.toml and incline_disk.toml (G = 200 mm/ms^2
// ramped over 0.05 ms), h = 0.5 mm, 2 ppc, uGIMP, floor top on a grid plane
// (z = 3). The body's centre-of-mass velocity and spin (angular momentum
// through the inertia tensor about the centre) are fitted from t = 0.07 ms
// to 0.2 ms.
const std::array<double, 2> kSlope3D = {2.0 / std::sqrt(5.0), 1.0 / std::sqrt(5.0)};

// Angle in degrees from d to the in-plane part of a.
double degrees_off_slope(const std::array<double, 3>& a) {
  return (std::atan2(a[1], a[0]) - std::atan2(kSlope3D[1], kSlope3D[0])) * 180.0 / std::numbers::pi;
}

struct Incline3D {
  double G = 0, theta = 0, mass = 0, radius = 0;
  std::array<double, 3> accel{}, spin_accel{}, reaction{};
  double slide = 0, sink = 0;
};

struct Motion3D {
  double m = 0, radius = 0;  // radius: sqrt(5 I_mean / (2 m)), a ball's R
  std::array<double, 3> x{}, v{}, omega{};
};

// Centre of mass, its velocity and the spin of material 0's particles.
Motion3D motion_3d(const Simulation& sim) {
  const auto pos = field(sim, "position"), vel = field(sim, "velocity"), mass = field(sim, "mass"),
             mat = field(sim, "material");
  Motion3D b;
  const std::size_t n = sim.particle_count();
  for (std::size_t p = 0; p < n; ++p) {
    if (mat.at(p) != 0) continue;
    b.m += mass.at(p);
    for (int c = 0; c < 3; ++c)
      b.x[c] += mass.at(p) * pos.at(p, c), b.v[c] += mass.at(p) * vel.at(p, c);
  }
  for (int c = 0; c < 3; ++c) b.x[c] /= b.m, b.v[c] /= b.m;
  Eigen::Vector3d L = Eigen::Vector3d::Zero();
  Eigen::Matrix3d I = Eigen::Matrix3d::Zero();  // inertia tensor about the centre of mass
  for (std::size_t p = 0; p < n; ++p) {
    if (mat.at(p) != 0) continue;
    Eigen::Vector3d r, u;
    for (int c = 0; c < 3; ++c) r[c] = pos.at(p, c) - b.x[c], u[c] = vel.at(p, c) - b.v[c];
    L += mass.at(p) * r.cross(u);
    I += mass.at(p) * (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose());
  }
  const Eigen::Vector3d omega = I.ldlt().solve(L);  // I is symmetric positive definite
  for (int c = 0; c < 3; ++c) b.omega[c] = omega[c];
  b.radius = std::sqrt(5.0 * I.trace() / 3.0 / (2.0 * b.m));
  return b;
}

const std::string kFloor3D = R"(
[simulation]
dimension = 3
end_time  = 0.2
cfl       = 0.5
scheme    = "MUSL"
flip      = 1.0
[grid]
origin = [0.0, 0.0, 0.0]
cell   = [0.5, 0.5, 0.5]
shape  = "gimp"
[[material]]
name    = "body"
type    = "isotropic"
density = 1.0e-3
nu      = 0.3
[[material]]
name     = "floor"
type     = "rigid"
density  = 1.0e-3
velocity = [0.0, 0.0, 0.0]
[[body]]
name     = "floor"
material = "floor"
shape    = "box"
min      = [1.0, 1.0, 1.0]
max      = [15.0, 15.0, 3.0]
particles_per_cell = 2
[[interaction]]
materials  = ["body", "floor"]
law        = "friction"
normal     = "rigid"
[[load]]
kind         = "gravity"
acceleration = [0.0, 0.0, -1.0]
ramp         = 0.05
)";

// The 4 x 4 x 2 mm block (E = 1000 MPa, "displacement" separation, 16 x 16
// x 14 cells around it) and the ball of radius 3 mm at (5, 5, 6) (E = 100
// MPa, "position" separation as for the 2D disk; 32 x 32 x 20 cells).
const std::string kBlock3D = R"(
[[body]]
name     = "block"
material = "body"
shape    = "box"
min      = [3.0, 3.0, 3.0]
max      = [7.0, 7.0, 5.0]
particles_per_cell = 2
)";
const std::string kBall3D = R"(
[[body]]
name     = "ball"
material = "body"
shape    = "sphere"
center   = [5.0, 5.0, 6.0]
radius   = 3.0
particles_per_cell = 2
)";

constexpr double kG3D = 200.0, kTheta3D = std::numbers::pi / 6;

// The settings run_incline_3d gives kFloor3D + body, then `overrides`.
std::vector<std::string> incline_3d_settings(const std::string& body, double mu,
                                             std::vector<std::string> overrides) {
  const double gt = kG3D * std::sin(kTheta3D), gn = -kG3D * std::cos(kTheta3D);
  const bool ball = body == kBall3D;
  overrides.insert(overrides.begin(), {"interaction[0].friction=" + num(mu),
                                       "load[0].acceleration=[" + num(gt * kSlope3D[0]) + "," +
                                           num(gt * kSlope3D[1]) + "," + num(gn) + "]",
                                       ball ? "grid.cells=[32,32,20]" : "grid.cells=[32,32,14]",
                                       ball ? "material[0].E=100.0" : "material[0].E=1000.0",
                                       ball ? "interaction[0].separation=\"position\""
                                            : "interaction[0].separation=\"displacement\""});
  return overrides;
}

Incline3D run_incline_3d(const std::string& body, double mu,
                         const std::vector<std::string>& overrides = {}) {
  const double G = kG3D, theta = kTheta3D;
  const bool ball = body == kBall3D;
  auto sim = testing::make_from_text(kFloor3D + body, incline_3d_settings(body, mu, overrides));
  Incline3D r;
  r.G = G, r.theta = theta;
  const Motion3D m0 = motion_3d(*sim);
  r.mass = m0.m, r.radius = m0.radius;
  Motion3D m = m0;
  std::vector<double> t;
  std::array<std::vector<double>, 3> v, w;
  int rows = 0;
  while (sim->time() < 0.2 - 1e-9 * sim->dt()) {
    sim->step();
    m = motion_3d(*sim);
    r.sink = std::max(r.sink, m0.x[2] - m.x[2]);
    if (sim->time() < 0.07) continue;
    t.push_back(sim->time());
    for (int c = 0; c < 3; ++c) v[c].push_back(m.v[c]), w[c].push_back(m.omega[c]);
    for (const Reaction& q : sim->reactions())
      if (q.name == "rigid:floor")
        for (int c = 0; c < 3; ++c) r.reaction[c] += q.force[c];
    ++rows;
  }
  for (int c = 0; c < 3; ++c)
    r.accel[c] = slope(t, v[c]), r.spin_accel[c] = slope(t, w[c]), r.reaction[c] /= rows;
  r.slide = std::hypot(m.x[0] - m0.x[0], m.x[1] - m0.x[1]);
  note(
      "3D %s mu %.2f: a (%.4f, %.4f, %.4f), alpha (%.4f, %.4f, %.4f), R %.4f, slide %.5f mm, "
      "sink %.5f mm, floor reaction (%.5f, %.5f, %.5f) N, m G %.5f N",
      ball ? "ball" : "block", mu, r.accel[0], r.accel[1], r.accel[2], r.spin_accel[0],
      r.spin_accel[1], r.spin_accel[2], r.radius, r.slide, r.sink, r.reaction[0], r.reaction[1],
      r.reaction[2], r.mass * G);
  return r;
}

// Block, sliding (mu = 0.2): |a| = G (sin theta - mu cos theta) = 65.36
// mm/ms^2 within 1 %, along d within 0.1 degree, the floor's
// reaction (mu N d, -N) within 1 %, N = m G cos theta. Sticking (mu = 0.7 >
// tan 30): no slide beyond 1 % of a cell, and the floor holds the tilted
// weight m G (sin theta d, -cos theta) within 1 %.
// The force on the floor, (T d, -N), each component within 1 %.
void expect_floor_reaction(const Incline3D& r, double T, double N) {
  for (int c = 0; c < 2; ++c)
    EXPECT_NEAR(r.reaction[c] / (T * kSlope3D[c]), 1.0, 0.01)
        << "tangential reaction " << c << ": " << r.reaction[c];
  EXPECT_NEAR(r.reaction[2] / -N, 1.0, 0.01) << "normal reaction " << r.reaction[2];
}

TEST(ValidationContact, Block3DSlidesAlongASlantOfTheFloor) {
  const double mu = 0.2;
  const Incline3D r = run_incline_3d(kBlock3D, mu);
  const double exact = r.G * (std::sin(r.theta) - mu * std::cos(r.theta));
  const double a_t = std::hypot(r.accel[0], r.accel[1]);
  EXPECT_NEAR(a_t / exact, 1.0, 0.01) << "|a_t| = " << a_t << ", exact " << exact;
  EXPECT_LT(std::abs(degrees_off_slope(r.accel)), 0.1) << "the block slid off d";
  EXPECT_LT(r.sink, 0.01 * 0.5) << "the block must stay on the floor";
  const double N = r.mass * r.G * std::cos(r.theta);
  expect_floor_reaction(r, mu * N, N);
}

// The sliding block above under USL at the 3D limits `run` and `check`
// warn above (usl_cfl_limit): linear shapes at cfl 0.55, cubic B-splines
// at 0.95. |a| within 0.5 %, along d within 0.1 degree. Measured (fitted
// to the mean displacement from 0.08 ms) 65.3584 and 65.3586 against
// 65.359; above the limits the block's velocity mode grows: linear at 0.65
// a = 67.25 (+2.9 %), cubic at 1.0 67.01 (+2.5 %), where 2D ran to 0.7 and
// 1.0.
TEST(ValidationContact, Block3DSlidesUnderUslAtItsLimits) {
  const double mu = 0.2;
  for (const auto& [shape, cfl] : {std::pair<std::string, std::string>{"linear", "0.55"},
                                   std::pair<std::string, std::string>{"bspline3", "0.95"}}) {
    const std::vector<std::string> usl = {"simulation.scheme=\"USL\"",
                                          "grid.shape=\"" + shape + "\"", "simulation.cfl=" + cfl};
    const Incline3D r = run_incline_3d(kBlock3D, mu, usl);
    const double exact = r.G * (std::sin(r.theta) - mu * std::cos(r.theta));
    const double a_t = std::hypot(r.accel[0], r.accel[1]);
    EXPECT_NEAR(a_t / exact, 1.0, 0.005) << shape << ": |a_t| = " << a_t << ", exact " << exact;
    EXPECT_LT(std::abs(degrees_off_slope(r.accel)), 0.1) << shape;
    // At the limit no warning; 0.05 above it, one.
    std::vector<std::string> above = usl;
    above.back() = "simulation.cfl=" + num(std::stod(cfl) + 0.05);
    for (const auto& [sets, warns] : {std::pair{usl, false}, std::pair{above, true}}) {
      const Scene scene = parse_scene_text(kFloor3D + kBlock3D, "block3d.toml",
                                           incline_3d_settings(kBlock3D, mu, sets));
      EXPECT_EQ(!usl_time_step_warning(scene, stable_time_step(scene)).empty(), warns)
          << shape << " " << sets.back();
    }
  }
}

TEST(ValidationContact, Block3DSticksWhenFrictionExceedsSlope) {
  const Incline3D r = run_incline_3d(kBlock3D, 0.7);
  EXPECT_LT(r.slide, 0.01 * 0.5);
  EXPECT_LT(std::hypot(r.accel[0], r.accel[1]), 0.01 * r.G * std::sin(r.theta));
  const double W = r.mass * r.G;  // the floor holds the whole tilted weight
  expect_floor_reaction(r, W * std::sin(r.theta), W * std::cos(r.theta));
}

// Ball, rolling (mu = 0.5 >= (2/7) tan theta = 0.165): a solid sphere rolls
// without slipping with a = (5/7) G sin theta = 71.43 mm/ms^2 along d
// (m a = m G sin theta - F, I alpha = F R, I = (2/5) m R^2). Tolerances as
// the 2D disk's (docs/contact_validation.md §4.2): a within 10 %, along d
// within 1 degree (its contact patch spans a few nodes of the cubic grid;
// measured 0.43 degree). The rolling constraint alpha R = a is the 2D disk's known
// limitation in 3D (§4.3, §10: measured 0.78 of it): checked only to have
// the right axis and sign and at least half the size.
TEST(ValidationContact, Ball3DRollsDownASlant) {
  const Incline3D r = run_incline_3d(kBall3D, 0.5);
  const double rolling = 5.0 / 7.0 * r.G * std::sin(r.theta);
  const double a = std::hypot(r.accel[0], r.accel[1]);
  EXPECT_NEAR(a / rolling, 1.0, 0.10) << "a = " << a << ", rolling " << rolling;
  EXPECT_LT(std::abs(degrees_off_slope(r.accel)), 1.0) << "the ball rolled off d";
  // On a floor below, rolling means v = R omega x z, i.e. omega = z x v / R:
  // the spin axis is z x d = (-d_y, d_x, 0), with alpha R = a about it and
  // no spin about d or z.
  const std::array<double, 3>& al = r.spin_accel;
  const double spin = (-al[0] * kSlope3D[1] + al[1] * kSlope3D[0]) * r.radius;
  const double wobble = (al[0] * kSlope3D[0] + al[1] * kSlope3D[1]) * r.radius;
  EXPECT_GT(spin / a, 0.5) << "alpha R = " << spin << ", a = " << a;
  EXPECT_LT(spin / a, 1.1) << "alpha R = " << spin << ", a = " << a;
  EXPECT_LT(std::abs(wobble), 0.02 * a) << "spin about d: " << wobble;
  EXPECT_LT(std::abs(al[2] * r.radius), 0.02 * a) << "spin about z: " << al[2];
}

// The same two runs with the grid shifted by half a cell, so that the floor
// top lies at cell mid-height instead of on a grid line: the sliding
// acceleration within 1 % of the grid-line run (and of the exact value), the
// block still sticks at mu = 0.7. "displacement" separation (the scene's).
TEST(ValidationContact, BlockOnInclineIndependentOfContactPlaneInCell) {
  const InclineRun line = run_incline("incline_block.toml", {});
  const InclineRun mid = run_incline("incline_block.toml", {kMidCell});
  EXPECT_NEAR(mid.accel / line.accel, 1.0, 0.01)
      << "grid line " << line.accel << ", mid-cell " << mid.accel;
  EXPECT_NEAR(mid.accel / sliding_accel(mid), 1.0, 0.01);
  EXPECT_LT(mid.sink, 0.01 * 0.5);
  const InclineRun stick = run_incline("incline_block.toml", {kMidCell, kSticking});
  EXPECT_LT(std::abs(stick.slide), 0.01 * 0.5);
}

// The same with the "position" separation method (ALGORITHM §3: contact when
// delta_n - 0.8 h < 0), which a block resting on a floor may also use: on a
// grid line and at cell mid-height the block slides at the exact
// acceleration (1 %) without sinking more than 2 % of a cell, and sticks at
// mu = 0.7 (slide below 1 % of a cell).
TEST(ValidationContact, BlockOnInclinePositionSeparationIndependentOfContactPlaneInCell) {
  MMPM_KNOWN_LIMITATION(
      "position separation with the fixed 0.8 h offset: at mid-cell the block sinks "
      "0.035 mm and slides 0.53 mm at mu = 0.7 (the displacement method passes)");
  const std::string position = "interaction[0].separation=\"position\"";
  for (const std::string& where : {std::string("grid.origin=[0.0,0.0]"), kMidCell}) {
    const InclineRun slide = run_incline("incline_block.toml", {position, where});
    EXPECT_NEAR(slide.accel / sliding_accel(slide), 1.0, 0.01) << where;
    EXPECT_LT(slide.sink, 0.02 * 0.5) << where;
    const InclineRun stick = run_incline("incline_block.toml", {position, where, kSticking});
    EXPECT_LT(std::abs(stick.slide), 0.01 * 0.5) << where;
  }
}

// Disk R = 3 mm, E = 100 MPa (contact half-width ~0.4 mm, about a cell),
// h = 0.5 mm (6 cells per radius), 2 x 2 ppc, "position" separation.
// mu = 0.5 >= tan(theta)/3: rolls without slipping, a = (2/3) G sin theta =
// 66.67 mm/ms^2 within 10 % (the disk is rough at 6 cells per radius) and the
// rolling constraint alpha R = -a within 5 %.
TEST(ValidationContact, DiskRollsWithoutSlipping) {
  const InclineRun r = run_incline("incline_disk.toml", {});
  const double roll = 2.0 / 3.0 * r.G * std::sin(r.theta);
  EXPECT_NEAR(r.accel / roll, 1.0, 0.10) << "a = " << r.accel << ", rolling " << roll;
  EXPECT_NEAR(r.spin_accel * r.radius / r.accel, -1.0, 0.05)
      << "alpha R = " << r.spin_accel * r.radius << ", a = " << r.accel;
}

// mu = 0.05 < tan(theta)/3: slides with a = G (sin theta - mu cos theta) =
// 91.34 mm/ms^2 (within 5 %) while friction spins it up at
// alpha = -2 mu G cos(theta) / R (within 10 %), slower than rolling would need.
TEST(ValidationContact, DiskSlidesWhenFrictionIsLow) {
  MMPM_KNOWN_LIMITATION(
      "the sliding disk's spin-up is 67 % of mu m g cos(theta) R / I with MUSL "
      "(linear acceleration within 1 %): nodes ahead of the contact point count as "
      "in contact under the paper's offset 0.8 h and push up there "
      "(docs/contact_validation.md §4.3; DiskSpinUpFollowsTheContactOffset)");
  const InclineRun r = run_incline("incline_disk.toml", {"interaction[0].friction=0.05"});
  EXPECT_NEAR(r.accel / sliding_accel(r), 1.0, 0.05)
      << "a = " << r.accel << ", exact " << sliding_accel(r);
  const double alpha = -2.0 * r.mu * r.G * std::cos(r.theta) / r.radius;
  EXPECT_NEAR(r.spin_accel / alpha, 1.0, 0.10) << "alpha = " << r.spin_accel << ", exact " << alpha;
  EXPECT_LT(std::abs(r.spin_accel) * r.radius, 0.5 * r.accel) << "it must slip";
}

// An incline built by rotating the geometry 20 degrees (floor and block as
// rotated boxes on the grid, vertical gravity G = 100 mm/ms^2 ramped over
// 0.05 ms), not by tilting gravity over a grid-aligned floor as in §3: the
// surfaces are staircases of particles. h = 0.25 mm, 2 x 2 ppc, block
// 4 x 1.5 mm, E = 1000 MPa, mu = 0.15 (inputs/rotated_incline.toml).
// Down-slope acceleration of the block's centre of mass, fitted over
// 0.07-0.2 ms.
double down_slope_accel(Simulation& sim) {
  const double th = 20.0 * std::numbers::pi / 180.0;
  std::vector<double> t, v;
  while (sim.time() < 0.2 - 1e-9 * sim.dt()) {
    sim.step();
    if (sim.time() < 0.07) continue;
    const BodyState b = body_states(sim, 2)[0];
    t.push_back(sim.time());
    v.push_back(-(b.vx * std::cos(th) + b.vy * std::sin(th)));  // down the slope
  }
  return slope(t, v);
}

// The down-slope accelerations of the two laws the scene is run with:
// frictionless G sin 20 = 34.202, mu = 0.15 G (sin 20 - 0.15 cos 20) =
// 20.107 mm/ms^2, each within 0.5 %.
void expect_slides_down_the_incline(double frictionless, double friction) {
  const double th = 20.0 * std::numbers::pi / 180.0;
  EXPECT_NEAR(frictionless / (100.0 * std::sin(th)), 1.0, 0.005) << frictionless;
  EXPECT_NEAR(friction / (100.0 * (std::sin(th) - 0.15 * std::cos(th))), 1.0, 0.005) << friction;
}

double rotated_incline_accel(const std::vector<std::string>& overrides) {
  return down_slope_accel(
      *make_simulation(parse_scene_file(input("rotated_incline.toml"), overrides)));
}

// With the slope's normal given (normal = "specified"), contact on the
// staircase surfaces is exact: frictionless a = G sin 20 = 34.202, and
// mu = 0.15 gives G (sin - mu cos) = 20.107 mm/ms^2; 0.5 % tolerance
// (measured 2e-14 and 2e-7).
TEST(ValidationContact, RotatedInclineWithSpecifiedNormal) {
  const std::string specified = "interaction[0].normal=\"specified\"";
  const std::string slope =
      "interaction[0].normal_vector=[0.3420201433256687, -0.9396926207859084]";
  expect_slides_down_the_incline(
      rotated_incline_accel({"interaction[0].law=\"frictionless\"", specified, slope}),
      rotated_incline_accel({specified, slope}));
}

// normal = "geometry" takes the floor's normal from its rotated box, not
// from its particles' staircase (docs/contact_validation.md §18): exact as
// the specified normal, on every face the block meets, without being told
// the slope. Frictionless a = 34.202, mu = 0.15 a = 20.107 mm/ms^2, 0.5 %
// (measured 34.2020 and 20.1075; h = 0.125 frictionless: 34.2020).
TEST(ValidationContact, RotatedInclineWithGeometryNormal) {
  expect_slides_down_the_incline(rotated_incline_accel({"interaction[0].law=\"frictionless\""}),
                                 rotated_incline_accel({}));
}

// The same incline with an elastic floor (E = 1000 MPa, its lower half held
// by boxes of fixed nodes one millimetre wide): both faces are deformable,
// each body's shape follows the rotation and translation that fit its
// particles, and where the block's leading edge meets the floor's face
// the pair takes the face's normal (solver/geometry_normals.hpp). Exact
// G sin 20 = 34.202 and G (sin 20 - 0.15 cos 20) = 20.107 mm/ms^2, 0.5 %
// (measured 34.2105 and 20.1114; h = 0.125: 34.2021; the specified normal
// gives 34.2102; mvg locks at -0.007).
std::string rotated_incline_on_an_elastic_floor() {
  std::string text = mmpm_test::read_text(input("rotated_incline.toml"));
  const std::string rigid = "type     = \"rigid\"\ndensity  = 1.0e-3\nvelocity = [0.0, 0.0]";
  const auto at = text.find(rigid);
  EXPECT_NE(at, std::string::npos);
  text.replace(at, rigid.size(), "type = \"isotropic\"\ndensity = 1.0e-3\nE = 1000.0\nnu = 0.3");
  // The floor's mid-plane y' = 3 (body frame), 1 mm below its face.
  const double th = 20.0 * std::numbers::pi / 180.0;
  const double px = 12.0 + std::sin(th), py = 4.0 - std::cos(th);
  std::ostringstream held;
  for (int x0 = 0; x0 < 24; ++x0) {
    const double top = -3.0 + 0.25 * std::floor((py + (x0 - px) * std::tan(th) + 3.0) / 0.25);
    if (top > -3.0)
      held << "[[boundary]]\nwhere = { min = [" << x0 << ".0, -3.0], max = [" << x0 + 1 << ".0, "
           << top << "] }\nfix = [\"x\", \"y\"]\n";
  }
  const auto load = text.find("[[load]]");
  text.insert(load, held.str());
  return text;
}

double elastic_floor_accel(const std::vector<std::string>& overrides) {
  return down_slope_accel(
      *testing::make_from_text(rotated_incline_on_an_elastic_floor(), overrides));
}

TEST(ValidationContact, RotatedInclineOnAnElasticFloorWithGeometryNormal) {
  expect_slides_down_the_incline(elastic_floor_accel({"interaction[0].law=\"frictionless\""}),
                                 elastic_floor_accel({}));
  const double th = 20.0 * std::numbers::pi / 180.0;
  const double refined = elastic_floor_accel(
      {"interaction[0].law=\"frictionless\"", "grid.cell=[0.125,0.125]", "grid.cells=[192,112]"});
  EXPECT_NEAR(refined / (100.0 * std::sin(th)), 1.0, 0.005) << refined;
}

// USL with linear shapes, blocks sliding under Coulomb friction: on
// incline_block.toml's grid-aligned rigid floor (a = G (sin 30 - 0.2 cos 30)
// = 65.359, fitted over 0.07-0.2 ms), on rotated_incline.toml's rigid
// staircase and on its elastic floor (20.107). At the block's light nodes
// the update leaves part of the force out of the momentum; the floor must
// take its normal part with the friction it carries (exchange_left_out,
// docs/validation.md §3.5 "Sliding pairs"). Left in dvel, it came back
// every step as a velocity mode, measured as the kinetic energy about the
// centre-of-mass velocity over the bulk: 4e-3 / 2.6e-2 (grid-aligned,
// cfl 0.5 / 0.7), 3.6e-2 / 8 (staircase; its K + U grew to 7 times the
// work at 0.7), 7.3e-2 on the elastic floor at 0.5, whose block stopped
// unstable at 0.65 and 0.7. Measured now 9e-7 / 1.2e-6, 1.1e-5 / 1.8e-5
// (MUSL 9e-6, 6e-5) and 8.6e-4 / 9.5e-4 on the elastic floor, where the
// block rocks on the floor's compliance (MUSL 9.8e-4, uGIMP 7.7e-4).
// Tolerances: a 0.5 %; the mode ratio 1e-4 on the rigid floors, 2e-3 on
// the elastic one; at cfl 0.5 and at 0.7, USL's limit for linear shapes.
TEST(ValidationContact, SlidingBlocksUnderUslWithLinearShapesCarryNoVelocityMode) {
  const double th = 20.0 * std::numbers::pi / 180.0;
  const double on_staircase = 100.0 * (std::sin(th) - 0.15 * std::cos(th));
  for (const char* cfl : {"0.5", "0.7"}) {
    const std::vector<std::string> usl = {"simulation.scheme=\"USL\"", "grid.shape=\"linear\"",
                                          std::string("simulation.cfl=") + cfl};
    const InclineRun grid_aligned = run_incline("incline_block.toml", usl);
    note("incline_block USL linear cfl %s: mode %.2e", cfl, grid_aligned.mode);
    EXPECT_NEAR(grid_aligned.accel / sliding_accel(grid_aligned), 1.0, 0.005) << "cfl " << cfl;
    EXPECT_LT(grid_aligned.mode, 1e-4) << "cfl " << cfl;

    auto rigid = make_simulation(parse_scene_file(input("rotated_incline.toml"), usl));
    auto elastic = testing::make_from_text(rotated_incline_on_an_elastic_floor(), usl);
    for (Simulation* sim : {rigid.get(), elastic.get()}) {
      const char* floor = sim == rigid.get() ? "rigid" : "elastic";
      const double a = down_slope_accel(*sim);
      const double ratio = velocity_mode_ratio(*sim, 2);
      note("rotated_incline, %s floor, USL linear cfl %s: a %.4f (exact %.4f), mode %.2e", floor,
           cfl, a, on_staircase, ratio);
      EXPECT_NEAR(a / on_staircase, 1.0, 0.005) << floor << " floor, cfl " << cfl;
      EXPECT_LT(ratio, sim == rigid.get() ? 1e-4 : 2e-3) << floor << " floor, cfl " << cfl;
    }
  }
}

// The same with normals computed from the grid: the staircases give each
// contact node a normal off the slope's by up to tens of degrees, and each
// node's constraint then takes part of the sliding velocity every step, so
// the block does not slide. Measured, frictionless (exact 34.2): mvg
// -0.009 (0.002 at h = 0.125 mm), avg -0.004, rigid 13.8 (-60 %; 13.8 at
// h = 0.125 too: it does not converge). Computed normals suit surfaces on
// grid lines, curved bodies (where MVG tracks the curvature, §4) and
// tilted gravity; a planar surface at an angle to the grid needs
// "specified", or "geometry" when the surface is a rigid body's (README
// "Choosing settings").
TEST(ValidationContact, RotatedInclineWithComputedNormals) {
  MMPM_KNOWN_LIMITATION(
      "frictionless block on a 20-degree incline built from rotated boxes: a = -0.009 (mvg), "
      "-0.004 (avg) and 13.8 (rigid) against 34.2 mm/ms^2; exact with normal = \"specified\"");
  const double th = 20.0 * std::numbers::pi / 180.0;
  for (const char* normal : {"mvg", "avg", "rigid"}) {
    const double a =
        rotated_incline_accel({"interaction[0].law=\"frictionless\"",
                               std::string("interaction[0].normal=\"") + normal + "\""});
    EXPECT_NEAR(a / (100.0 * std::sin(th)), 1.0, 0.05) << normal << ": a = " << a;
  }
}

// Why the sliding disk spins up too slowly (docs/contact_validation.md §4.3):
// with the paper's contact offset 0.8 h the nodes up to ~1 mm ahead of the
// contact point, where the disk is still 0-0.13 mm above the floor, count
// as in contact; the normal force they take sits ahead of the centre and
// its torque cancels about half of the friction torque. A smaller offset
// registers contact only nearer the contact point: at 0.6 h the spin-up is
// within 10 % of the exact value, and the disk sinks deeper (the price).
// h = 0.5 mm, mu = 0.05, the fit window of DiskSlidesWhenFrictionIsLow.
// Measured 0.511 (0.8 h) and 0.993 (0.6 h) before MUSL's strain pass held
// the pairs pass B held (kHeldInPassB, §12): that repeat's one-sided test was
// a second brake. Now 0.665 and 0.956: the offset still holds a third back.
TEST(ValidationContact, DiskSpinUpFollowsTheContactOffset) {
  double spin[2] = {0, 0}, sink[2] = {0, 0};
  const double offsets[2] = {0.8, 0.6};
  for (int k = 0; k < 2; ++k) {
    const InclineRun r = run_incline(
        "incline_disk.toml",
        {"interaction[0].friction=0.05", "interaction[0].contact_offset=" + num(offsets[k])});
    const double alpha = -2.0 * r.mu * r.G * std::cos(r.theta) / r.radius;
    spin[k] = r.spin_accel / alpha;
    sink[k] = r.sink;
    note("contact_offset %.1f: spin-up %.3f of exact, a %.3f (exact %.3f), sink %.4f mm",
         offsets[k], spin[k], r.accel, sliding_accel(r), r.sink);
    EXPECT_NEAR(r.accel / sliding_accel(r), 1.0, 0.05) << "offset " << offsets[k];
  }
  EXPECT_NEAR(spin[1], 1.0, 0.10) << "spin-up with the offset 0.6 h";
  EXPECT_LT(spin[0], 0.75) << "the paper's offset holds the spin back";
  EXPECT_GT(spin[1] - spin[0], 0.2) << "the offset must be what holds the spin back";
  EXPECT_GT(sink[1], sink[0] + 0.1) << "a later contact lets the disk sink deeper";
}

// §9 A rigid grip's work (docs/contact_validation.md §9,
// inputs/gripped_bar.toml). A bar (E 1000
// MPa, nu 0, plane stress, 10 x 1 mm, h = 0.5 mm, 2 x 2 ppc, uGIMP) bonded
// to two rigid grips by perfect interfaces (the contact laws, "stick"
// included, act only while the materials approach, so they cannot pull):
// the left grip at rest, the right one moved by a velocity table
// 0 -> 0.1 -> 0 mm/ms over 0.1 ms (d = 0.005 mm in all), slow against the
// bar's 0.01 ms wave transit; grid damping 200 / ms settles it by 0.3 ms.
// The grips do the only work, so their work (ALGORITHM §7: the force on
// the bodies times the grip's velocity) is the external work, and
// kinetic + strain + damping - external work stays within 1 % of the work
// (measured +0.29 %; before the grips' work was counted it was +100 %).
// The strain energy is E A d^2 / (2 L) = 1.25e-3 mJ with L = 10 mm, the
// distance between the grips, to 1 % (measured 8e-6). With the grip far
// from the bar the same table moves it without work or kinetic energy: a
// prescribed motion is not part of the system's energy.

TEST(ValidationContact, RigidGripWorkIsExternalWork) {
  auto sim = make_simulation(parse_scene_file(input("gripped_bar.toml")));
  testing::run_until(*sim, 0.3);
  const Energies e = sim->energies();
  const double exact = 1000.0 * 1.0 * 0.005 * 0.005 / (2.0 * 10.0);
  const double balance = energy_balance(e);
  note(
      "gripped bar: W %.6g mJ, strain %.6g (exact %.6g), kinetic %.3g, damping %.4g, "
      "balance %.3g of W",
      e.external_work, e.strain, exact, e.kinetic, e.damping, balance / e.external_work);
  EXPECT_NEAR(e.strain / exact, 1.0, 0.01);
  EXPECT_LT(std::abs(balance), 0.01 * e.external_work);
  EXPECT_LT(e.kinetic, 1e-3 * e.strain) << "settled";

  auto apart = make_simulation(parse_scene_file(
      input("gripped_bar.toml"), {"body[2].min=[13.0, 0.0]", "body[2].max=[14.0, 1.0]"}));
  testing::run_until(*apart, 0.07);
  const Energies f = apart->energies();
  EXPECT_EQ(f.kinetic, 0.0);
  EXPECT_EQ(f.external_work, 0.0);
  EXPECT_EQ(f.strain, 0.0);
}

// A rigid platen pressed into an elastic block (inputs/platen.toml,
// docs/contact_validation.md §11): frictionless contact, free side, roller
// base, so the block is in uniaxial stress and the platen's reaction is the
// block's stiffness times its travel d: F = E' A d / L, with E' = E/(1 - nu^2)
// in plane strain (A = 4 mm x 1 mm, L = 4 mm) and E in 3D (A = 2 x 2 mm).
// h = 0.25 mm (L = 16 h), 2 ppc, d = 0.01 mm (4 % of a cell) at 1 ms;
// tolerance 1 %. Before the rigid-presence test (kRigidPresentFraction),
// uGIMP read +7.2 % (2D) and +7.6 % (3D): the platen's overhanging
// particles made the nodes one cell inside the block contact nodes, and
// the block's top cell rode with the platen (+h / (L - h) = +6.7 %).

// The last step's reaction named `name` along `axis`.
double reaction_force(const Simulation& sim, const std::string& name, int axis) {
  for (const Reaction& r : sim.reactions())
    if (r.name == name) return r.force[std::size_t(axis)];
  ADD_FAILURE() << "no reaction named " << name;
  return std::numeric_limits<double>::quiet_NaN();
}

// The platen's reaction along `axis` after the step that reaches t = 1 ms.
double platen_force_at_1ms(Simulation& sim, int axis) {
  testing::run_until(sim, 1.0);
  return reaction_force(sim, "rigid:platen", axis);
}

double platen_reaction_over_exact(const std::vector<std::string>& overrides) {
  auto sim = make_simulation(parse_scene_file(input("platen.toml"), overrides));
  const double force = platen_force_at_1ms(*sim, 1);
  const double exact = 1000.0 / (1.0 - 0.3 * 0.3) * 4.0 * (0.01 * sim->time()) / 4.0;
  return force / exact;
}

TEST(ValidationContact, RigidPlatenReactionIsTheBlocksStiffness) {
  for (const char* shape : {"linear", "gimp"})
    for (const char* separation : {"displacement", "position"}) {
      const double ratio = platen_reaction_over_exact(
          {std::string("grid.shape=\"") + shape + "\"",
           std::string("interaction[0].separation=\"") + separation + "\""});
      note("platen 2D %s %s: F / exact %.4f", shape, separation, ratio);
      EXPECT_NEAR(ratio, 1.0, 0.01) << shape << " " << separation;
    }
}

TEST(ValidationContact, RigidPlatenReactionIsTheBlocksStiffness3D) {
  const std::string scene = R"(
[simulation]
dimension = 3
end_time = 1.0
cfl = 0.5
[grid]
origin = [-1.0, -1.0, -1.0]
cell = [0.25, 0.25, 0.25]
cells = [16, 16, 28]
shape = "gimp"
[[material]]
name = "block"
type = "isotropic"
density = 1.0e-3
E = 1000.0
nu = 0.3
[[material]]
name = "platen"
type = "rigid"
density = 1.0e-3
velocity = [0.0, 0.0, -0.01]
[[body]]
name = "block"
material = "block"
shape = "box"
min = [0.0, 0.0, 0.0]
max = [2.0, 2.0, 4.0]
[[body]]
name = "platen"
material = "platen"
shape = "box"
min = [-0.5, -0.5, 4.0]
max = [2.75, 2.75, 4.5]
[[interaction]]
materials = ["block", "platen"]
law = "frictionless"
normal = "rigid"
[[boundary]]
where = { min = [-1.0, -1.0, -1.0], max = [3.0, 3.0, 0.0] }
fix = ["z"]
[[boundary]]
where = { min = [-1.0, -1.0, -1.0], max = [0.0, 3.0, 6.0] }
fix = ["x"]
[[boundary]]
where = { min = [-1.0, -1.0, -1.0], max = [3.0, 0.0, 6.0] }
fix = ["y"]
)";
  auto sim = testing::make_from_text(scene);
  const double force = platen_force_at_1ms(*sim, 2);
  const double exact = 1000.0 * 4.0 * (0.01 * sim->time()) / 4.0;
  note("platen 3D gimp displacement: F / exact %.4f", force / exact);
  EXPECT_NEAR(force / exact, 1.0, 0.01);
}

// §12 Pressed contact under MUSL and pure FLIP (docs/contact_validation.md
// §12). MUSL repeats pass B on the re-extrapolated momenta, and the strain
// reads its result. That repeat used to stop approach only. At a pressed
// contact the re-extrapolated relative velocity is noise of either sign, so
// the strain saw partings the particles never made; pure FLIP keeps the
// noise, and the strain fell behind the motion step after step. Pass B now
// marks the pairs it held and the repeat holds them too (kHeldInPassB).
// Before, over the windows below: the stiff platen's drive read 0.47-2.09
// of exact (kinetic / strain up to 0.09, 9 % of the work lost); the rigid
// platen on a block of 1 particle per cell fell to 0.14-0.46 of exact.

// The reaction named `name` along y over stiffness x travel (`speed` mm/ms), averaged
// step by step over the windows [times[i-1], times[i]) (times[0]: the start). A mean
// over a window, not one step's value: an undamped drive rings around the static
// reaction (the stiff platen: +-3.4 % in the last 0.05 ms of 0.3, under USL +-1 %).
std::vector<double> reaction_over_exact(Simulation& sim, const std::string& name,
                                        const std::vector<double>& times, double stiffness,
                                        double speed, int axis = 1) {
  std::vector<double> out;
  testing::run_until(sim, times[0]);
  for (std::size_t w = 1; w < times.size(); ++w) {
    double sum = 0;
    long steps = 0;
    while (sim.time() < times[w] - 1e-9 * sim.dt()) {
      sim.step();
      sum += std::abs(reaction_force(sim, name, axis)) / (stiffness * speed * sim.time());
      ++steps;
    }
    out.push_back(sum / double(steps));
  }
  return out;
}

// The drive's stiffness in inputs/stiff_platen.toml: the block (E' W / L,
// W = L = 4 mm) and the platen (E_p W / t, t = 0.5 mm) in series, 1097.4 N/mm.
double stiff_platen_stiffness() {
  return 1.0 / (4.0 / (1000.0 / (1.0 - 0.3 * 0.3) * 4.0) + 0.5 / (1.0e5 * 4.0));
}

// inputs/stiff_platen.toml pushed 0.003 mm over 0.3 ms (the scene's speed), with
// `overrides` on top.
std::unique_ptr<Simulation> stiff_platen_for_0_3ms(std::vector<std::string> overrides) {
  overrides.insert(overrides.begin(), {"boundary[2].displacement=[0.0, -0.003]",
                                       "boundary[2].ramp=0.3", "simulation.end_time=0.3"});
  return make_simulation(parse_scene_file(input("stiff_platen.toml"), overrides));
}

// The frictionless stiff platen under `scheme`: the reaction's mean over each
// 0.05 ms from 0.1 ms within 1 % of the series stiffness, kinetic energy under
// 1e-3 of the strain energy, the energy balance within 1e-3 of the work.
void expect_stiff_platen_reads_the_series_stiffness(const std::string& scheme) {
  auto sim = stiff_platen_for_0_3ms({"simulation.scheme=\"" + scheme + "\""});
  const std::vector<double> ratio = reaction_over_exact(
      *sim, "plane_y=4.5", {0.1, 0.15, 0.2, 0.25, 0.3}, stiff_platen_stiffness(), 0.01);
  const Energies e = sim->energies();
  const double balance = energy_balance(e);
  note(
      "stiff platen, %s: F / exact, means over 0.05 ms from 0.1 ms: %.4f %.4f %.4f %.4f; "
      "kinetic / strain %.3g, balance %.3g of W",
      scheme.c_str(), ratio[0], ratio[1], ratio[2], ratio[3], e.kinetic / e.strain,
      balance / e.external_work);
  for (double r : ratio) EXPECT_NEAR(r, 1.0, 0.01) << scheme;
  EXPECT_LT(e.kinetic, 1e-3 * e.strain) << scheme;
  EXPECT_LT(std::abs(balance), 1e-3 * e.external_work) << scheme;
}

// inputs/stiff_platen.toml: E 100000 against 1000 MPa, frictionless, linear
// shapes, 2 ppc, h = 0.25 mm; the drive's reaction against the series
// stiffness k = 1097.4 N/mm. Pushed 0.003 mm over 0.3 ms (the scene's speed;
// the block's first mode is 0.014 ms). Tolerances: the reaction's mean over
// each 0.05 ms from 0.1 ms within 1 % (measured within 0.1 %); kinetic energy
// under 1e-3 of the strain energy; the energy balance within 1e-3 of the work.
TEST(ValidationContact, StiffPlatenUnderPureFlipReadsTheSeriesStiffness) {
  expect_stiff_platen_reads_the_series_stiffness("MUSL");
}

// The same pair joined by a bilinear interface: perfect in compression (a
// one-sided normal, which pass B holds as it holds contact), Dn = 10 MPa/mm
// in tension, a perfect tangential direction (it keeps the block's top from
// spreading, so the exact value is not the uniaxial one). USL has no repeat
// of pass B; MUSL must read what USL reads, to 1 %, as the mean over
// 0.2-0.3 ms. Before: MUSL read 0.17-2.04 of the uniaxial stiffness over 1 ms.
TEST(ValidationContact, StiffPlatenOnAOneSidedInterfaceReadsAsUsl) {
  double ratio[2] = {0, 0};
  const char* schemes[2] = {"MUSL", "USL"};
  for (int s = 0; s < 2; ++s) {
    auto sim = stiff_platen_for_0_3ms(
        {std::string("simulation.scheme=\"") + schemes[s] + "\"",
         "interaction[0].law=\"interface\"", "interaction[0].traction_law=\"bilinear\"",
         "interaction[0].Dn=10.0", "interaction[0].Dt=\"perfect\"",
         "interaction[0].normal=\"specified\"", "interaction[0].normal_vector=[0.0, 1.0]"});
    ratio[s] =
        reaction_over_exact(*sim, "plane_y=4.5", {0.2, 0.3}, stiff_platen_stiffness(), 0.01)[0];
    const Energies e = sim->energies();
    note("stiff platen, one-sided interface, %s: F / uniaxial %.4f, kinetic / strain %.3g",
         schemes[s], ratio[s], e.kinetic / e.strain);
    EXPECT_LT(e.kinetic, 1e-3 * e.strain) << schemes[s];
  }
  EXPECT_NEAR(ratio[0] / ratio[1], 1.0, 0.01);
}

// §13 The same platen under USF (docs/contact_validation.md §13). USF's
// strain reads the velocities of pass A, which decided contact on the
// extrapolated momenta, on approach alone: at the pressed face those carry
// FLIP's noise of either sign, so the strain saw partings the bodies never
// made. The run gained energy until it failed: over these windows the drive
// read 2.74 / 2.04 / 2.21 / 2.69 of exact, kinetic / strain 0.15, and the
// balance was +0.47 of the work. Pass A now holds the pairs the last step's
// pass B held (kHeldInPassB) and sticks the Coulomb pairs it held stuck
// (kStuckInPassB). Tolerances as the MUSL test above; Coulomb (mu = 0.3
// holds the top face from spreading, no closed form) against USL, 1 %: it
// read 1.003-1.010 of the stiffness USL reads (1.050) with the hold alone.
TEST(ValidationContact, StiffPlatenUnderUsfReadsTheSeriesStiffness) {
  expect_stiff_platen_reads_the_series_stiffness("USF");

  double coulomb[2] = {0, 0};
  const char* schemes[2] = {"USF", "USL"};
  for (int s = 0; s < 2; ++s) {
    auto run =
        stiff_platen_for_0_3ms({std::string("simulation.scheme=\"") + schemes[s] + "\"",
                                "interaction[0].law=\"friction\"", "interaction[0].friction=0.3"});
    coulomb[s] =
        reaction_over_exact(*run, "plane_y=4.5", {0.2, 0.3}, stiff_platen_stiffness(), 0.01)[0];
  }
  note("stiff platen, Coulomb mu 0.3: F / uniaxial USF %.4f, USL %.4f", coulomb[0], coulomb[1]);
  EXPECT_NEAR(coulomb[0] / coulomb[1], 1.0, 0.01);
}

// §14 The stiff platen with quadratic B-splines: the reaction's mean over
// 0.1-0.3 ms against the series stiffness, minus 1, at h = 0.25 mm (L/h = 16)
// and 0.125 mm (32), with the interaction's normal given by `normal`.
std::array<double, 2> stiff_platen_excess_with_bspline2(const std::vector<std::string>& normal) {
  std::array<double, 2> excess{};
  const char* cells[2][2] = {{"grid.cell=[0.25, 0.25]", "grid.cells=[28, 28]"},
                             {"grid.cell=[0.125, 0.125]", "grid.cells=[56, 56]"}};
  for (int r = 0; r < 2; ++r) {
    std::vector<std::string> overrides = {"grid.shape=\"bspline2\"", cells[r][0], cells[r][1]};
    overrides.insert(overrides.end(), normal.begin(), normal.end());
    auto sim = stiff_platen_for_0_3ms(overrides);
    excess[r] =
        reaction_over_exact(*sim, "plane_y=4.5", {0.1, 0.3}, stiff_platen_stiffness(), 0.01)[0] -
        1.0;
  }
  return excess;
}

// With the specified normal (0, 1) the splines' excess is the width of their
// contact layer (three node rows hold both materials): it halves with h.
// Measured +2.12 % and +1.10 % (+0.58 % at h = 0.0625, 0.05 ms means). The
// tolerances: the fine excess 0.4-0.65 of the coarse one (first order), and
// under 1.5 %. 14 s.
TEST(ValidationContact, StiffPlatenWithSplinesConvergesUnderTheSpecifiedNormal) {
  const std::array<double, 2> e = stiff_platen_excess_with_bspline2(
      {"interaction[0].normal=\"specified\"", "interaction[0].normal_vector=[0.0, 1.0]"});
  note("stiff platen, bspline2, specified normal: F / k - 1 = %.4f at h = 0.25, %.4f at 0.125",
       e[0], e[1]);
  EXPECT_GT(e[1], 0.4 * e[0]);
  EXPECT_LT(e[1], 0.65 * e[0]);
  EXPECT_LT(std::abs(e[1]), 0.015);
}

// The same under the default mass-gradient normal. The block's free top
// corner tilts it (n = (0.705, 0.710) and (0.996, 0.085) on the nodes there),
// so the platen's push holds the corner from spreading: a point restraint
// whose effect barely shrinks with h (+3.4 % and +3.3 %; +2.7 % at
// h = 0.0625). Same tolerances as the specified normal's test.
TEST(ValidationContact, StiffPlatenWithSplinesConvergesUnderTheMassGradientNormal) {
  MMPM_KNOWN_LIMITATION(
      "with bspline2 the MVG normal tilts at the block's free corner and restrains it: "
      "+3.4 % and +3.3 % at h = 0.25 and 0.125 mm, where the specified normal halves "
      "(docs/contact_validation.md §14)");
  const std::array<double, 2> e = stiff_platen_excess_with_bspline2({});
  note("stiff platen, bspline2, MVG normal: F / k - 1 = %.4f at h = 0.25, %.4f at 0.125", e[0],
       e[1]);
  EXPECT_GT(e[1], 0.4 * e[0]);
  EXPECT_LT(e[1], 0.65 * e[0]);
  EXPECT_LT(std::abs(e[1]), 0.015);
}

// reaction_over_exact's means over 0.1-0.2, 0.2-0.9 and 0.9-1.0 ms of a platen
// drive: the first and last within 0.5 % of k and within 0.3 % of each other.
void expect_stiffness_held_over_travel(const std::vector<double>& ratio, const char* label) {
  note("stiff platen, %s: F / k over 0.1-0.2 ms %.4f, 0.9-1.0 ms %.4f", label, ratio[0], ratio[2]);
  EXPECT_NEAR(ratio[0], 1.0, 0.005) << label;
  EXPECT_NEAR(ratio[2], 1.0, 0.005) << label;
  EXPECT_NEAR(ratio[2], ratio[0], 0.003) << label;
}

// The stiff platen with `shape` at cell h (0.25 or 0.125) over the whole 1 ms
// drive: reaction_over_exact's means over 0.1-0.2, 0.2-0.9 and 0.9-1.0 ms.
std::vector<double> stiff_platen_over_1ms(const char* shape, double h,
                                          const std::vector<std::string>& extra = {}) {
  std::vector<std::string> overrides{std::string("grid.shape=\"") + shape + "\""};
  if (h < 0.2)
    overrides.insert(overrides.end(), {"grid.cell=[0.125, 0.125]", "grid.cells=[56, 56]"});
  overrides.insert(overrides.end(), extra.begin(), extra.end());
  auto sim = make_simulation(parse_scene_file(input("stiff_platen.toml"), overrides));
  return reaction_over_exact(*sim, "plane_y=4.5", {0.1, 0.2, 0.9, 1.0}, stiff_platen_stiffness(),
                             0.01);
}

void stiff_platen_with_ugimp_over_1ms(double h) {
  expect_stiffness_held_over_travel(stiff_platen_over_1ms("gimp", h),
                                    h < 0.2 ? "uGIMP, h = 0.125" : "uGIMP, h = 0.25");
}

// §16-17 The stiff platen under a law that ties the faces (stick, Coulomb)
// at cell h: uGIMP's means over 0.1-0.2 and 0.9-1.0 ms within 0.2 % of each
// other and each within 0.5 % of the linear stencil's. There is no closed
// form (the stuck top face makes the block about 5 % stiffer than
// uniaxial); linear shapes never put a sliver on the row below the face (a
// particle reaches only the nodes of its own cell), so they are the
// reference free of the drift.
void expect_tied_platen_held_over_travel(double h, const std::vector<std::string>& law,
                                         const char* label) {
  const std::vector<double> ugimp = stiff_platen_over_1ms("gimp", h, law);
  const std::vector<double> linear = stiff_platen_over_1ms("linear", h, law);
  note(
      "stiff platen under %s, h = %.3f: F / k over 0.1-0.2 ms %.4f (linear %.4f), 0.9-1.0 ms "
      "%.4f (linear %.4f)",
      label, h, ugimp[0], linear[0], ugimp[2], linear[2]);
  EXPECT_NEAR(ugimp[2], ugimp[0], 0.002) << label << ", h " << h;
  EXPECT_NEAR(ugimp[0], linear[0], 0.005 * linear[0]) << label << ", h " << h;
  EXPECT_NEAR(ugimp[2], linear[2], 0.005 * linear[2]) << label << ", h " << h;
}

const std::vector<std::string> kStickLaw{"interaction[0].law=\"stick\""};
const std::vector<std::string> kCoulombLaw{"interaction[0].law=\"friction\"",
                                           "interaction[0].friction=0.3"};

// §14-15 uGIMP pressed contact over the scene's whole 1 ms drive (0.01 mm,
// 4 % of a cell at h = 0.25, 8 % at 0.125). The platen's particle domains,
// flush with the face on a grid line, reach the node row below as soon as
// they move; that row turned multimaterial with a sliver of platen and the
// reaction rose with the travel: 1.000 -> 1.009 at h = 0.25 and 1.001 ->
// 1.017 at h = 0.125 (0.1 ms means). A contact partner under
// kContactPresentFraction of a cell is now absent at the node. Measured
// 2026-12-05 (0.1 ms means at 0.1-0.2 / 0.9-1.0 ms): 0.9991 / 0.9979 and
// 0.9995 / 0.9982 (h = 0.125: the long twin below). Tolerances: each mean
// within 0.5 % of k, and the last within 0.3 % of the first (before: 0.9 %
// and 1.6 %).
TEST(ValidationContact, StiffPlatenWithUgimpHoldsItsStiffnessAsTheFacesTravel) {
  stiff_platen_with_ugimp_over_1ms(0.25);
}

// §16 uGIMP pressed contact under stick over the 1 ms drive, h = 0.25. With
// no presence test under stick the reaction rose with the travel (0.2 ms
// means 1.0514 -> 1.0553, §15; 0.1 ms means 1.0509 -> 1.0567, which the
// tolerances below fail); with every sliver absent the held corner
// rang (below); with only a sliver thin along the normal facing a present
// partner absent, measured 2026-12-05 (0.1 ms means over 0.1-0.2 / 0.9-1.0
// ms): 1.0497 / 1.0495, linear 1.0501 / 1.0490.
TEST(ValidationContact, StiffPlatenUnderStickWithUgimpHoldsItsStiffnessAsTheFacesTravel) {
  expect_tied_platen_held_over_travel(0.25, kStickLaw, "stick");
}

// §17 The same under Coulomb (mu = 0.3), which now takes stick's presence
// test. Without a test the reaction rose with the travel (0.2 ms means
// 1.0498 -> 1.0535, §15); with it, before MUSL's strain pass stuck the pairs
// pass B held stuck, the face slid at h = 0.125 (the long twin). Measured
// 2026-12-05 (0.1 ms means over 0.1-0.2 / 0.9-1.0 ms): 1.0483 / 1.0482,
// linear 1.0490 / 1.0484.
TEST(ValidationContact, StiffPlatenUnderCoulombWithUgimpHoldsItsStiffnessAsTheFacesTravel) {
  expect_tied_platen_held_over_travel(0.25, kCoulombLaw, "Coulomb");
}

// The stiff platen (h = 0.25) under `law`, held after its 1 ms drive to
// 3 ms: the loudest kinetic / strain ratio over 2-3 ms, step by step, the
// energy balance over the work at 3 ms, and the mean reaction over 2-3 ms
// over k times the drive's 0.01 mm.
struct HeldPlaten {
  double loudest = 0, balance = 0, reaction = 0;
};
HeldPlaten held_platen(const std::vector<std::string>& law, const char* label,
                       const char* shape = "gimp") {
  std::vector<std::string> overrides{std::string("grid.shape=\"") + shape + "\"",
                                     "simulation.end_time=3.0"};
  overrides.insert(overrides.end(), law.begin(), law.end());
  auto sim = make_simulation(parse_scene_file(input("stiff_platen.toml"), overrides));
  testing::run_until(*sim, 2.0);
  HeldPlaten out;
  long steps = 0;
  while (sim->time() < 3.0 - 1e-9 * sim->dt()) {
    sim->step();
    const Energies e = sim->energies();
    out.loudest = std::max(out.loudest, e.kinetic / e.strain);
    out.reaction += std::abs(reaction_force(*sim, "plane_y=4.5", 1));
    ++steps;
  }
  out.reaction /= stiff_platen_stiffness() * 0.01 * double(steps);
  const Energies e = sim->energies();
  out.balance = energy_balance(e) / e.external_work;
  note(
      "%s platen (%s) held to 3 ms: kinetic / strain up to %.3g over 2-3 ms, balance %.3g of W, "
      "F / (k 0.01 mm) %.4f",
      label, shape, out.loudest, out.balance, out.reaction);
  return out;
}

// §15-17: a Coulomb platen (mu = 0.3, uGIMP, h = 0.25) held after its 1 ms
// drive. With every sliver absent its free corner rang and the top face
// slid off: kinetic / strain 6.0e-3 over 2-4 ms and 9.1e-3 over 4-6 ms,
// +9.9 % of the work by 20 ms (mmpm run, series rows). With no presence
// test: kinetic / strain 3.4-12e-5, balance -1.8e-3 of the work at 20 ms.
// With stick's test (a sliver thin along the normal facing a present
// partner) and the strain pass sticking the pairs pass B held stuck,
// measured 2026-12-05: 1.7e-4 over 2-3 ms, -1.1e-3 of W. Tolerances: kinetic under 1e-3 of the
// strain energy over 2-3 ms, step by step; the balance within 2e-3 of the
// work at 3 ms.
TEST(ValidationContact, StiffPlatenUnderCoulombStaysQuietWhenHeld) {
  const HeldPlaten held = held_platen(kCoulombLaw, "Coulomb");
  EXPECT_LT(held.loudest, 1e-3);
  EXPECT_LT(std::abs(held.balance), 2e-3);
}

// §16: stick's presence test keeps a sliver beside the block's free edge
// tied to the platen. With every sliver absent, the held stick platen's
// corner rang: kinetic / strain 1.2-1.3e-3 over 2-20 ms (series rows),
// against 5.6-6.4e-5 without the rule. Measured 2026-12-05: 6.5e-5 over
// 2-3 ms, -5.6e-4 of W.
// Tolerances: kinetic under 3e-4 of the strain energy over 2-3 ms, step by
// step; the balance within 1e-3 of the work at 3 ms.
TEST(ValidationContact, StiffPlatenUnderStickStaysQuietWhenHeld) {
  const HeldPlaten held = held_platen(kStickLaw, "stick");
  EXPECT_LT(held.loudest, 3e-4);
  EXPECT_LT(std::abs(held.balance), 1e-3);
}

// §17 MUSL's strain pass and Coulomb at rest: the linear stiff platen
// (h = 0.25, mu = 0.3) with 1 % PIC (flip = 0.99), held after its drive.
// The strain pass repeats pass B on re-extrapolated momenta, whose relative
// normal velocity at a pressed face is noise of either sign; deciding
// Coulomb's cone on them left the strain free to slide where pass B had
// stuck the face. Once the PIC share had damped the motion (kinetic /
// strain 1e-8) the face slid within 0.05 ms of the drive's stop: the
// reaction swung 0.85-1.19 of k times 0.01 mm over 1.1-3 ms, kinetic /
// strain up to 1e-3, 4.0 % of the work lost (with mu = 1 too). Now a pair
// pass B held stuck sticks in the strain pass. Measured 2026-12-05:
// kinetic / strain 1.7e-8, balance -9.4e-4 of W, reaction 1.0484 against
// stick's 1.0489 (before: 1.0e-3, -4.1e-2, 1.0154). Tolerances: kinetic under 1e-5 of the strain
// energy over 2-3 ms, step by step; the balance within 2e-3 of the work at 3 ms; the mean reaction
// over 2-3 ms within 0.3 % of stick's in the same hold (a slip zone at the corner makes Coulomb's a
// little lower).
TEST(ValidationContact, StiffPlatenUnderCoulombWithPicStaysStuckWhenHeld) {
  const std::vector<std::string> pic{"simulation.flip=0.99"};
  std::vector<std::string> coulomb = kCoulombLaw, stick = kStickLaw;
  coulomb.insert(coulomb.end(), pic.begin(), pic.end());
  stick.insert(stick.end(), pic.begin(), pic.end());
  const HeldPlaten c = held_platen(coulomb, "Coulomb, flip 0.99", "linear");
  const HeldPlaten s = held_platen(stick, "stick, flip 0.99", "linear");
  EXPECT_LT(c.loudest, 1e-5);
  EXPECT_LT(std::abs(c.balance), 2e-3);
  EXPECT_NEAR(c.reaction, s.reaction, 0.003 * s.reaction);
}

// USF's carried record (the last pass B's held and stuck pairs) is state
// between steps, so it is in the checkpoint: a run restored part-way
// continues as the uninterrupted one, bit for bit. Restored without it (a
// checkpoint from before 2026-12-05) the first pass A decides on approach
// alone and the run differs, which shows the record is read.
TEST(Restart, UsfContactRecordIsInTheCheckpoint) {
  const std::vector<std::string> usf = {"simulation.scheme=\"USF\"",
                                        "interaction[0].law=\"friction\"",
                                        "interaction[0].friction=0.3"};
  auto reference = stiff_platen_for_0_3ms(usf);
  for (int k = 0; k < 400; ++k) reference->step();
  const std::vector<io::Blob> state = reference->save_state();
  ASSERT_TRUE(std::any_of(state.begin(), state.end(),
                          [](const io::Blob& b) { return b.name == "mm.held_flags"; }));
  for (int k = 0; k < 200; ++k) reference->step();

  auto resume = [&](bool with_record) {
    std::vector<io::Blob> blobs;
    for (const io::Blob& b : state)
      if (with_record || b.name.rfind("mm.", 0) != 0) blobs.push_back(b);
    auto sim = stiff_platen_for_0_3ms(usf);
    sim->load_state(blobs);
    for (int k = 0; k < 200; ++k) sim->step();
    return sim;
  };
  for (const char* f : {"position", "velocity", "stress"}) {
    EXPECT_EQ(resume(true)->particle_field(f).values, reference->particle_field(f).values) << f;
    EXPECT_NE(resume(false)->particle_field(f).values, reference->particle_field(f).values) << f;
  }
}

// inputs/platen.toml with the block seeded 1 particle per cell (the platen
// keeps 2), MUSL, pure FLIP: the rigid platen's reaction, its means over
// 0.4-0.5, 0.5-0.9 and 0.9-1 ms, against E' A d / L, 1 %.
TEST(ValidationContact, RigidPlatenOnOneParticlePerCellUnderPureFlip) {
  const double k = 1000.0 / (1.0 - 0.3 * 0.3);
  for (const char* shape : {"linear", "gimp"}) {
    auto sim = make_simulation(parse_scene_file(
        input("platen.toml"),
        {std::string("grid.shape=\"") + shape + "\"", "body[0].particles_per_cell=1"}));
    const std::vector<double> ratio =
        reaction_over_exact(*sim, "rigid:platen", {0.4, 0.5, 0.9, 1.0}, k, 0.01);
    note("platen, 1 ppc, %s: F / exact %.4f over 0.4-0.5 ms, %.4f over 0.9-1 ms", shape, ratio[0],
         ratio[2]);
    for (double r : ratio) EXPECT_NEAR(r, 1.0, 0.01) << shape;
  }
}

// ---------------------------------------------------------------------------
// Refinement (ctest -L long)
// ---------------------------------------------------------------------------

// Velocity exchange at h = 0.25 and 0.125 mm (4 and 8 particles per mm),
// same geometry, frictionless: within 5 % like the CI run, and momentum to
// round-off (1e-12). Runs ~1 min.
TEST(ValidationContactLong, HeadOnImpactRefined) {
  MMPM_LONG_TEST();
  MMPM_KNOWN_LIMITATION(
      "at h = 0.25 mm the energy after separation is +17.4 % of K0 (exchange "
      "error 4.7 %); h = 0.125 mm: +1.8 % (0.99 %). Measured 2026-11-23, the "
      "same at commit 243b899; cause not isolated");
  for (double h : {0.25, 0.125}) {
    const int nx = int(std::lround(25.0 / h)), ny = int(std::lround(8.0 / h));
    const CollisionRun r =
        run_collision({law_override("frictionless"), "grid.cell=[" + num(h) + "," + num(h) + "]",
                       "grid.cells=[" + std::to_string(nx) + "," + std::to_string(ny) + "]"},
                      0.25);
    ASSERT_LT(r.velocity_change, 1e-6) << "h " << h;
    note("h %.3f: vA %.4f vB %.4f, exchange error %.4f, (K+U)/K0 %.4f, momentum %.3e", h, r.vA,
         r.vB, exchange_error(r), r.total_end / r.kinetic0, r.max_momentum_error);
    EXPECT_LT(exchange_error(r), 0.05) << "h " << h << ": vA " << r.vA << ", vB " << r.vB;
    EXPECT_NEAR(r.total_end / r.kinetic0, 1.0, 0.05) << "h " << h;
    EXPECT_LT(r.max_momentum_error, 1e-12) << "h " << h;
  }
}

// The same at h = 0.125, twice the travel in cells (8 %): before
// the presence rule 1.001 -> 1.017; measured 0.9995 / 0.9982 (2026-12-05).
TEST(ValidationContactLong, StiffPlatenWithUgimpHoldsItsStiffnessRefined) {
  MMPM_LONG_TEST();
  stiff_platen_with_ugimp_over_1ms(0.125);
}

// The stick platen at h = 0.125 (70 s): before, 0.1 ms means 1.0504 ->
// 1.0589; measured 2026-12-05: 1.0493 / 1.0496, linear 1.0496 / 1.0485.
TEST(ValidationContactLong, StiffPlatenUnderStickWithUgimpHoldsItsStiffnessRefined) {
  MMPM_LONG_TEST();
  expect_tied_platen_held_over_travel(0.125, kStickLaw, "stick");
}

// The Coulomb platen at h = 0.125: with stick's presence test and the
// strain pass deciding Coulomb on its own momenta, the face slid off at
// 0.12 ms (0.2 ms means 1.0115 / 1.0055 / 1.0075 / 1.0076, kinetic / strain
// 1.3e-2); without a test 1.0501 -> 1.0558. Measured 2026-12-05:
// 1.0487 / 1.0485, linear 1.0490 / 1.0483 (39 s).
TEST(ValidationContactLong, StiffPlatenUnderCoulombWithUgimpHoldsItsStiffnessRefined) {
  MMPM_LONG_TEST();
  expect_tied_platen_held_over_travel(0.125, kCoulombLaw, "Coulomb");
}

// The same in 3D (inputs/stiff_platen_3d.toml): a quarter model (symmetry
// planes x = 0 and y = 0, free sides at x = y = 2), block 2 x 2 x 4 mm, platen
// 3 x 3 x 0.5 mm, uGIMP, h = 0.25, 2 ppc, the top nodes driven 0.01 mm over
// 1 ms. k = E A / L in series with the platen (A = 4 mm^2): 998.75 N/mm.
// Before the presence rule the 0.1 ms means rose 1.0005 -> 1.0063 (series
// rows, every 7 steps); measured with it 2026-12-05 (step means): 0.9995 /
// 0.9986. Same tolerances as 2D. 80000 steps, about 100 s on 2 threads.
TEST(ValidationContactLong, StiffPlatenWithUgimpHoldsItsStiffness3D) {
  MMPM_LONG_TEST();
  auto sim = make_simulation(parse_scene_file(input("stiff_platen_3d.toml")));
  const double k = 1.0 / (4.0 / (1000.0 * 4.0) + 0.5 / (1.0e5 * 4.0));
  const std::vector<double> ratio =
      reaction_over_exact(*sim, "plane_z=4.5", {0.1, 0.2, 0.9, 1.0}, k, 0.01, 2);
  expect_stiffness_held_over_travel(ratio, "3D, uGIMP, h = 0.25");
}

// Disk at h = 0.25 and 0.125 mm (12 and 24 cells per radius): rolling a
// within 10 % and the rolling constraint within 5 %; sliding a within 5 % and
// its spin-up within 10 %. Runs 6 s (h = 0.125 mm: 7000 disk particles).
TEST(ValidationContactLong, DiskOnInclineRefined) {
  MMPM_LONG_TEST();
  MMPM_KNOWN_LIMITATION(
      "the sliding disk's spin-up (as DiskSlidesWhenFrictionIsLow): 50 % of "
      "the exact value at h = 0.25 mm, 66 % at 0.125; at h = 0.25 mm the rolling "
      "disk's a is 0.906 of (2/3) G sin(theta) and alpha R / a = -1.10. "
      "Measured 2026-12-05, after MUSL's strain pass stuck the Coulomb pairs "
      "pass B held stuck (before: 0.895, -1.14; 2026-11-23: 51 %, 69 %, a "
      "within 10 %, -1.14)");
  for (double h : {0.25, 0.125}) {
    const std::vector<std::string> fine = {"grid.cell=[" + num(h) + "," + num(h) + "]",
                                           "grid.cells=[" +
                                               std::to_string(int(std::lround(16.0 / h))) + "," +
                                               std::to_string(int(std::lround(11.0 / h))) + "]"};
    const InclineRun roll = run_incline("incline_disk.toml", fine);
    const double a_roll = 2.0 / 3.0 * roll.G * std::sin(roll.theta);
    EXPECT_NEAR(roll.accel / a_roll, 1.0, 0.10)
        << "h " << h << ": a = " << roll.accel << ", rolling " << a_roll;
    EXPECT_NEAR(roll.spin_accel * roll.radius / roll.accel, -1.0, 0.05) << "h " << h;
    auto low = fine;
    low.push_back("interaction[0].friction=0.05");
    const InclineRun slide = run_incline("incline_disk.toml", low);
    EXPECT_NEAR(slide.accel / sliding_accel(slide), 1.0, 0.05) << "h " << h;
    const double alpha = -2.0 * slide.mu * slide.G * std::cos(slide.theta) / slide.radius;
    EXPECT_NEAR(slide.spin_accel / alpha, 1.0, 0.10)
        << "h " << h << ": alpha = " << slide.spin_accel << ", exact " << alpha;
  }
}

// Two blocks stuck under shear and pressure do not creep (uGIMP, stick,
// specified normal). shear_blocks.toml (lower E = 2400, nu = 0.33; upper
// E = 1200, nu = 0.2; h = 0.5 mm, the contact on the grid line y = 2) with
// its interface replaced by stick contact, the top loaded by tau = 0.001 and
// -0.01 MPa (pressed shut), damped at 20 /ms. The rows next to the contact
// (y0 = 1.875 and 2.125) then differ by the shear strain's 0.125 tau (1/G1
// + 1/G2) = 3.885e-7 mm. While contact left out fields below 1e-6 of the
// lightest particle, the slivers the pressed upper block put on the node row
// below the contact moved on their own: the slip read 3.910e-7 at 0.5 ms
// and crept to 3.954e-7 at 1.5 ms (4.016e-7 at 3 ms). Now every field the
// grid gives a velocity takes part (MultimaterialStage::setup): 3.8904e-7
// and 3.8928e-7 (docs/contact_validation.md §24). Tolerances: the slip
// within 0.5 % of the shear strain's at 1.5 ms, and its growth from 0.5 to
// 1.5 ms below 0.2 % of it.
TEST(ValidationContact, StuckShearBlocksDoNotCreep) {
  const std::string scene = testing::replace_between(
      mmpm_test::read_text(input("shear_blocks.toml")), "[[interaction]]", "[[boundary]]",
      "[[interaction]]\nmaterials = [\"lower\", \"upper\"]\nlaw = \"stick\"\n"
      "normal = \"specified\"\nnormal_vector = [0.0, 1.0]\n");
  const double tau = 0.001, G1 = 2400 / (2 * 1.33), G2 = 1200 / (2 * 1.2);
  auto sim = testing::make_from_text(
      scene, {"load[0].traction=[" + num(tau) + ",-0.01]", "grid.damping=20.0"});
  // The rows next to the contact.
  const auto slip = [&] {
    return testing::row_mean_displacement(*sim, 2.125, 0) -
           testing::row_mean_displacement(*sim, 1.875, 0);
  };
  testing::run_until(*sim, 0.5);
  const double early = slip();
  testing::run_until(*sim, 1.5);
  const double late = slip(), exact = 0.125 * tau * (1 / G1 + 1 / G2);
  note("[stuck shear] slip %.5g at 0.5 ms, %.5g at 1.5 ms, shear strain's %.5g", early, late,
       exact);
  EXPECT_NEAR(late / exact, 1.0, 0.005);
  EXPECT_LT(std::abs(late - early), 0.002 * exact);
}

}  // namespace
}  // namespace mmpm
