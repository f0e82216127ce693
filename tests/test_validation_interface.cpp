// Imperfect interfaces (Nairn 2013; ALGORITHM §3.2, §4) against exact solutions
// (docs/validation.md §1, §2, §4, §5; tests/analytic.hpp) and against the paper's
// own checks (location independence, stability at the extremes). Results and the
// reasons behind every tolerance: docs/interface_validation.md.
//
// The runs use the shipped scenes (inputs/series_bars.toml, shear_blocks.toml,
// dls.toml, sphere_in_cube.toml, two_layer.toml) with --set-style overrides, so the
// scenes a user runs are the ones validated here. Suite ValidationInterface runs in
// CI (each test a few seconds on 2 cores); ValidationInterfaceLong holds the
// refinement studies (ctest -L long).
//
// A measured quantity worth knowing before reading the tolerances (interface
// validation doc, "stiff-interface bias"): the separation δ = x_b − x_a is the
// difference of the mass-weighted mean displacements of the two materials at a
// node. With uGIMP and 2 particles per cell those means sit 3h/8 on either side of
// the interface, so at equilibrium the nodes see δ = [u] + (3h/8)(ε_a + ε_b) and
// the interface behaves as if its compliance were 1/D − (3h/8)(1/E_a + 1/E_b)
// (normal) or 1/D − (3h/8)(1/G_a + 1/G_b) (tangential). The tests check that
// model explicitly: it is first order in h and vanishes for a perfect interface.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "tests/analytic.hpp"
#include "tests/test_util.hpp"
#include "tests/validation_util.hpp"

namespace mmpm {
namespace {

using testing::Column;
using testing::field;
using testing::run_until;

std::string input_path(const std::string& name) {
  return std::string(MMPM_SOURCE_DIR) + "/inputs/" + name;
}

std::unique_ptr<Simulation> make_scene(const std::string& name,
                                       const std::vector<std::string>& ov) {
  return make_simulation(parse_scene_file(input_path(name), ov));
}

std::string num(double v) {
  std::ostringstream os;
  os.precision(17);
  os << v;
  std::string s = os.str();
  if (s.find_first_of(".eE") == std::string::npos && s != "inf") s += ".0";
  return s;
}

std::string stiffness_value(double D) {
  return std::isinf(D) ? "\"perfect\"" : num(D);
}

// Least-squares line u = a y + b through the points (y, u).
struct Line {
  double slope = 0, intercept = 0;
  double at(double y) const { return slope * y + intercept; }
};
Line fit_line(const std::vector<double>& y, const std::vector<double>& u) {
  double sy = 0, su = 0, syy = 0, syu = 0;
  const double n = double(y.size());
  for (std::size_t k = 0; k < y.size(); ++k) {
    sy += y[k], su += u[k], syy += y[k] * y[k], syu += y[k] * u[k];
  }
  Line l;
  l.slope = (n * syu - sy * su) / (n * syy - sy * sy);
  l.intercept = (su - l.slope * sy) / n;
  return l;
}

// Static particle state of a finished run.
struct State {
  Column pos, disp, mat;
  Energies e;
  double x0(std::size_t p, int d) const { return pos.at(p, d) - disp.at(p, d); }
};
State state_of(const Simulation& sim) {
  return {field(sim, "position"), field(sim, "displacement"), field(sim, "material"),
          sim.energies()};
}

// Line through displacement component `comp` against the initial coordinate y0 of
// the particles of material `m` with lo < y0 < hi (one cell away from interfaces and
// loaded faces, where the discretisation of the load and of the interface bends the
// field; see the interface validation doc).
Line fit_material(const State& s, int m, int comp, double lo, double hi) {
  std::vector<double> y, u;
  for (std::size_t p = 0; p < s.mat.values.size(); ++p) {
    if (int(s.mat.at(p)) != m) continue;
    const double y0 = s.x0(p, 1);
    if (y0 <= lo || y0 >= hi) continue;
    y.push_back(y0);
    u.push_back(s.disp.at(p, comp));
  }
  EXPECT_GT(y.size(), 8u);
  return fit_line(y, u);
}

bool finite(const Energies& e) {
  return std::isfinite(e.kinetic) && std::isfinite(e.strain) && std::isfinite(e.interface);
}

// ---------------------------------------------------------------------------
// (a) Two bars in series, normal interface (docs/validation.md §1)
// ---------------------------------------------------------------------------
// inputs/series_bars.toml: bars A (y 0-5) and B (y 5-10), 2 mm wide (symmetry plane
// at x = 0, free side at x = 2), 1 mm thick, plane stress, both E = 2400, nu = 0.33:
// uniaxial stress with E on both sides (same Poisson contraction, so the interface
// carries no shear and Dt does not matter). Roller base, traction sigma on B's top.
struct BarsResult {
  double compliance = 0;  // (u_top - u_bottom) / P from the bulk fields [mm/N]
  double jump = 0;        // opening at y = 5 from the two bulk fields [mm]
  Energies e;
  double slope_a = 0, slope_b = 0;  // strains of the bulk fields
};

BarsResult run_bars(double Dn, double sigma, double h, double t_end,
                    const std::string& Dt = "\"perfect\"",
                    const std::vector<std::string>& extra = {}) {
  const int nx = int(std::lround(4.0 / h)), ny = int(std::lround(12.0 / h));
  std::vector<std::string> ov = {
      "grid.cell=[" + num(h) + "," + num(h) + "]",
      "grid.cells=[" + std::to_string(nx) + "," + std::to_string(ny) + "]",
      "interaction[0].Dn=" + stiffness_value(Dn),
      "interaction[0].Dt=" + Dt,
      "load[0].traction=[0.0," + num(sigma) + "]",
  };
  ov.insert(ov.end(), extra.begin(), extra.end());
  auto sim = make_scene("series_bars.toml", ov);
  run_until(*sim, t_end);
  const State s = state_of(*sim);
  const Line a = fit_material(s, 0, 1, h, 5.0 - h), b = fit_material(s, 1, 1, 5.0 + h, 10.0 - h);
  BarsResult r;
  r.compliance = (b.at(10.0) - a.at(0.0)) / (sigma * 2.0);
  r.jump = b.at(5.0) - a.at(5.0);
  r.e = s.e;
  r.slope_a = a.slope;
  r.slope_b = b.slope;
  return r;
}

// Resolution h = 0.5 mm (4 x 20 cells per bar), 2x2 particles per cell, uGIMP, MUSL.
// Static by damping (1 ms; kinetic/U < 1e-5 checked). The load keeps the opening
// sigma/Dn <= 1e-3 mm (0.2 % of a cell): the contact area of (P-20) follows the
// particles, so larger openings soften the interface by about opening/cell.
// Tolerances: compliance 1.5 %; opening vs the discrete model
// sigma/Dn - (3h/8)(2 sigma/E) within 1 % of sigma/Dn; interface energy vs
// P^2/(2 Dn A) within 0.5 %.
TEST(ValidationInterface, SeriesBarsNormalCompliance) {
  const double E = 2400, A = 2.0, h = 0.5;
  for (double Dn : {analytic::kInf, 100.0, 10.0, 1.0}) {
    const double sigma = std::isinf(Dn) ? 0.01 : std::min(0.01, 1e-3 * Dn);
    const BarsResult r = run_bars(Dn, sigma, h, 1.0);
    const auto ex = analytic::series_bars(E, 5.0, E, 5.0, Dn, A, sigma * A);
    SCOPED_TRACE("Dn = " + num(Dn));
    std::printf(
        "[bars h=0.5] Dn %-8g compliance %+.3f %%  opening %.5g (continuum %.5g)  U_int/exact "
        "%.4f\n",
        Dn, 100 * (r.compliance / ex.compliance - 1), r.jump, ex.jump,
        std::isinf(Dn) ? 0.0 : r.e.interface / ex.U_interface);
    EXPECT_TRUE(finite(r.e));
    EXPECT_LT(r.e.kinetic, 1e-5 * (r.e.strain + r.e.interface)) << "not static";
    EXPECT_NEAR(r.compliance / ex.compliance, 1.0, 0.015)
        << "C = " << r.compliance << " exact " << ex.compliance;
    const double model_jump = ex.jump - 0.375 * h * 2.0 * sigma / E;
    if (!std::isinf(Dn)) {
      EXPECT_NEAR((r.jump - model_jump) / ex.jump, 0.0, 0.01)
          << "opening " << r.jump << ", continuum " << ex.jump << ", discrete model " << model_jump;
      EXPECT_NEAR(r.e.interface / ex.U_interface, 1.0, 0.005)
          << "U_int " << r.e.interface << " exact " << ex.U_interface;
    } else {
      EXPECT_EQ(r.e.interface, 0.0);
      EXPECT_NEAR(r.jump / (sigma * 10.0 / E), 0.0, 0.002) << "a perfect interface opened";
    }
  }
}

// The bilinear law (ALGORITHM §3.2: stiff in compression, soft in tension)
// on the same bars: Dn = 10 when the interface opens, Dn_compression = 100
// when it closes. Pulled (sigma = +0.01 MPa) the bars must read the
// compliance and interface energy of Dn = 10; pushed (sigma = -0.01 MPa)
// those of Dn = 100, with a negative opening. A law that took the sign of
// delta_n from the wrong material, or kept one stiffness, fails one side by
// a factor 7.4 in compliance (the interface term is 96 % of it at Dn = 10,
// 71 % at Dn = 100: C = 0.0521 against 0.0071 mm/N). Tolerances as SeriesBarsNormalCompliance:
// compliance 1.5 %, interface energy 0.5 % (h = 0.5 mm, static at 1 ms).
TEST(ValidationInterface, SeriesBarsBilinearLawTakesTheStiffnessOfTheOpeningsSign) {
  const double E = 2400, A = 2.0, h = 0.5, Dn_open = 10.0, Dn_closed = 100.0;
  const std::vector<std::string> bilinear = {"interaction[0].traction_law=\"bilinear\"",
                                             "interaction[0].Dn_compression=" + num(Dn_closed)};
  for (double sigma : {0.01, -0.01}) {
    const BarsResult r = run_bars(Dn_open, sigma, h, 1.0, "\"perfect\"", bilinear);
    const double Dn = sigma > 0 ? Dn_open : Dn_closed;
    const auto ex = analytic::series_bars(E, 5.0, E, 5.0, Dn, A, sigma * A);
    SCOPED_TRACE("sigma = " + num(sigma));
    std::printf("[bars bilinear] sigma %+g compliance %+.3f %% (vs Dn %g)  U_int/exact %.4f\n",
                sigma, 100 * (r.compliance / ex.compliance - 1), Dn,
                r.e.interface / ex.U_interface);
    EXPECT_TRUE(finite(r.e));
    EXPECT_LT(r.e.kinetic, 1e-5 * (r.e.strain + r.e.interface)) << "not static";
    EXPECT_NEAR(r.compliance / ex.compliance, 1.0, 0.015)
        << "C = " << r.compliance << " exact " << ex.compliance;
    EXPECT_NEAR(r.e.interface / ex.U_interface, 1.0, 0.005)
        << "U_int " << r.e.interface << " exact " << ex.U_interface;
    EXPECT_EQ(r.jump > 0, sigma > 0) << "opening " << r.jump;
  }
}

// The bilinear law's default compression branch is perfect: a one-sided constraint
// (docs/multimaterial.md §4.1). Under a static compressive load it must hold like a
// perfect interface, without creeping shut: stuck while the bars approach, released
// when they do not, it is re-decided in pass B on the updated momenta, and a release
// there would let the gap close by a step's motion every time. Same run as above
// (h 0.5, 1 ms, static by damping): compliance of the bars alone within 1.5 %, no
// interface energy, the bulk fields' jump at the interface below 5 % of the opening
// the tension branch would give.
TEST(ValidationInterface, SeriesBarsBilinearPerfectCompressionHoldsAStaticLoad) {
  const double E = 2400, A = 2.0, h = 0.5, sigma = -0.01;
  const BarsResult r =
      run_bars(10.0, sigma, h, 1.0, "\"perfect\"", {"interaction[0].traction_law=\"bilinear\""});
  const auto ex =
      analytic::series_bars(E, 5.0, E, 5.0, std::numeric_limits<double>::infinity(), A, sigma * A);
  std::printf("[bars bilinear perfect compression] compliance %+.3f %%  jump %.3e  U_int %.3e\n",
              100 * (r.compliance / ex.compliance - 1), r.jump, r.e.interface);
  EXPECT_TRUE(finite(r.e));
  EXPECT_LT(r.e.kinetic, 1e-5 * r.e.strain) << "not static";
  EXPECT_NEAR(r.compliance / ex.compliance, 1.0, 0.015)
      << "C = " << r.compliance << " exact " << ex.compliance;
  EXPECT_EQ(r.e.interface, 0.0);
  // The bulk fields meet at y = 5 (the tension branch would open them by sigma/Dn =
  // 1e-3 mm); a gap creeping shut would show as an overlap.
  EXPECT_LT(std::abs(r.jump), 0.05 * std::abs(sigma) / 10.0) << "opening " << r.jump;
}

// Two free bars (series_bars.toml's, 2 x 5 mm each, E 2400, rho 1.2e-3, with nu 0,
// plane stress) meet at 0.5 mm/ms each. The bilinear law: Dn = 10 MPa/mm in tension, perfect in
// compression. While they touch, the perfect branch must act as contact does; the compression wave
// comes back after 2L/c = 7.07e-3 ms and the bars part, so the frictionless contact run is the
// reference to t = 0.01 ms. Then the tension spring (Dn A = 20 N/mm between two 0.012 g bars, omega
// = 57.7 /ms) takes the relative motion: a quarter period, 0.027 ms, later nearly all of it is
// interface energy. Before the perfect branch was one-sided it held the gap shut while the bars
// pulled apart: K + U_int at 0.01 ms read 1.76e-3 mJ against contact's 2.59e-3 (the rest went into
// the bars' vibration) and the spring's peak 1.54e-3 (0.58 of contact's K). Resolution: h 0.5 mm, 2
// x 2 particles per cell, uGIMP, MUSL, cfl 0.5. Tolerances: K + U_int within 2 % of contact's K at
// 0.01 ms (measured 0.2 %); peak U_int above 0.75 of contact's K (measured 0.92: the rest is the
// bars' vibration), between 0.028 and 0.042 ms (rigid bars: 0.034); K + U + U_int within 5 % of the
// initial 3e-3 mJ.
TEST(ValidationInterface, BilinearPerfectCompressionReleasesABouncingPair) {
  // inputs/series_bars.toml without its supports, load and damping, the bars set moving.
  const std::vector<std::string> free_bars = {"boundary=[]",
                                              "load=[]",
                                              "grid.damping=0.0",
                                              "simulation.flip=1.0",
                                              "material[0].nu=0.0",
                                              "material[1].nu=0.0",
                                              "body[0].velocity=[0.0,0.5]",
                                              "body[1].velocity=[0.0,-0.5]"};
  std::vector<std::string> bilinear = free_bars, frictionless = free_bars;
  bilinear.push_back("interaction[0].traction_law=\"bilinear\"");
  frictionless.push_back(
      "interaction[0]={materials=[\"bar_a\",\"bar_b\"],law=\"frictionless\","
      "normal=\"specified\",normal_vector=[0.0,1.0]}");
  auto bounce = make_scene("series_bars.toml", bilinear);
  auto contact = make_scene("series_bars.toml", frictionless);
  run_until(*bounce, 0.01);
  run_until(*contact, 0.01);
  const Energies b = bounce->energies(), c = contact->energies();
  std::printf("[bouncing bars] t 0.01: K + U_int %.4e, contact K %.4e\n", b.kinetic + b.interface,
              c.kinetic);
  EXPECT_NEAR((b.kinetic + b.interface) / c.kinetic, 1.0, 0.02);
  double peak = 0, t_peak = 0;
  while (bounce->time() < 0.045 - 1e-9) {
    run_until(*bounce, bounce->time() + 5e-4);
    const Energies e = bounce->energies();
    ASSERT_TRUE(finite(e));
    if (e.interface > peak) peak = e.interface, t_peak = bounce->time();
  }
  const Energies e = bounce->energies();
  std::printf("[bouncing bars] peak U_int %.4e at %.4f ms (%.3f of contact's K); total %.4e\n",
              peak, t_peak, peak / c.kinetic, e.kinetic + e.strain + e.interface);
  EXPECT_GT(peak, 0.75 * c.kinetic);
  EXPECT_GT(t_peak, 0.028);
  EXPECT_LT(t_peak, 0.042);
  EXPECT_NEAR((e.kinetic + e.strain + e.interface) / 3e-3, 1.0, 0.05);
}

// The bars turned over: the roller holds B's top (y = 10) and the traction pulls A's
// bottom down, so A moves away from the interface and B stays. The grid gains 3 mm below
// (uGIMP reach of the load face) and above (the roller's nodes).
std::vector<std::string> pulled_from_below(double h, double sigma) {
  return {"grid.origin=[-1.0,-2.0]",
          "grid.cells=[" + std::to_string(std::lround(4.0 / h)) + "," +
              std::to_string(std::lround(15.0 / h)) + "]",
          "boundary[0].where={ min = [-1.0, 10.0], max = [3.0, 13.0] }",
          "boundary[1].where={ min = [-1.0, -2.0], max = [0.0, 13.0] }",
          "load[0].where={ body = \"bottom\", face = \"y_min\" }",
          "load[0].traction=[0.0," + num(-sigma) + "]"};
}

// area = "closed" (docs/multimaterial.md §7.1; docs/interface_validation.md Finding 10). The
// paper's (P-20) area on the current domains loses 1.5 δ_n/h of itself as the interface
// opens, so at a fixed opening refinement moves away from the exact answer. With the
// opening closed first it must converge whichever bar moves: pulled at B's top (A stays)
// and turned over (pulled at A's bottom, B stays), and with the exact integration, whose
// per-node pass is the other code path. Dn = 10, σ = 0.05 MPa: opening 5e-3 mm,
// 1 % of a cell at h = 0.5, 2 % at h = 0.25. Static at 1 ms. Tolerances: U_int within 0.3 %
// of P²/(2 Dn A) (measured ≤ 0.06 %), compliance 1.5 %. The paper's area on the same bars
// must show the defect, U_int more than 2.5 % high at h = 0.25 (3.2 % measured) and more
// than at h = 0.5 (1.6 %): a "closed" that fell back to the paper's area fails.
TEST(ValidationInterface, SeriesBarsClosedAreaConvergesAtAFixedOpening) {
  const double E = 2400, A = 2.0, Dn = 10.0, sigma = 0.05;
  const auto ex = analytic::series_bars(E, 5.0, E, 5.0, Dn, A, sigma * A);
  const std::vector<std::string> closed = {"interaction[0].area=\"closed\""};
  for (bool from_below : {false, true}) {
    for (double h : {0.5, 0.25}) {
      std::vector<std::string> extra = closed;
      if (from_below) {
        const auto flip = pulled_from_below(h, sigma);
        extra.insert(extra.end(), flip.begin(), flip.end());
      }
      const BarsResult r = run_bars(Dn, sigma, h, 1.0, "\"perfect\"", extra);
      SCOPED_TRACE(std::string(from_below ? "pulled at A's bottom" : "pulled at B's top") +
                   ", h = " + num(h));
      std::printf(
          "[bars closed area] %s h %-5g compliance %+.3f %%  opening %.5g  U_int/exact %.5f\n",
          from_below ? "A pulled" : "B pulled", h, 100 * (r.compliance / ex.compliance - 1), r.jump,
          r.e.interface / ex.U_interface);
      EXPECT_TRUE(finite(r.e));
      EXPECT_GT(r.jump, 0.8 * ex.jump) << "the interface did not open";
      EXPECT_LT(r.e.kinetic, 1e-5 * (r.e.strain + r.e.interface)) << "not static";
      EXPECT_NEAR(r.compliance / ex.compliance, 1.0, 0.015);
      EXPECT_NEAR(r.e.interface / ex.U_interface, 1.0, 0.003);
    }
  }
  // The per-node pass (exact integration, ALGORITHM §4.5) closes the same way as the batch.
  std::vector<std::string> exact = closed;
  exact.push_back("interaction[0].integration=\"exact\"");
  const BarsResult e = run_bars(Dn, sigma, 0.25, 1.0, "\"perfect\"", exact);
  std::printf("[bars closed area] exact integration h 0.25  U_int/exact %.5f\n",
              e.e.interface / ex.U_interface);
  EXPECT_NEAR(e.e.interface / ex.U_interface, 1.0, 0.003);
  const double paper_coarse = run_bars(Dn, sigma, 0.5, 1.0).e.interface / ex.U_interface;
  const double paper_fine = run_bars(Dn, sigma, 0.25, 1.0).e.interface / ex.U_interface;
  std::printf("[bars paper area] U_int/exact %.5f (h 0.5), %.5f (h 0.25)\n", paper_coarse,
              paper_fine);
  EXPECT_GT(paper_fine, 1.025);
  EXPECT_GT(paper_fine - 1, paper_coarse - 1);
}

// Dt does not enter (same Poisson contraction on both sides): Dt = Dn gives the same
// compliance as Dt = perfect within 0.1 %. h = 0.5 mm, Dn = 10 MPa/mm.
TEST(ValidationInterface, SeriesBarsTangentialStiffnessDoesNotMatter) {
  const BarsResult perfect_t = run_bars(10.0, 0.01, 0.5, 1.0, "\"perfect\"");
  const BarsResult equal_t = run_bars(10.0, 0.01, 0.5, 1.0, "10.0");
  EXPECT_NEAR(equal_t.compliance / perfect_t.compliance, 1.0, 0.001);
  EXPECT_NEAR(equal_t.e.interface / perfect_t.e.interface, 1.0, 0.001);
}

// Float against double at h = 0.25 mm (16 x 48 cells, 11 300 steps of
// 8.8e-5 ms to t = 1 ms), Dn = 10. Near equilibrium a step moves a
// particle by less than half an ulp of its float position (9.5e-7 mm at
// y = 10), so plain float sums stop short of the static state. Float
// positions now keep their rounding error (kernels/position_sum.hpp,
// [simulation] compensated_positions, default true): the float run's
// compliance and opening must match the double run's within 0.1 % (what
// is left is float round-off in the stresses, ~1e-7 per operation; measured
// 8e-6) and the exact compliance within the 1.5 % of
// SeriesBarsNormalCompliance. The plain-sum run
// (compensated_positions = false) is the failure this guards against: its
// compliance is off the double run's by more than 5 % (measured -22.9 %).
TEST(ValidationInterface, SeriesBarsFloatMatchesDouble) {
  const double E = 2400, A = 2.0, h = 0.25, Dn = 10.0, sigma = 0.01;
  const std::string Dt = "\"perfect\"";
  const BarsResult d = run_bars(Dn, sigma, h, 1.0);
  const BarsResult f = run_bars(Dn, sigma, h, 1.0, Dt, {"simulation.precision=\"float\""});
  const BarsResult plain =
      run_bars(Dn, sigma, h, 1.0, Dt,
               {"simulation.precision=\"float\"", "simulation.compensated_positions=false"});
  const auto ex = analytic::series_bars(E, 5.0, E, 5.0, Dn, A, sigma * A);
  std::printf(
      "[bars h=0.25] compliance vs exact: double %+.4f %%, float %+.4f %%, float plain sums "
      "%+.4f %%; opening float/double %.6f\n",
      100 * (d.compliance / ex.compliance - 1), 100 * (f.compliance / ex.compliance - 1),
      100 * (plain.compliance / ex.compliance - 1), f.jump / d.jump);
  EXPECT_TRUE(finite(f.e));
  EXPECT_NEAR(f.compliance / d.compliance, 1.0, 1e-3);
  EXPECT_NEAR(f.jump / d.jump, 1.0, 1e-3);
  EXPECT_NEAR(f.compliance / ex.compliance, 1.0, 0.015);
  EXPECT_GT(std::abs(plain.compliance / d.compliance - 1.0), 0.05);
}

// The same bars in compressible neo-Hookean (plane strain, perfect
// interface, h = 0.25 mm, sigma = 0.01 MPa: a strain of 3.7e-6). At this
// strain the neo-Hookean bar is the linear one, so the compliance is
// 2 L (1 - nu^2) / (E A) (uniaxial stress in plane strain, free side),
// within the 1.5 % of SeriesBarsNormalCompliance. Float must match double
// within 0.1 %: the deformation gradient is kept as H = F - I
// (kernels/constitutive.hpp NeoHookeanPoint); as F, float lost the strain
// increments below 6e-8 and the top moved 3.7x too far
// (docs/performance.md "Strains in float").
TEST(ValidationInterface, SeriesBarsNeoHookeanFloatMatchesDouble) {
  const double E = 2400, nu = 0.33, A = 2.0, h = 0.25, sigma = 0.01;
  const std::string Dt = "\"perfect\"";
  const std::vector<std::string> neo = {"simulation.plane=\"strain\"",
                                        "material[0].type=\"neohookean\"",
                                        "material[1].type=\"neohookean\""};
  auto with = [&](const std::string& extra) {
    auto v = neo;
    v.push_back(extra);
    return v;
  };
  const BarsResult d =
      run_bars(analytic::kInf, sigma, h, 1.0, Dt, with("simulation.precision=\"double\""));
  const BarsResult f =
      run_bars(analytic::kInf, sigma, h, 1.0, Dt, with("simulation.precision=\"float\""));
  const double Ep = E / (1 - nu * nu);
  const auto ex = analytic::series_bars(Ep, 5.0, Ep, 5.0, analytic::kInf, A, sigma * A);
  std::printf("[neo-Hookean bars h=0.25] compliance vs exact: double %+.4f %%, float %+.4f %%\n",
              100 * (d.compliance / ex.compliance - 1), 100 * (f.compliance / ex.compliance - 1));
  EXPECT_TRUE(finite(d.e) && finite(f.e));
  EXPECT_LT(d.e.kinetic, 1e-5 * d.e.strain) << "not static";
  EXPECT_NEAR(d.compliance / ex.compliance, 1.0, 0.015);
  EXPECT_NEAR(f.compliance / d.compliance, 1.0, 1e-3);
  EXPECT_NEAR(f.e.strain / d.e.strain, 1.0, 1e-3);
}

// The stiff-interface bias is first order in h: at 1/Dn = 1e-3 mm/MPa the compliance
// error (h = 0.5: -3.1 %) halves with every halving of the cell (ratio 0.40-0.60), and
// the opening follows the discrete model within 2 % of sigma/Dn at every h.
TEST(ValidationInterfaceLong, SeriesBarsStiffInterfaceBiasConvergesFirstOrder) {
  MMPM_LONG_TEST();
  const double E = 2400, A = 2.0, Dn = 1000.0, sigma = 0.01;
  const auto ex = analytic::series_bars(E, 5.0, E, 5.0, Dn, A, sigma * A);
  std::vector<double> err;
  for (double h : {0.5, 0.25, 0.125}) {
    const BarsResult r = run_bars(Dn, sigma, h, 0.8);
    err.push_back(r.compliance / ex.compliance - 1.0);
    const double model_jump = ex.jump - 0.375 * h * 2.0 * sigma / E;
    EXPECT_NEAR((r.jump - model_jump) / ex.jump, 0.0, 0.02) << "h = " << h;
    std::printf("[bars 1/Dn=1e-3] h = %.3f  compliance error %+.3f %%  opening %.4g (model %.4g)\n",
                h, 100 * err.back(), r.jump, model_jump);
  }
  for (std::size_t k = 1; k < err.size(); ++k) {
    EXPECT_LT(err[k], 0.0);
    EXPECT_NEAR(err[k] / err[k - 1], 0.5, 0.1);
  }
}

// ---------------------------------------------------------------------------
// (b) Two blocks in simple shear, tangential interface (docs/validation.md §2)
// ---------------------------------------------------------------------------
// inputs/shear_blocks.toml: block 1 (y 0-2, G1 = 902.26) on a fixed base, block 2
// (y 2-4, G2 = 500), 4 mm wide, side node columns held in y (they carry the
// complementary shear), shear traction tau on the top. Dn perfect.
struct ShearResult {
  double top = 0, jump = 0;
  Energies e;
};

ShearResult run_shear(double Dt, double tau, double t_end,
                      const std::vector<std::string>& extra = {}) {
  std::vector<std::string> ov = {"interaction[0].Dt=" + stiffness_value(Dt),
                                 "load[0].traction=[" + num(tau) + ",0.0]"};
  ov.insert(ov.end(), extra.begin(), extra.end());
  auto sim = make_scene("shear_blocks.toml", ov);
  run_until(*sim, t_end);
  const State s = state_of(*sim);
  const double h = 0.5;
  const Line a = fit_material(s, 0, 0, h, 2.0 - h), b = fit_material(s, 1, 0, 2.0 + h, 4.0 - h);
  return {b.at(4.0), b.at(2.0) - a.at(2.0), s.e};
}

// Resolution h = 0.5 mm (8 x 4 cells per block), 2x2 ppc. tau keeps the slip
// <= 1e-3 mm. Tolerances: top displacement within 1 % of (V 2.2) for 1/Dt >= 0.1 and
// the perfect interface; at 1/Dt = 0.01, where the stiff-interface bias is -3.6 %,
// within 0.5 % of (V 2.2) with 1/Dt replaced by 1/Dt - (3h/8)(1/G1 + 1/G2); slip vs
// that model within 1 % of tau/Dt; interface energy within 0.5 % of tau^2 W t/(2 Dt).
TEST(ValidationInterface, ShearStackTangentialCompliance) {
  const double G1 = analytic::shear_modulus(2400, 0.33), G2 = analytic::shear_modulus(1200, 0.2);
  const double h = 0.5, W = 4.0, bias = 0.375 * h * (1 / G1 + 1 / G2);
  for (double Dt : {analytic::kInf, 100.0, 10.0, 1.0}) {
    const double tau = std::isinf(Dt) ? 1e-3 : std::min(1e-3, 1e-3 * Dt);
    const ShearResult r = run_shear(Dt, tau, 0.8);
    const auto ex = analytic::shear_stack(G1, 2.0, G2, 2.0, Dt, tau);
    SCOPED_TRACE("Dt = " + num(Dt));
    std::printf(
        "[shear h=0.5] Dt %-8g u_top %+.3f %%  slip %.5g (continuum %.5g)  U_int/exact %.4f\n", Dt,
        100 * (r.top / ex.top_displacement - 1), r.jump, ex.jump,
        std::isinf(Dt) ? 0.0 : r.e.interface / (ex.U_interface_per_area * W));
    EXPECT_TRUE(finite(r.e));
    EXPECT_LT(r.e.kinetic, 1e-5 * (r.e.strain + r.e.interface)) << "not static";
    const double model_top = ex.top_displacement - (std::isinf(Dt) ? 0.0 : tau * bias);
    if (std::isinf(Dt) || 1 / Dt >= 0.1) {
      EXPECT_NEAR(r.top / ex.top_displacement, 1.0, 0.01)
          << "u_top " << r.top << " exact " << ex.top_displacement;
    } else {
      EXPECT_NEAR(r.top / model_top, 1.0, 0.005)
          << "u_top " << r.top << " exact " << ex.top_displacement << " with the bias "
          << model_top;
    }
    if (!std::isinf(Dt)) {
      EXPECT_NEAR((r.jump - (ex.jump - tau * bias)) / ex.jump, 0.0, 0.01) << "slip " << r.jump;
      EXPECT_NEAR(r.e.interface / (ex.U_interface_per_area * W), 1.0, 0.005);
    } else {
      EXPECT_EQ(r.e.interface, 0.0);
      EXPECT_NEAR(r.jump / ex.top_displacement, 0.0, 0.002);
    }
  }
}

// separation = "extrapolated" (kernels/separation_extrapolation.hpp) removes the
// stiff-interface bias: each material's displacement is taken at the node, not at
// its particles' centroid 3h/8 away. The bars at h = 0.5 mm and the shear stack
// at h = 0.5 mm, 2x2 ppc, at the stiffnesses where the centroid's bias is
// largest (1/D = 1e-3 and 1e-2): the opening / slip must match the continuum's
// sigma/D within 1 % (the centroid reads 0.847 / 0.985 and 0.429 / 0.943 of
// it; the slip at 1/Dt = 1e-3, 1e-6 mm or 16 % of the top's displacement, within
// 2 %: measured 1.1 %, 0.2 % of the top's), the compliance / top displacement the
// exact one within 0.5 %, the interface energy within 0.5 %. A perfect interface
// is unchanged.
TEST(ValidationInterface, ExtrapolatedSeparationHasNoStiffInterfaceBias) {
  const std::vector<std::string> extrapolated = {"interaction[0].separation=\"extrapolated\""};
  const double E = 2400, A = 2.0, h = 0.5;
  for (double Dn : {analytic::kInf, 1000.0, 100.0}) {
    const double sigma = 0.01;
    const BarsResult r = run_bars(Dn, sigma, h, 1.0, "\"perfect\"", extrapolated);
    const auto ex = analytic::series_bars(E, 5.0, E, 5.0, Dn, A, sigma * A);
    SCOPED_TRACE("bars, Dn = " + num(Dn));
    std::printf(
        "[bars h=0.5 extrapolated] Dn %-8g compliance %+.3f %%  opening / continuum %.4f  "
        "U_int/exact %.4f\n",
        Dn, 100 * (r.compliance / ex.compliance - 1), std::isinf(Dn) ? 0.0 : r.jump / ex.jump,
        std::isinf(Dn) ? 0.0 : r.e.interface / ex.U_interface);
    EXPECT_TRUE(finite(r.e));
    EXPECT_LT(r.e.kinetic, 1e-5 * (r.e.strain + r.e.interface)) << "not static";
    EXPECT_NEAR(r.compliance / ex.compliance, 1.0, 0.005);
    if (!std::isinf(Dn)) {
      EXPECT_NEAR(r.jump / ex.jump, 1.0, 0.01);
      EXPECT_NEAR(r.e.interface / ex.U_interface, 1.0, 0.005);
    }
  }
  const double G1 = analytic::shear_modulus(2400, 0.33), G2 = analytic::shear_modulus(1200, 0.2);
  for (double Dt : {analytic::kInf, 1000.0, 100.0}) {
    const double tau = 1e-3;
    const ShearResult r = run_shear(Dt, tau, 0.8, extrapolated);
    const auto ex = analytic::shear_stack(G1, 2.0, G2, 2.0, Dt, tau);
    SCOPED_TRACE("shear, Dt = " + num(Dt));
    std::printf(
        "[shear h=0.5 extrapolated] Dt %-8g u_top %+.3f %%  slip / continuum %.4f  "
        "U_int/exact %.4f\n",
        Dt, 100 * (r.top / ex.top_displacement - 1), std::isinf(Dt) ? 0.0 : r.jump / ex.jump,
        std::isinf(Dt) ? 0.0 : r.e.interface / (ex.U_interface_per_area * 4.0));
    EXPECT_TRUE(finite(r.e));
    EXPECT_LT(r.e.kinetic, 1e-5 * (r.e.strain + r.e.interface)) << "not static";
    EXPECT_NEAR(r.top / ex.top_displacement, 1.0, 0.005);
    if (!std::isinf(Dt)) {
      EXPECT_NEAR(r.jump / ex.jump, 1.0, Dt > 100 ? 0.02 : 0.01);
      EXPECT_NEAR(r.e.interface / (ex.U_interface_per_area * 4.0), 1.0, 0.005);
    }
  }
  // The paper's centroid at the stiffest case, for contrast (and so that this test
  // would see the option doing nothing).
  const BarsResult bars = run_bars(1000.0, 0.01, h, 1.0);
  const ShearResult shear = run_shear(1000.0, 1e-3, 0.8);
  const double bars_jump = analytic::series_bars(E, 5.0, E, 5.0, 1000.0, A, 0.02).jump;
  const double shear_jump = analytic::shear_stack(G1, 2.0, G2, 2.0, 1000.0, 1e-3).jump;
  std::printf(
      "[centroid h=0.5] D 1000: bars opening / continuum %.4f, shear slip / continuum %.4f\n",
      bars.jump / bars_jump, shear.jump / shear_jump);
  EXPECT_LT(bars.jump / bars_jump, 0.9);
  EXPECT_LT(shear.jump / shear_jump, 0.6);
}

// The same stack in 3D, sheared along d = (2, 1, 0) / sqrt 5 (along no grid
// axis and no diagonal): blocks 4 x 4 x 2 mm (lower, z 0-2, G1 = 902.26;
// upper, z 2-4, G2 = 500), interface z = 2 on a grid plane, base fixed, the
// side node columns held in z (they carry the complementary shear), traction
// tau d on the top, Dn perfect, Dt = 10 (the interface term is 94 % of the
// top displacement). ALGORITHM §3.2 in 3D: one tangential force along the
// tangential opening. The bulk fields' displacement along d must match
// (V 2.2) as in 2D (1 %), their slip tau / Dt as the 2D bias model (1 % of
// tau / Dt), U_int = tau^2 A / (2 Dt) (0.5 %), and the displacement across
// d (its perpendicular in the plane) must stay below 0.5 % of the one along
// it: a tangent taken from one axis, or a force on one component, would turn
// the slip off d. h = 0.5 mm, 2 ppc per direction, uGIMP, static at 0.8 ms.
// `grid` overrides the cells (the normal's cell edge stays 0.5 mm).
void check_shear_stack_3d(const std::vector<std::string>& grid, const char* label) {
  const double G1 = analytic::shear_modulus(2400, 0.33), G2 = analytic::shear_modulus(1200, 0.2);
  const double h = 0.5, Dt = 10.0, tau = 1e-3, bias = 0.375 * h * (1 / G1 + 1 / G2);
  const double d[2] = {2.0 / std::sqrt(5.0), 1.0 / std::sqrt(5.0)};
  const std::string scene = R"(
[simulation]
dimension = 3
end_time  = 0.8
cfl       = 0.5
flip      = 0.99
[grid]
origin  = [-1.0, -1.0, -1.0]
cell    = [0.5, 0.5, 0.5]
cells   = [12, 12, 12]
shape   = "gimp"
damping = 40.0
[[material]]
name    = "lower"
type    = "isotropic"
density = 1.2e-3
E       = 2400.0
nu      = 0.33
[[material]]
name    = "upper"
type    = "isotropic"
density = 1.2e-3
E       = 1200.0
nu      = 0.2
[[body]]
name     = "block1"
material = "lower"
shape    = "box"
min      = [0.0, 0.0, 0.0]
max      = [4.0, 4.0, 2.0]
particles_per_cell = 2
[[body]]
name     = "block2"
material = "upper"
shape    = "box"
min      = [0.0, 0.0, 2.0]
max      = [4.0, 4.0, 4.0]
particles_per_cell = 2
[[interaction]]
materials     = ["lower", "upper"]
law           = "interface"
Dn            = "perfect"
Dt            = 10.0
normal        = "specified"
normal_vector = [0.0, 0.0, 1.0]
separation    = "displacement"
[[boundary]]
where = { min = [-1.0, -1.0, -1.0], max = [5.0, 5.0, 0.0] }
fix   = ["x", "y", "z"]
[[boundary]]
where = { min = [-1.0, -1.0, -1.0], max = [0.0, 5.0, 5.0] }
fix   = ["z"]
[[boundary]]
where = { min = [4.0, -1.0, -1.0], max = [5.0, 5.0, 5.0] }
fix   = ["z"]
[[boundary]]
where = { min = [-1.0, -1.0, -1.0], max = [5.0, 0.0, 5.0] }
fix   = ["z"]
[[boundary]]
where = { min = [-1.0, 4.0, -1.0], max = [5.0, 5.0, 5.0] }
fix   = ["z"]
[[load]]
kind     = "traction"
where    = { body = "block2", face = "z_max" }
traction = [0.0, 0.0, 0.0]
ramp     = 0.05
)";
  std::vector<std::string> overrides = grid;
  overrides.push_back("load[0].traction=[" + num(tau * d[0]) + "," + num(tau * d[1]) + ",0.0]");
  auto sim = testing::make_from_text(scene, overrides);
  run_until(*sim, 0.8);
  const State s = state_of(*sim);
  // Lines through the displacement along d and across it against z0, one
  // cell away from the base, the interface and the top.
  auto fit = [&](int m, double lo, double hi, bool along) {
    std::vector<double> z, u;
    for (std::size_t p = 0; p < s.mat.values.size(); ++p) {
      if (int(s.mat.at(p)) != m) continue;
      const double z0 = s.x0(p, 2);
      if (z0 <= lo || z0 >= hi) continue;
      z.push_back(z0);
      u.push_back(along ? s.disp.at(p, 0) * d[0] + s.disp.at(p, 1) * d[1]
                        : -s.disp.at(p, 0) * d[1] + s.disp.at(p, 1) * d[0]);
    }
    return fit_line(z, u);
  };
  const Line a = fit(0, h, 2.0 - h, true), b = fit(1, 2.0 + h, 4.0 - h, true);
  const Line a_across = fit(0, h, 2.0 - h, false), b_across = fit(1, 2.0 + h, 4.0 - h, false);
  const auto ex = analytic::shear_stack(G1, 2.0, G2, 2.0, Dt, tau);
  const double top = b.at(4.0), slip = b.at(2.0) - a.at(2.0);
  std::printf(
      "[shear 3D %s] Dt %g u_top %+.3f %%  slip %.5g (continuum %.5g, bias model %.5g)  "
      "U_int/exact %.4f  across/along at the top %.2e\n",
      label, Dt, 100 * (top / ex.top_displacement - 1), slip, ex.jump, ex.jump - tau * bias,
      s.e.interface / (ex.U_interface_per_area * 16.0), b_across.at(4.0) / top);
  EXPECT_TRUE(finite(s.e));
  EXPECT_LT(s.e.kinetic, 1e-5 * (s.e.strain + s.e.interface)) << "not static";
  EXPECT_NEAR(top / ex.top_displacement, 1.0, 0.01) << "u_top " << top;
  EXPECT_NEAR((slip - (ex.jump - tau * bias)) / ex.jump, 0.0, 0.01) << "slip " << slip;
  EXPECT_NEAR(s.e.interface / (ex.U_interface_per_area * 16.0), 1.0, 0.005);
  EXPECT_LT(std::abs(b_across.at(4.0)), 0.005 * top) << "the top moved across d";
  EXPECT_LT(std::abs(a_across.at(2.0)), 0.005 * top) << "the lower block moved across d";
}

TEST(ValidationInterface, ShearStack3DSlipsAlongTheTraction) {
  check_shear_stack_3d({}, "h=0.5");
}

// The same with cells 0.5 x 1 x 0.5 mm: the interface plane's two cell
// edges differ, so h_perp of (P-22) in the paper's 3D form, with t along the
// slip d, reads 0.583 instead of dz = 0.5 and the interface area is 14 % too
// small (measured with that form on 0.25 x 0.5 x 0.5 cells, the same ratio:
// u_top +15.1 %, U_int 1.166 x exact). The section form h_perp =
// |diag(dx) n| = dz must give the regular mesh's answers within the same
// tolerances (docs/multimaterial.md §6).
TEST(ValidationInterface, ShearStack3DUnequalCellsInTheInterfacePlane) {
  check_shear_stack_3d({"grid.cell=[0.5,1.0,0.5]", "grid.cells=[12,6,12]"}, "0.5x1x0.5");
}

// ---------------------------------------------------------------------------
// (c) Double lap shear stiffness vs generalized shear lag (docs/validation.md §4)
// ---------------------------------------------------------------------------
struct DlsRun {
  double k = 0, interface_fraction = 0;
  Energies e;
};

DlsRun run_dls(double Dt, double h, double t_end, const std::vector<std::string>& extra = {}) {
  const int nx = int(std::lround(5.0 / h)), ny = int(std::lround(37.0 / h));
  std::vector<std::string> ov = {
      "interaction[0].Dt=" + stiffness_value(Dt), "grid.cell=[" + num(h) + "," + num(h) + "]",
      "grid.cells=[" + std::to_string(nx) + "," + std::to_string(ny) + "]"};
  ov.insert(ov.end(), extra.begin(), extra.end());
  auto sim = make_scene("dls.toml", ov);
  run_until(*sim, t_end);
  DlsRun r;
  r.e = sim->energies();
  const double U = r.e.strain + r.e.interface;
  r.k = analytic::stiffness_from_energy(2.0, U);
  r.interface_fraction = r.e.interface / U;
  return r;
}

// Paper geometry (three 1 mm wood layers, bond 25 mm, P = 2 N on 1 mm depth), grain
// along y, SN normal, Dn perfect, interfaces on grid lines. h = 0.5 mm (2 cells per
// layer thickness), 2x2 ppc, MUSL, 0.25 ms. Measured k: +0.8 % (1/Dt = 0.1),
// +0.3 % (1/Dt = 1). Tolerances: k within 2 % of analytic::dls_stiffness, interface
// share of the energy within 0.01 of the theory's (0.505, 0.909).
TEST(ValidationInterface, DlsStiffnessVsShearLag) {
  for (double inv : {0.1, 1.0}) {
    const DlsRun r = run_dls(1.0 / inv, 0.5, 0.25);
    const auto ex = analytic::DlsShearLag({}, {}, 1.0 / inv).result();
    SCOPED_TRACE("1/Dt = " + num(inv));
    std::printf(
        "[dls h=0.5] 1/Dt %.2f  k %.2f  shear lag %.2f (%+.2f %%)  interface share %.4f (theory "
        "%.4f)\n",
        inv, r.k, ex.k, 100 * (r.k / ex.k - 1), r.interface_fraction, ex.interface_fraction);
    EXPECT_TRUE(finite(r.e));
    EXPECT_NEAR(r.k / ex.k, 1.0, 0.02) << "k = " << r.k << " shear lag " << ex.k;
    EXPECT_NEAR(r.interface_fraction, ex.interface_fraction, 0.01);
  }
}

// ---------------------------------------------------------------------------
// B-splines and the interface area (docs/multimaterial.md §7.2)
// ---------------------------------------------------------------------------
// A B-spline puts a grid-line interface in three rows of nodes. (P-20) gives
// each row a full share: the bars read 0.740 (bspline2) and 0.650 (bspline3) of
// the exact interface energy, the interface 35 % and 54 % too stiff. The
// gradient area, the B-splines' default, reads ∫_Γ S_i dΓ per node. Bars at
// h = 0.5 mm, Dn = 10 (the interface is 96 % of the compliance), static at
// 1 ms; tolerances of SeriesBarsNormalCompliance: compliance 1.5 %, U_int
// 0.5 % (measured 0.99990 both). The paper's area is run as the contrast.
TEST(ValidationInterface, SeriesBarsWithBSplinesReadTheExactInterfaceEnergy) {
  const double E = 2400, A = 2.0, h = 0.5, Dn = 10.0, sigma = 0.01;
  const auto ex = analytic::series_bars(E, 5.0, E, 5.0, Dn, A, sigma * A);
  for (const char* shape : {"bspline2", "bspline3"}) {
    const std::string shape_key = std::string("grid.shape=\"") + shape + "\"";
    const BarsResult r = run_bars(Dn, sigma, h, 1.0, "\"perfect\"", {shape_key});
    const BarsResult paper =
        run_bars(Dn, sigma, h, 1.0, "\"perfect\"", {shape_key, "interaction[0].area=\"paper\""});
    SCOPED_TRACE(shape);
    std::printf("[bars %s] compliance %+.3f %%  U_int/exact %.5f (paper's area %.5f)\n", shape,
                100 * (r.compliance / ex.compliance - 1), r.e.interface / ex.U_interface,
                paper.e.interface / ex.U_interface);
    EXPECT_TRUE(finite(r.e));
    EXPECT_LT(r.e.kinetic, 1e-5 * (r.e.strain + r.e.interface)) << "not static";
    EXPECT_NEAR(r.compliance / ex.compliance, 1.0, 0.015);
    EXPECT_NEAR(r.e.interface / ex.U_interface, 1.0, 0.005);
    EXPECT_LT(paper.e.interface / ex.U_interface, 0.8) << "the paper's area no longer overcounts";
  }
}

// The shear stack (Dt = 10, tau = 1e-3 MPa) with B-splines: U_int within
// 0.5 % of the exact τ² W / (2 Dt) (measured 1.00000 both; the paper's area
// 0.739 and 0.649).
TEST(ValidationInterface, ShearStackWithBSplinesReadsTheExactInterfaceEnergy) {
  const double G1 = analytic::shear_modulus(2400, 0.33), G2 = analytic::shear_modulus(1200, 0.2);
  const double Dt = 10.0, tau = 1e-3, W = 4.0;
  const auto ex = analytic::shear_stack(G1, 2.0, G2, 2.0, Dt, tau);
  for (const char* shape : {"bspline2", "bspline3"}) {
    const ShearResult r = run_shear(Dt, tau, 0.8, {std::string("grid.shape=\"") + shape + "\""});
    SCOPED_TRACE(shape);
    std::printf("[shear %s] U_int/exact %.5f\n", shape,
                r.e.interface / (ex.U_interface_per_area * W));
    EXPECT_TRUE(finite(r.e));
    EXPECT_LT(r.e.kinetic, 1e-5 * (r.e.strain + r.e.interface)) << "not static";
    EXPECT_NEAR(r.e.interface / (ex.U_interface_per_area * W), 1.0, 0.005);
  }
}

// The DLS with B-splines at h = 0.25 mm (4 cells per lap; at 2 cells the
// central lap's two faces share node rows and their gradient shares cancel,
// which `check` warns about): the tolerances of DlsStiffnessVsShearLag, k
// within 2 % of the shear lag and the interface's share of the energy within
// 0.01. Measured k 252.5 / 46.01 (bspline2), 252.6 / 46.03 (bspline3) against
// uGIMP's 250.5 / 45.45 at the same h; shares 0.503, 0.907.
TEST(ValidationInterface, DlsWithBSplinesVsShearLag) {
  for (const char* shape : {"bspline2", "bspline3"})
    for (double inv : {0.1, 1.0}) {
      const DlsRun r =
          run_dls(1.0 / inv, 0.25, 0.25, {std::string("grid.shape=\"") + shape + "\""});
      const auto ex = analytic::DlsShearLag({}, {}, 1.0 / inv).result();
      SCOPED_TRACE(std::string(shape) + " 1/Dt = " + num(inv));
      std::printf(
          "[dls %s h=0.25] 1/Dt %.2f  k %.2f  shear lag %.2f (%+.2f %%)  share %.4f (%.4f)\n",
          shape, inv, r.k, ex.k, 100 * (r.k / ex.k - 1), r.interface_fraction,
          ex.interface_fraction);
      EXPECT_TRUE(finite(r.e));
      EXPECT_NEAR(r.k / ex.k, 1.0, 0.02);
      EXPECT_NEAR(r.interface_fraction, ex.interface_fraction, 0.01);
    }
}

// The specimen turned by 30 degrees about (1.5, 17.5) (tools/figure.py
// fig9's overrides, h = 0.5 mm, 1/Dt = 0.1): its layers' faces are
// staircases of particles. normal = "geometry" reads the interfaces from
// the turned boxes and gives the specified normal's stiffness (measured
// 225.44 both, 0.1 %; the -10 % against the shear lag is this h's, docs/
// interface_validation.md Fig. 9); mvg reads 347.84 (docs/
// contact_validation.md §18).
TEST(ValidationInterface, RotatedDlsWithGeometryNormalMatchesTheSpecified) {
  const std::vector<std::string> turned = {"body[0].rotate=30.0",
                                           "body[1].rotate=30.0",
                                           "body[2].rotate=30.0",
                                           "material[0].axis=[-0.5,0.8660254037844387]",
                                           "material[1].axis=[-0.5,0.8660254037844387]",
                                           "interaction[0].normal_vector=[0.8660254037844387,0.5]",
                                           "grid.cell=[0.5,0.5]",
                                           "grid.origin=[-10.0,0.5]",
                                           "grid.cells=[46,68]",
                                           "interaction[0].Dt=10.0"};
  double k[2] = {0, 0};
  const char* normals[2] = {"specified", "geometry"};
  for (int i = 0; i < 2; ++i) {
    std::vector<std::string> ov = turned;
    ov.push_back(std::string("interaction[0].normal=\"") + normals[i] + "\"");
    auto sim = make_scene("dls.toml", ov);
    run_until(*sim, 0.25);
    const Energies e = sim->energies();
    EXPECT_TRUE(finite(e));
    k[i] = analytic::stiffness_from_energy(2.0, e.strain + e.interface);
  }
  std::printf("[dls 30 deg h=0.5] k specified %.3f geometry %.3f\n", k[0], k[1]);
  EXPECT_NEAR(k[1] / k[0], 1.0, 0.001) << k[0] << " " << k[1];
}

// Two bars 5 x 4 mm end to end on a grid line (x = 5), Dn = 100, Dt = 1000
// MPa/mm, the left end on a roller plane, the right end pulled by 1 MPa
// (linear shapes, h = 0.5, 2 x 2 ppc, ν = 0, damped to rest by 1 ms; an
// outside review's scene). Exact: U = σ² V / (2E) = 0.02 and U_int = σ² A /
// (2 Dn) = 0.02 mJ. At the interface's end nodes each box's normal is a
// corner's, and the signed distance switched between the shared face and
// the side face as the bars moved: the left bar, moving 0.0025 mm, read
// the side face there, the corner rows carried σxx ≈ 3 and U_int read
// 0.0110. normal = "geometry" now takes the faces that face each other
// (take_facing_faces) and gives the specified normal's energies (measured:
// both U 0.01998, U_int 0.02084). Tolerance: the specified run's energies
// within 1e-6; both within 5 % of exact (the grid-line interface's
// displacement-separation bias, docs/interface_validation.md).
TEST(ValidationInterface, BarsEndToEndWithGeometryNormalMatchTheSpecified) {
  const std::string scene = R"([simulation]
dimension = 2
end_time = 1.0
flip = 0.95
[grid]
origin = [-2.0, -2.0]
cell = [0.5, 0.5]
cells = [28, 16]
shape = "linear"
damping = 20.0
[[material]]
name = "left"
type = "isotropic"
density = 1.0e-3
E = 1000.0
nu = 0.0
[[material]]
name = "right"
type = "isotropic"
density = 1.0e-3
E = 1000.0
nu = 0.0
[[body]]
name = "l"
material = "left"
shape = "box"
min = [0.0, 0.0]
max = [5.0, 4.0]
[[body]]
name = "r"
material = "right"
shape = "box"
min = [5.0, 0.0]
max = [10.0, 4.0]
[[interaction]]
materials = ["left", "right"]
law = "interface"
Dn = 100.0
Dt = 1000.0
normal_vector = [1.0, 0.0]
[[boundary]]
where = { x = 0.0 }
fix = ["x"]
[[load]]
kind = "traction"
where = { body = "r", face = "x_max" }
traction = [1.0, 0.0]
ramp = 0.02
)";
  Energies e[2];
  const char* normals[2] = {"specified", "geometry"};
  for (int i = 0; i < 2; ++i) {
    auto sim = testing::make_from_text(
        scene, {std::string("interaction[0].normal=\"") + normals[i] + "\""});
    run_until(*sim, 1.0);
    e[i] = sim->energies();
    std::printf("[bars end to end] %-9s U %.5f U_int %.5f (exact 0.02, 0.02)\n", normals[i],
                e[i].strain, e[i].interface);
    EXPECT_NEAR(e[i].strain / 0.02, 1.0, 0.05) << normals[i];
    EXPECT_NEAR(e[i].interface / 0.02, 1.0, 0.05) << normals[i];
  }
  EXPECT_NEAR(e[1].strain / e[0].strain, 1.0, 1e-6);
  EXPECT_NEAR(e[1].interface / e[0].interface, 1.0, 1e-6);
}

// Refinement h = 0.5 -> 0.25 mm over 1/Dt = 0 (perfect), 0.01, 0.1, 1 (0.25 ms).
// At h = 0.25 every value is within 1.5 % of the shear-lag k (the perfect end, where
// the theory's singular end tractions and the bending it ignores matter most, within
// 2 %), and the error at the perfect end shrinks with refinement.
TEST(ValidationInterfaceLong, DlsStiffnessRefinement) {
  MMPM_LONG_TEST();
  std::vector<double> err_coarse, err_fine;
  const std::vector<double> inverse = {0.0, 0.01, 0.1, 1.0};
  for (double inv : inverse) {
    const double Dt = inv == 0 ? analytic::kInf : 1.0 / inv;
    const double exact = analytic::dls_stiffness(Dt);
    const DlsRun c = run_dls(Dt, 0.5, 0.25), f = run_dls(Dt, 0.25, 0.25);
    err_coarse.push_back(c.k / exact - 1), err_fine.push_back(f.k / exact - 1);
    std::printf("[dls] 1/Dt = %.2f  k(0.5) = %.2f  k(0.25) = %.2f  shear lag %.2f\n", inv, c.k, f.k,
                exact);
    EXPECT_NEAR(f.k / exact, 1.0, inv == 0 ? 0.02 : 0.015) << "1/Dt = " << inv;
  }
  EXPECT_LT(std::abs(err_fine[0]), std::abs(err_coarse[0]));
}

// ---------------------------------------------------------------------------
// (d) Location independence (paper Fig. 8): interface on a grid line vs on cell
//     midplanes (grid origin shifted by half a cell), SN normal.
// ---------------------------------------------------------------------------
double two_layer_interface_energy(double h, double Dt, bool midplane, double t_end) {
  const double x0 = -1.0 - (midplane ? 0.5 * h : 0.0);
  const int nx = int(std::lround(10.0 / h)), ny = int(std::lround(22.0 / h));
  auto sim =
      make_scene("two_layer.toml",
                 {"grid.cell=[" + num(h) + "," + num(h) + "]", "grid.origin=[" + num(x0) + ",-1.0]",
                  "grid.cells=[" + std::to_string(nx) + "," + std::to_string(ny) + "]",
                  "interaction[0].Dt=" + num(Dt), "interaction[0].Dn=\"perfect\"",
                  "interaction[0].normal=\"specified\"", "interaction[0].min_volume=0.0",
                  "boundary[0].where={min=[-2.0,-2.0],max=[10.0,0.0]}"});
  run_until(*sim, t_end);
  const Energies e = sim->energies();
  EXPECT_TRUE(finite(e));
  return e.interface;
}

// Two-layer specimen (inputs/two_layer.toml: 4 x 20 mm layers, 4 mm thick, 0.5 MPa,
// Dn perfect, SN normal, no volume screening), h = 0.5 mm, 1/Dt = 0.5 mm/MPa, static
// by 0.8 ms. The contact area (P-20) makes the total interface energy independent of
// where the interface lies within a cell up to a first-order discretisation error.
// Tolerance 5 % (measured 3.7 % at h = 0.5; 2.0 % at h = 0.25, see the Long test).
// For scale: the paper's uncorrected midplane area doubles the effective Dt, which
// moves the energy by 40 % here (0.461 -> 0.644 N/m^2 for Dt 2 -> 4).
// History: this bound was first set at 3 %; the measured 3.6-3.7 % failed it, and the
// refinement study (gap halves with h) is what the test now relies on.
TEST(ValidationInterface, TwoLayerInterfaceLocationIndependence) {
  const double grid = two_layer_interface_energy(0.5, 2.0, false, 0.8);
  const double mid = two_layer_interface_energy(0.5, 2.0, true, 0.8);
  std::printf("[two-layer h=0.5, 1/Dt=0.5] U_int grid line %.6g, midplane %.6g mJ (ratio %.4f)\n",
              grid, mid, mid / grid);
  EXPECT_GT(grid, 0.0);
  EXPECT_NEAR(mid / grid, 1.0, 0.05);
}

// The grid-line/midplane gap is first order in h: at 1/Dt = 0.5 it shrinks by a factor
// 0.35-0.65 from h = 0.5 to h = 0.25 mm, and at h = 0.25 it is below 3 % for
// 1/Dt = 0.1, 0.5 and 1 (static by 0.8 ms).
TEST(ValidationInterfaceLong, TwoLayerInterfaceLocationIndependenceFine) {
  MMPM_LONG_TEST();
  const double coarse = two_layer_interface_energy(0.5, 2.0, true, 0.8) /
                            two_layer_interface_energy(0.5, 2.0, false, 0.8) -
                        1;
  double fine_half = 0;
  for (double inv : {0.1, 0.5, 1.0}) {
    const double grid = two_layer_interface_energy(0.25, 1 / inv, false, 0.8);
    const double mid = two_layer_interface_energy(0.25, 1 / inv, true, 0.8);
    std::printf("[two-layer h=0.25, 1/Dt=%.2f] U_int grid line %.6g, midplane %.6g mJ\n", inv, grid,
                mid);
    EXPECT_NEAR(mid / grid, 1.0, 0.03) << "1/Dt = " << inv;
    if (inv == 0.5) fine_half = mid / grid - 1;
  }
  EXPECT_NEAR(fine_half / coarse, 0.5, 0.15)
      << "gap h=0.5: " << coarse << ", h=0.25: " << fine_half;
}

// ---------------------------------------------------------------------------
// (e) Stability at the extremes (ALGORITHM §4.4, §4.5)
// ---------------------------------------------------------------------------
// Series bars (h = 0.5 mm), Dn = Dt = D, load 1e-3 MPa, 0.4 ms (static for D >= 1).
struct ExtremeRun {
  bool threw = false;
  std::string message;
  Energies e;
  double compliance = 0;
  long limited = 0;
};

ExtremeRun run_extreme(double D, bool force_limit, const std::string& integration, double t_end) {
  ExtremeRun r;
  const std::string d = stiffness_value(D);
  auto sim = make_scene(
      "series_bars.toml",
      {"interaction[0].Dn=" + d, "interaction[0].Dt=" + d,
       std::string("interaction[0].force_limit=") + (force_limit ? "true" : "false"),
       "interaction[0].integration=\"" + integration + "\"", "load[0].traction=[0.0,0.001]"});
  try {
    while (sim->time() < t_end) {
      sim->step();
      r.limited = std::max(r.limited, sim->counters().force_limited_nodes);
      if (sim->step_count() % 50 == 0 && !finite(sim->energies())) break;
    }
  } catch (const SimulationError& e) {
    r.threw = true;
    r.message = e.what();
  }
  r.e = sim->energies();
  if (!r.threw && finite(r.e)) {
    const State s = state_of(*sim);
    const Line a = fit_material(s, 0, 1, 0.5, 4.5), b = fit_material(s, 1, 1, 5.5, 9.5);
    r.compliance = (b.at(10.0) - a.at(0.0)) / (0.001 * 2.0);
  }
  return r;
}

// With the force limit, 1/D from 1e-12 to 1e3 mm/MPa and "perfect" all run to the end
// with finite energies. Bounded: the stored energy never exceeds twice the static
// energy at that D (a ramped load overshoots by less), and for D >= 1e6 the stiff
// directions become stick (force-limited counts > 0) and the compliance equals the
// perfect one within 0.5 %, with no interface energy above 1e-3 of the strain energy.
TEST(ValidationInterface, ExtremesStableWithForceLimit) {
  const double E = 2400, A = 2.0, P = 0.001 * A;
  const double C_perfect = analytic::series_bars(E, 5, E, 5, analytic::kInf, A, P).compliance;
  for (double D : {analytic::kInf, 1e12, 1e9, 1e6, 1e3, 1.0, 1e-3}) {
    SCOPED_TRACE("D = " + num(D));
    const ExtremeRun r = run_extreme(D, true, "explicit", 0.4);
    std::printf(
        "[extremes, force limit] D %-8g threw %d  U %.4g (static %.4g)  U_int %.3g  C/C_perfect "
        "%.5f  limited %ld\n",
        D, int(r.threw), r.e.strain + r.e.interface,
        analytic::series_bars(E, 5, E, 5, D, A, P).U_total, r.e.interface, r.compliance / C_perfect,
        r.limited);
    ASSERT_FALSE(r.threw) << r.message;
    ASSERT_TRUE(finite(r.e));
    const auto ex = analytic::series_bars(E, 5, E, 5, D, A, P);
    EXPECT_LE(r.e.strain + r.e.interface + r.e.kinetic, 2.0 * ex.U_total);
    if (D >= 1e6) {
      if (!std::isinf(D)) {
        EXPECT_GT(r.limited, 0);
      }
      EXPECT_NEAR(r.compliance / C_perfect, 1.0, 0.005);
      EXPECT_LT(r.e.interface, 1e-3 * r.e.strain);
    }
  }
}

// Without the force limit the stiff end misbehaves: at D >= 1e6 MPa/mm the explicit
// interface spring (omega dt >> 2 at the interface nodes) is unstable, and the run
// either stops with "unstable" or its energies leave every physical bound (non-finite,
// or more than 10x the static energy). The soft end (D = 1) is unaffected.
TEST(ValidationInterface, ExtremesUnstableWithoutForceLimit) {
  const double E = 2400, A = 2.0, P = 0.001 * A;
  for (double D : {1e12, 1e6}) {
    SCOPED_TRACE("D = " + num(D));
    const ExtremeRun r = run_extreme(D, false, "explicit", 0.05);
    const auto ex = analytic::series_bars(E, 5, E, 5, D, A, P);
    std::printf("[extremes, no limit] D %-8g threw %d (%s)  U %.4g\n", D, int(r.threw),
                r.message.substr(0, 60).c_str(), r.e.strain + r.e.interface + r.e.kinetic);
    const bool blew_up =
        r.threw || !finite(r.e) || r.e.strain + r.e.interface + r.e.kinetic > 10 * ex.U_total;
    EXPECT_TRUE(blew_up) << "energy " << r.e.strain + r.e.interface + r.e.kinetic << " static "
                         << ex.U_total;
  }
  const ExtremeRun soft = run_extreme(1.0, false, "explicit", 0.05);
  EXPECT_FALSE(soft.threw) << soft.message;
  EXPECT_TRUE(finite(soft.e));
}

// integration = "exact" (ALGORITHM §4.5) is stable at the stiff end without any force
// limit: D = 1e12 and 1e6 give the perfect compliance within 0.5 %; D = 1e3 gives the
// explicit scheme's compliance within 0.5 %.
TEST(ValidationInterface, ExtremesExactIntegrationStable) {
  const double E = 2400, A = 2.0, P = 0.001 * A;
  const double C_perfect = analytic::series_bars(E, 5, E, 5, analytic::kInf, A, P).compliance;
  for (double D : {1e12, 1e6}) {
    SCOPED_TRACE("D = " + num(D));
    const ExtremeRun r = run_extreme(D, false, "exact", 0.4);
    std::printf("[extremes, exact] D %-8g threw %d  C/C_perfect %.5f  limited %ld\n", D,
                int(r.threw), r.compliance / C_perfect, r.limited);
    ASSERT_FALSE(r.threw) << r.message;
    ASSERT_TRUE(finite(r.e));
    EXPECT_NEAR(r.compliance / C_perfect, 1.0, 0.005);
  }
  const ExtremeRun ex = run_extreme(1e3, false, "exact", 0.4),
                   ep = run_extreme(1e3, true, "explicit", 0.4);
  ASSERT_FALSE(ex.threw || ep.threw);
  EXPECT_NEAR(ex.compliance / ep.compliance, 1.0, 0.005);
}

// integration = "exact" at rest: the series bars of SeriesBarsNormalCompliance
// (h = 0.5 mm, uGIMP, MUSL, static by damping at 1 ms) at Dn = 1e3 and 1e4,
// where θ = ωΔt at the interface nodes is 0.3 and 0.9. Without Δf_i the
// exact spring held the bars with k s C(θ): the interface energy read +3.2 %
// and +37 % (an outside review), and a last step shortened to 0.3 Δt, whose
// C(θ) differs, kicked the resting bars (kinetic energy 8.5e-15 -> 2.1e-11
// mJ). Tolerances: interface energy P²/(2 Dn A) within 0.5 % (as the
// explicit scheme's test), and still static (K < 1e-5 (U + U_int)) after the
// short step.
TEST(ValidationInterface, SeriesBarsExactSpringAtRestReadsTheInterfaceEnergy) {
  const double E = 2400, A = 2.0, h = 0.5, sigma = 0.01;
  for (double Dn : {1e3, 1e4}) {
    SCOPED_TRACE("Dn = " + num(Dn));
    const int nx = int(std::lround(4.0 / h)), ny = int(std::lround(12.0 / h));
    auto sim = make_scene("series_bars.toml",
                          {"grid.cell=[" + num(h) + "," + num(h) + "]",
                           "grid.cells=[" + std::to_string(nx) + "," + std::to_string(ny) + "]",
                           "interaction[0].Dn=" + num(Dn), "interaction[0].integration=\"exact\"",
                           "load[0].traction=[0.0," + num(sigma) + "]"});
    run_until(*sim, 1.0);
    const auto ex = analytic::series_bars(E, 5.0, E, 5.0, Dn, A, sigma * A);
    const Energies rest = state_of(*sim).e;
    sim->step_within(sim->time() + 0.3 * sim->dt());
    const Energies after = state_of(*sim).e;
    std::printf("[bars exact] Dn %-6g U_int/exact %.5f  K %.3g -> %.3g after a 0.3 dt step\n", Dn,
                rest.interface / ex.U_interface, rest.kinetic, after.kinetic);
    EXPECT_NEAR(rest.interface / ex.U_interface, 1.0, 0.005);
    EXPECT_LT(rest.kinetic, 1e-5 * (rest.strain + rest.interface)) << "not static";
    EXPECT_LT(after.kinetic, 1e-5 * (after.strain + after.interface)) << "kicked by the short step";
  }
}

// A perfect interface between a soft, light bar and a stiff, heavy one moves
// as one field. series_bars (h = 0.5 mm, uGIMP) with the bottom bar at E =
// 2.4 MPa, nu = 0, density 1e3 and 1e5 times below the top bar's, sigma =
// 2.4e-4 MPa, damped at 15 /ms; at 1 ms the two-field run must be the run
// with both bars in one shared field (no [[interaction]]), and both the
// uniaxial sigma y / E. The light bar's top particle row, 0.125 mm below the
// interface, reaches the node row above it (y = 5.5) with uGIMP weights of
// ~1e-6 once it stretches. While the pass left out fields below 1e-6 of the
// lightest particle, those slivers moved on their own
// and the row lagged: 0.950 (ratio 1e3) and 0.265 (1e5) of sigma y / E at
// 1 ms, 0.86 and 0.012 at 3 ms (an outside review; docs/interface_validation.md
// Finding 13). Now an interface bonds every field the grid gives a velocity
// (MultimaterialStage::setup): 1.0011 at 1 ms for both ratios, the shared
// field's digits. Tolerances: the shared field within 1e-4 of its value
// (round-off and the pass's order), sigma y / E within 0.3 % (at 1 ms the
// damped bars are 0.1 % from rest). Under pure FLIP the unbonded slivers
// also fed the particle velocities the grid does not see (Finding 5): the
// equal-density bars with the perfect interface carried 2.6e-10 mJ of
// kinetic energy at 1 ms (6e-4 of the strain energy) and kept gaining; now
// 2e-17. Checked below 1e-6 of the strain energy.
TEST(ValidationInterface, PerfectInterfaceAtLargeDensityRatioMovesAsOneField) {
  const double E_soft = 2.4, sigma = 2.4e-4;
  std::ifstream file(input_path("series_bars.toml"));
  const std::string shared = testing::replace_between(
      std::string((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>()),
      "[[interaction]]", "[[boundary]]", "");
  // The top particle row of the light bar and the row below it, over sigma y / E.
  const auto rows = [&](const Simulation& sim) {
    std::array<double, 2> out{};
    for (int r = 0; r < 2; ++r) {
      const double y0 = 4.875 - 0.25 * r;
      out[r] = testing::row_mean_displacement(sim, y0, 1) / (sigma * y0 / E_soft);
    }
    return out;
  };
  for (double ratio : {1e3, 1e5}) {
    SCOPED_TRACE("density ratio " + num(ratio));
    const std::vector<std::string> ov = {"material[0].E=" + num(E_soft),
                                         "material[0].density=" + num(1.2e-3 / ratio),
                                         "material[0].nu=0.0",
                                         "material[1].nu=0.0",
                                         "load[0].traction=[0.0," + num(sigma) + "]",
                                         "grid.damping=15.0"};
    std::vector<std::string> bonded = ov;
    bonded.push_back("interaction[0].Dn=\"perfect\"");
    auto two = make_scene("series_bars.toml", bonded);
    auto one = testing::make_from_text(shared, ov);
    run_until(*two, 1.0);
    run_until(*one, 1.0);
    const auto r2 = rows(*two), r1 = rows(*one);
    std::printf(
        "[bars perfect] ratio %-6g rows/(sigma y/E): two fields %.5f %.5f  shared %.5f %.5f\n",
        ratio, r2[0], r2[1], r1[0], r1[1]);
    for (int r = 0; r < 2; ++r) {
      EXPECT_NEAR(r2[r], r1[r], 1e-4) << "row " << r;
      EXPECT_NEAR(r2[r], 1.0, 0.003) << "row " << r;
    }
  }
  auto flip =
      make_scene("series_bars.toml", {"interaction[0].Dn=\"perfect\"", "simulation.flip=1.0"});
  run_until(*flip, 1.0);
  const Energies e = flip->energies();
  std::printf("[bars perfect] pure FLIP at 1 ms: K %.3g mJ, U %.3g mJ\n", e.kinetic, e.strain);
  EXPECT_LT(e.kinetic, 1e-6 * e.strain);
}

// ---------------------------------------------------------------------------
// (e2) A fibre in 3D: the radial normal about an axis (ALGORITHM §5, SN radial
// for cylindrical inclusions)
// ---------------------------------------------------------------------------
// A quarter glass fibre (r = 0.6 mm) in a 1 x 1 mm polymer cell, Dn = 1e3,
// Dt = 1e4 MPa/mm, symmetry planes x = 0, y = 0, the outer faces moved to
// 0.5 % strain in x and y (transverse biaxial load), damped to 0.02 ms; the
// paper's sphere-in-cube materials and grid (0.1 mm, uGIMP, 2 ppc). In 2D
// plane strain; in 3D as a slab 0.2 mm thick along the fibre, both z faces
// held in z (plane strain), with `normal = "radial"`, `axis = [0, 0, 1]`
// (inputs/fibre_slab.toml, the shipped scene).
// Every 3D particle has a 2D twin at the same (x, y) and the slab's z
// columns see the same fields, so the 3D run must be the 2D run (and so must
// the same slab turned to run along x, kFibre3DAlongX): in-plane
// displacements within 1e-9 of the largest, u_z = 0, strain, interface
// energy and work per thickness within 1e-9 (measured: 3e-16 and 6
// digits). Without the axis the 3D normal points from the point (0, 0, 0),
// tilts out of the plane by up to atan(0.2 / 0.6) = 18 degrees, and mixes
// Dt into the radial opening: measured U_int +21.5 %, checked > 5 % off.
// The glass fibre and the polymer matrix of every fibre cell below.
const std::string kFibreMaterials = R"([[material]]
name    = "glass"
type    = "isotropic"
density = 2.5e-3
E       = 70000.0
nu      = 0.25
[[material]]
name    = "polymer"
type    = "isotropic"
density = 1.2e-3
E       = 2400.0
nu      = 0.33
)";
const std::string kFibre2D = R"([simulation]
dimension = 2
plane     = "strain"
thickness = 1.0
end_time  = 0.02
cfl       = 0.5
flip      = 0.99
[grid]
origin  = [-0.1, -0.1]
cell    = [0.1, 0.1]
cells   = [13, 13]
shape   = "gimp"
damping = 1500.0
)" + kFibreMaterials + R"([[body]]
name     = "matrix"
material = "polymer"
shape    = "box"
min      = [0.0, 0.0]
max      = [1.0, 1.0]
particles_per_cell = 2
[[body]]
name     = "fibre"
material = "glass"
shape    = "disk"
center   = [0.0, 0.0]
radius   = 0.6
clip     = { min = [0.0, 0.0], max = [1.0, 1.0] }
particles_per_cell = 2
[[interaction]]
materials   = ["glass", "polymer"]
law         = "interface"
Dn          = 1.0e3
Dt          = 1.0e4
normal      = "radial"
center      = [0.0, 0.0]
separation  = "displacement"
[[boundary]]
where = { min = [-0.1, -0.1], max = [0.0, 1.2] }
fix   = ["x"]
[[boundary]]
where = { min = [-0.1, -0.1], max = [1.2, 0.0] }
fix   = ["y"]
[[boundary]]
where        = { min = [1.0, -0.1], max = [1.2, 1.2] }
fix          = ["x"]
displacement = [0.005, 0.0]
ramp         = 0.003
[[boundary]]
where        = { min = [-0.1, 1.0], max = [1.2, 1.2] }
fix          = ["y"]
displacement = [0.0, 0.005]
ramp         = 0.003
)";

// The fibre slab again with the fibre along x: the cylinder body's and the
// normal's `axis = [1, 0, 0]`, every coordinate of inputs/fibre_slab.toml cycled (x, y, z)
// -> (z, x, y). Same checks, with the 2D (x, y) as the slab's (y, z).
const std::string kFibre3DAlongX = R"([simulation]
dimension = 3
end_time  = 0.02
cfl       = 0.5
flip      = 0.99
[grid]
origin  = [-0.2, -0.1, -0.1]
cell    = [0.1, 0.1, 0.1]
cells   = [6, 13, 13]
shape   = "gimp"
damping = 1500.0
)" + kFibreMaterials + R"([[body]]
name     = "matrix"
material = "polymer"
shape    = "box"
min      = [0.0, 0.0, 0.0]
max      = [0.2, 1.0, 1.0]
particles_per_cell = 2
[[body]]
name     = "fibre"
material = "glass"
shape    = "cylinder"
center   = [0.0, 0.0, 0.0]
radius   = 0.6
length   = 0.2
axis     = [1.0, 0.0, 0.0]
clip     = { min = [0.0, 0.0, 0.0], max = [0.2, 1.0, 1.0] }
particles_per_cell = 2
[[interaction]]
materials   = ["glass", "polymer"]
law         = "interface"
Dn          = 1.0e3
Dt          = 1.0e4
normal      = "radial"
center      = [0.0, 0.0, 0.0]
axis        = [1.0, 0.0, 0.0]
separation  = "displacement"
[[boundary]]
where = { min = [-0.2, -0.1, -0.1], max = [0.4, 0.0, 1.2] }
fix   = ["y"]
[[boundary]]
where = { min = [-0.2, -0.1, -0.1], max = [0.4, 1.2, 0.0] }
fix   = ["z"]
[[boundary]]
where = { min = [-0.2, -0.1, -0.1], max = [0.0, 1.2, 1.2] }
fix   = ["x"]
[[boundary]]
where = { min = [0.2, -0.1, -0.1], max = [0.4, 1.2, 1.2] }
fix   = ["x"]
[[boundary]]
where        = { min = [-0.2, 1.0, -0.1], max = [0.4, 1.2, 1.2] }
fix          = ["y"]
displacement = [0.0, 0.005, 0.0]
ramp         = 0.003
[[boundary]]
where        = { min = [-0.2, -0.1, 1.0], max = [0.4, 1.2, 1.2] }
fix          = ["z"]
displacement = [0.0, 0.0, 0.005]
ramp         = 0.003
)";

// The slab's particles against their 2D twins: `in_plane` names the slab's
// two section axes (the 2D x and y), the third is along the fibre.
void expect_slab_is_the_plane_cell(const State& a, std::size_t plane_count, const State& b,
                                   std::size_t slab_count, std::array<int, 2> in_plane, int along,
                                   const char* label) {
  double largest = 0, worst = 0, worst_along = 0;
  for (std::size_t p = 0; p < plane_count; ++p)
    largest = std::max({largest, std::abs(a.disp.at(p, 0)), std::abs(a.disp.at(p, 1))});
  std::size_t twins = 0;
  for (std::size_t q = 0; q < slab_count; ++q) {
    for (std::size_t p = 0; p < plane_count; ++p) {
      if (std::abs(a.x0(p, 0) - b.x0(q, in_plane[0])) > 1e-9 ||
          std::abs(a.x0(p, 1) - b.x0(q, in_plane[1])) > 1e-9)
        continue;
      ++twins;
      worst = std::max({worst, std::abs(a.disp.at(p, 0) - b.disp.at(q, in_plane[0])),
                        std::abs(a.disp.at(p, 1) - b.disp.at(q, in_plane[1]))});
      worst_along = std::max(worst_along, std::abs(b.disp.at(q, along)));
      break;
    }
  }
  const double t = 0.2;
  std::printf(
      "[fibre %s] 2D: U %.6e U_int %.6e W %.6e; 3D / t: U %.6e U_int %.6e W %.6e; worst "
      "in-plane difference %.2e of %.3e, |u along the fibre| %.1e\n",
      label, a.e.strain, a.e.interface, a.e.external_work, b.e.strain / t, b.e.interface / t,
      b.e.external_work / t, worst, largest, worst_along);
  EXPECT_EQ(twins, slab_count) << label << ": a 3D particle without a 2D twin";
  EXPECT_LT(worst, 1e-9 * largest) << label;
  EXPECT_LT(worst_along, 1e-9 * largest) << label;
  EXPECT_NEAR(b.e.strain / t / a.e.strain, 1.0, 1e-9) << label;
  EXPECT_NEAR(b.e.interface / t / a.e.interface, 1.0, 1e-9) << label;
  EXPECT_NEAR(b.e.external_work / t / a.e.external_work, 1.0, 1e-9) << label;
}

TEST(ValidationInterface, FibreIn3DWithARadialAxisIsThe2DPlaneStrainCell) {
  auto plane = testing::make_from_text(kFibre2D);
  auto slab = make_scene("fibre_slab.toml", {});  // the shipped scene
  auto slab_x = testing::make_from_text(kFibre3DAlongX);
  run_until(*plane, 0.02);
  run_until(*slab, 0.02);
  run_until(*slab_x, 0.02);
  const State a = state_of(*plane);
  EXPECT_GT(a.e.interface, 0.1 * a.e.strain) << "the interface must matter";
  expect_slab_is_the_plane_cell(a, plane->particle_count(), state_of(*slab), slab->particle_count(),
                                {0, 1}, 2, "along z");
  expect_slab_is_the_plane_cell(a, plane->particle_count(), state_of(*slab_x),
                                slab_x->particle_count(), {1, 2}, 0, "along x");
  const double t = 0.2;

  // The same slab with the radial normal about the point (0, 0, 0).
  std::ifstream file(input_path("fibre_slab.toml"));
  std::string point((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  const std::size_t key = point.find("\naxis        =");  // the interaction's, not the body's
  ASSERT_NE(key, std::string::npos);
  point.erase(key, point.find('\n', key + 1) - key);
  auto tilted = testing::make_from_text(point);
  run_until(*tilted, 0.02);
  const double off = tilted->energies().interface / t / a.e.interface - 1;
  std::printf("[fibre] 3D with the point normal: U_int / t %+.1f %% off the 2D cell\n", 100 * off);
  EXPECT_GT(std::abs(off), 0.05);
}

// The 2D fibre cell refined, h = 0.1, 0.05, 0.025 mm (13² to 52² cells), with the
// paper's area, the closed one (docs/multimaterial.md §7.1) and the gradient one
// (§7.2). The interface opens about 5e-3 mm (Dn = 1e3 MPa/mm under 0.5 % strain):
// 5 % of a cell at h = 0.1, 20 % at 0.025. No exact answer for a square cell, so the
// test asserts refinement behaviour, static at 0.02 ms (measured, U = strain +
// interface energy in mJ, 1 mm thick):
//   paper:    U 0.068633, 0.067529, 0.065524; U_int 0.014723, 0.014061, 0.012468
//   closed:   U 0.069726, 0.069369, 0.069133; U_int 0.015440, 0.015393, 0.015190
//   gradient: U 0.068387, 0.068526, 0.068569; U_int 0.014823, 0.014880, 0.014860
// With the closed area the changes of U shrink (−0.51 %, −0.34 %; checked: the second
// below 0.5 % and below the first) and U_int moves by 1.3 % from 0.05 to 0.025 (checked
// < 2 %). The gradient area's changes are +0.20 %, +0.06 % (checked: the second below
// 0.2 % and below the first; U_int within 0.5 %). With the paper's area U_int falls
// 11 % over the same refinement (checked > 8 %): its area loses 1.5 × opening / cell.
TEST(ValidationInterface, FibreCellWithTheClosedAndGradientAreasConvergeUnderRefinement) {
  const char* rules[3] = {"paper", "closed", "gradient"};
  double U[3][3], U_int[3][3];
  const double hs[3] = {0.1, 0.05, 0.025};
  for (int rule = 0; rule < 3; ++rule)
    for (int k = 0; k < 3; ++k) {
      const std::string n = std::to_string(std::lround(1.3 / hs[k]));
      auto sim = testing::make_from_text(
          kFibre2D,
          {"grid.cell=[" + num(hs[k]) + "," + num(hs[k]) + "]", "grid.cells=[" + n + "," + n + "]",
           std::string("interaction[0].area=\"") + rules[rule] + "\""});
      run_until(*sim, 0.02);
      const State s = state_of(*sim);
      EXPECT_TRUE(finite(s.e));
      EXPECT_LT(s.e.kinetic, 1e-4 * (s.e.strain + s.e.interface)) << "not static";
      U[rule][k] = s.e.strain + s.e.interface;
      U_int[rule][k] = s.e.interface;
      std::printf("[fibre cell %-8s] h %-5g U %.6f U_int %.6f\n", rules[rule], hs[k], U[rule][k],
                  U_int[rule][k]);
    }
  const auto step = [&](int rule, int k) { return std::abs(U[rule][k + 1] / U[rule][k] - 1); };
  EXPECT_LT(step(1, 1), 0.005);
  EXPECT_LT(step(1, 1), step(1, 0));
  EXPECT_NEAR(U_int[1][2] / U_int[1][1], 1.0, 0.02);
  EXPECT_LT(step(2, 1), 0.002);
  EXPECT_LT(step(2, 1), step(2, 0));
  EXPECT_NEAR(U_int[2][2] / U_int[2][1], 1.0, 0.005);
  EXPECT_LT(U_int[0][2] / U_int[0][1], 0.92) << "the paper's area no longer loses area";
}

// ---------------------------------------------------------------------------
// (f) 3D sphere in a cube: bulk modulus vs the composite spheres assemblage
// ---------------------------------------------------------------------------
struct CubeRun {
  double K_energy = 0, K_pressure = 0, interface_fraction = 0;
  Energies e;
};

// inputs/sphere_in_cube.toml: 1 mm cube, eps0 = 0.5 %, symmetry planes held, outer
// faces displaced (boxes 3, 4, 5). K from energy (P-35) and from the mean normal
// reaction on the three outer faces, each of area 1 mm^2 (P-36).
CubeRun run_cube(double D, double h, int ppc, double t_end,
                 const std::vector<std::string>& extra = {}) {
  const int n = int(std::lround(1.3 / h));
  std::vector<std::string> ov = {
      "interaction[0].Dn=" + stiffness_value(D),
      "interaction[0].Dt=" + stiffness_value(D),
      "grid.cell=[" + num(h) + "," + num(h) + "," + num(h) + "]",
      "grid.cells=[" + std::to_string(n) + "," + std::to_string(n) + "," + std::to_string(n) + "]",
      "body[0].particles_per_cell=" + std::to_string(ppc),
      "body[1].particles_per_cell=" + std::to_string(ppc)};
  ov.insert(ov.end(), extra.begin(), extra.end());
  auto sim = make_scene("sphere_in_cube.toml", ov);
  run_until(*sim, t_end);
  CubeRun r;
  r.e = sim->energies();
  const double eps0 = 0.005, l = 1.0;
  const double U = r.e.strain + r.e.interface;
  r.K_energy = analytic::bulk_from_energy(U, l * l * l, eps0);
  double mean = 0;
  for (const Reaction& re : sim->reactions()) {
    if (re.name == "box3") mean += re.force[0];
    if (re.name == "box4") mean += re.force[1];
    if (re.name == "box5") mean += re.force[2];
  }
  r.K_pressure = analytic::bulk_from_pressure(mean / 3.0 / (l * l), eps0);
  r.interface_fraction = r.e.interface / U;
  return r;
}

double csa(double D) {
  const double Ki = analytic::bulk_modulus(70000, 0.25), Km = analytic::bulk_modulus(2400, 0.33),
               Gm = analytic::shear_modulus(2400, 0.33);
  return analytic::csa_bulk(Ki, Km, Gm, std::numbers::pi / 6 * 0.343, 0.7, D);
}

// 100 um cells (10 across the cube), 1 particle per cell per direction (1000
// particles), radial normal, Dn = Dt = 1e4 MPa/mm (1/D = 1e-4, the middle of the
// transition: CSA 2328.7 MPa, 17 % of the energy in the interface), 0.012 ms.
// Generous tolerance: both K within 6 % of CSA (measured +4.4 % energy, +2.6 %
// pressure; the cube is a cubic array, not the CSA, and h = 100 um gives the
// stiff-interface bias of about +2 % here), and K_energy >= K_pressure - 1 %.
TEST(ValidationInterface, SphereInCubeBulkModulusCoarse) {
  const CubeRun r = run_cube(1e4, 0.1, 1, 0.012);
  const double exact = csa(1e4);
  std::printf(
      "[cube h=0.1 ppc=1 1/D=1e-4] K_energy %.1f  K_pressure %.1f  CSA %.1f  U_int/U %.3f\n",
      r.K_energy, r.K_pressure, exact, r.interface_fraction);
  EXPECT_TRUE(finite(r.e));
  EXPECT_NEAR(r.K_energy / exact, 1.0, 0.06);
  EXPECT_NEAR(r.K_pressure / exact, 1.0, 0.06);
  EXPECT_GT(r.interface_fraction, 0.1);
}

// Without the force limit the explicit interface spring at a node the
// interface halves has omega^2 = (2 D / h)(1 / rho_a + 1 / rho_b) and is
// stable while omega dt < 2 (docs/multimaterial.md §8; `check` and `run`
// warn above it). two_layer.toml (h = 0.25, rho = 1.2e-3 both, cfl 0.5):
// the bound is D = 4.3e4 MPa/mm; measured stable at 3e4 (0.70 x), unstable
// at 6e4 (1.39 x, step 86). Here 0.7 x and 1.4 x the bound, for 0.05 ms
// (600 steps), Dn = Dt = D.
TEST(ValidationInterface, StiffnessBoundWithoutForceLimit) {
  const double h = 0.25, rho = 1.2e-3;
  for (const double factor : {0.7, 1.4}) {
    auto probe = make_scene("two_layer.toml", {});
    const double dt = probe->dt();
    const double bound = 2 * h / (2 / rho * dt * dt);  // omega dt = 2
    const std::string d = num(factor * bound);
    auto sim = make_scene("two_layer.toml", {"interaction[0].Dn=" + d, "interaction[0].Dt=" + d,
                                             "interaction[0].force_limit=false"});
    bool threw = false;
    try {
      run_until(*sim, 0.05);
    } catch (const SimulationError&) {
      threw = true;
    }
    std::printf("[no limit, two_layer] D = %.3g (%.1f x bound %.3g): %s\n", factor * bound, factor,
                bound, threw ? "unstable" : "completed");
    EXPECT_EQ(threw, factor > 1) << "D = " << factor << " x " << bound;
    if (!threw) {
      EXPECT_TRUE(finite(sim->energies()));
    }
  }
}

// The paper's Fig. 12 "no force limits" curve, at 100 um and 1 ppc for
// 12 us: where the limit never acts (1/D = 1e-2, 1e-4) K from pressure is
// the limited run's within 0.5 %; at 1/D = 1e-6 the run completes and K
// rises above the perfect interface's CSA value (measured 3371 against
// 3062 in this loop, 3330 with `mmpm run`; the limited run 2967), as the
// paper says ("K rises above the theoretical limit and keeps rising until
// the calculations become unstable"); at 1/D = 1e-7 (omega dt = 4.3 by the
// bound above) it goes unstable. Before the tangent fix (mm_normals.hpp
// resolved_opening_squared) every one of these runs stopped as unstable
// within a few steps (docs/interface_validation.md, Finding 3).
TEST(ValidationInterface, SphereInCubeWithoutForceLimit) {
  const std::vector<std::string> no_limit = {"interaction[0].force_limit=false"};
  for (const double D : {1e2, 1e4}) {
    const CubeRun free = run_cube(D, 0.1, 1, 0.012, no_limit), limited = run_cube(D, 0.1, 1, 0.012);
    std::printf("[cube no limit 1/D=%.0e] K_p %.1f (limited %.1f)\n", 1 / D, free.K_pressure,
                limited.K_pressure);
    EXPECT_TRUE(finite(free.e));
    EXPECT_NEAR(free.K_pressure / limited.K_pressure, 1.0, 0.005) << "D = " << D;
  }
  const CubeRun stiff = run_cube(1e6, 0.1, 1, 0.012, no_limit);
  std::printf("[cube no limit 1/D=1e-6] K_p %.1f  CSA(perfect) %.1f\n", stiff.K_pressure,
              csa(std::numeric_limits<double>::infinity()));
  EXPECT_TRUE(finite(stiff.e));
  EXPECT_GT(stiff.K_pressure, csa(std::numeric_limits<double>::infinity()));
  EXPECT_THROW(run_cube(1e7, 0.1, 1, 0.012, no_limit), SimulationError);
}

// A run's last step is shortened to land on end_time (Stepper::step_within).
// The force limit (§4.4) takes its decisions for the run's regular step
// (MMConfig::limit_dt): taken for the short step, whose f_lim is
// (dt / dt_short)^2 larger, they let go every direction the earlier steps
// held stuck, and the last row, the one summary.json reports, read other
// energies: sphere_in_cube at 2 ppc and D = 1e6 had its interface energy
// go from 0.00289 to 0.0164 mJ (limited directions 324 -> 120) in its last,
// short step. Here 100 um, 1 ppc, D = 1e4: two runs of 600 regular steps,
// then one regular step and one of 0.01 dt. Pass A reads the state at the
// start of the step, so the two must report the same limited directions
// (114) and the same interface energy (1e-12).
TEST(ValidationInterface, ShortLastStepKeepsTheStickDecisions) {
  const std::vector<std::string> cube = {
      "interaction[0].Dn=1e4", "interaction[0].Dt=1e4",        "grid.cell=[0.1,0.1,0.1]",
      "grid.cells=[13,13,13]", "body[0].particles_per_cell=1", "body[1].particles_per_cell=1"};
  auto regular = make_scene("sphere_in_cube.toml", cube),
       shortened = make_scene("sphere_in_cube.toml", cube);
  for (int k = 0; k < 600; ++k) regular->step(), shortened->step();
  regular->step();
  shortened->step_within(shortened->time() + 0.01 * shortened->dt());
  const long limited = regular->counters().force_limited_nodes;
  std::printf("[short last step] limited %ld / %ld, interface energy %.9g / %.9g\n", limited,
              shortened->counters().force_limited_nodes, regular->energies().interface,
              shortened->energies().interface);
  EXPECT_GT(limited, 0);
  EXPECT_EQ(shortened->counters().force_limited_nodes, limited);
  EXPECT_NEAR(shortened->energies().interface / regular->energies().interface, 1.0, 1e-12);
}

// 100 um and 50 um cells, 2 particles per cell per direction, at 1/D = 1e-6 (near
// perfect), 1e-4 (transition) and 1e-2 (nearly debonded): both K within 5 % of CSA at
// 50 um, and at 1/D = 1e-4 the 50 um error is smaller than the 100 um error.
void sphere_refinement(double inv) {
  const double exact = csa(1 / inv);
  const CubeRun c = run_cube(1 / inv, 0.1, 2, 0.015), f = run_cube(1 / inv, 0.05, 2, 0.015);
  std::printf("[cube 1/D=%.0e] 100um: K_e %.1f K_p %.1f | 50um: K_e %.1f K_p %.1f | CSA %.1f\n",
              inv, c.K_energy, c.K_pressure, f.K_energy, f.K_pressure, exact);
  EXPECT_NEAR(f.K_energy / exact, 1.0, 0.05) << "1/D = " << inv;
  EXPECT_NEAR(f.K_pressure / exact, 1.0, 0.05) << "1/D = " << inv;
  if (inv == 1e-4) {
    EXPECT_LT(std::abs(f.K_energy / exact - 1), std::abs(c.K_energy / exact - 1));
  }
}

// USL with linear shapes at a static interface (docs/validation.md §3.5,
// "Light nodes: the whole force, and where it is held"). A field lighter than
// m_L at a node (USL's light-node mass, 0.5 m_p at cfl 0.5 with linear
// shapes) took only m / m_L of its internal force into the momentum, but all
// of its interface force, and the rest of the internal force reached the
// particles through dvel even where a support or a stuck partner held the
// node: a particle-velocity mode at the interface and the symmetry planes
// that the PIC fraction never removed. Checked against the same scene under
// MUSL (which has no light nodes) at h = 0.1 mm (sphere, 0.02 ms, cfl 0.5)
// and h = 0.25 mm (two_layer_mid, 0.8 ms, cfl 0.7). Before (2026-12-06,
// 56d2652): sphere K / U = 1.7e-2 and U +3.2 % of MUSL's, two-layer K / U =
// 4.1e-3 and U_int -39 %. After: K / U 7e-11 and 3e-10, U +0.44 % and U_int
// +0.34 % (USL's own difference: uGIMP under USL reads U +0.46 % on the
// sphere). Tolerances: K / U < 1e-7 (MUSL's own 2e-8 and 3e-10), U and
// U_int within 1 %.
TEST(ValidationInterface, StaticInterfaceUnderUslWithLinearShapesHoldsStill) {
  struct Case {
    const char* scene;
    const char* cfl;
    double t_end;
  };
  for (const Case c :
       {Case{"sphere_in_cube.toml", "0.5", 0.02}, Case{"two_layer_mid.toml", "0.7", 0.8}}) {
    Energies e[2];
    for (int usl = 0; usl < 2; ++usl) {
      auto sim =
          make_scene(c.scene, {"grid.shape=\"linear\"", std::string("simulation.cfl=") + c.cfl,
                               usl ? "simulation.scheme=\"USL\"" : "simulation.scheme=\"MUSL\""});
      run_until(*sim, c.t_end);
      e[usl] = sim->energies();
    }
    const double U = e[1].strain + e[1].interface;
    std::printf("%s: USL K / U = %.3e, U %.6g vs MUSL %.6g, U_int %.6g vs %.6g\n", c.scene,
                e[1].kinetic / U, e[1].strain, e[0].strain, e[1].interface, e[0].interface);
    EXPECT_LT(e[1].kinetic / U, 1e-7) << c.scene;
    EXPECT_NEAR(e[1].strain / e[0].strain, 1.0, 0.01) << c.scene;
    EXPECT_NEAR(e[1].interface / e[0].interface, 1.0, 0.01) << c.scene;
  }
}

TEST(ValidationInterfaceLong, SphereInCubeBulkModulusRefinement) {
  MMPM_LONG_TEST();
  for (double inv : {1e-4, 1e-2}) sphere_refinement(inv);
}

// The transition region of the paper's Fig. 12 (1/D = 1e-6 mm/MPa): the
// force limit switches node directions between force and stick every few
// steps and the energy-based K drifts (8.1 % high at 50 um, 13 % at 100 um;
// docs/interface_validation.md, findings 1-2).
TEST(ValidationInterfaceLong, SphereInCubeTransitionRegion) {
  MMPM_LONG_TEST();
  MMPM_KNOWN_LIMITATION(
      "force-limit switching at D A ~ 2 m_red / dt^2: K from energy 8.1 % high at 50 um");
  sphere_refinement(1e-6);
}

// Two bars 1 x 0.5 mm (E = 1e3 MPa, rho = 1e-3, nu = 0), h = 0.25, 2
// particles per cell, linear shapes, joined on the grid line x = 1 by an
// imperfect interface, no damping, MUSL with pure FLIP
// (docs/interface_validation.md Finding 14); `keys` (the law's, and any blocks
// after it) end the [[interaction]] table.
std::string undamped_bars_scene(const std::string& keys) {
  return R"(
[simulation]
dimension = 2
plane = "stress"
thickness = 1.0
end_time = 3.0
cfl = 0.5
flip = 1.0
scheme = "MUSL"
[grid]
origin = [-1.0, -1.0]
cell = [0.25, 0.25]
cells = [16, 10]
shape = "linear"
[[material]]
name = "a"
type = "isotropic"
density = 1.0e-3
E = 1.0e3
nu = 0.0
[[material]]
name = "b"
type = "isotropic"
density = 1.0e-3
E = 1.0e3
nu = 0.0
[[body]]
name = "A"
material = "a"
shape = "box"
min = [0.0, 0.0]
max = [1.0, 0.5]
particles_per_cell = 2
[[body]]
name = "B"
material = "b"
shape = "box"
min = [1.0, 0.0]
max = [2.0, 0.5]
particles_per_cell = 2
[[interaction]]
materials = ["a", "b"]
law = "interface"
normal = "specified"
normal_vector = [1.0, 0.0]
)" + keys +
         "\n";
}

// (K + U + U_int) / E0 of a scene at each of `times` (ms, increasing); empty if
// the scene starts without energy.
std::vector<double> undamped_bars_energy(const std::string& scene,
                                         const std::vector<std::string>& overrides,
                                         const std::vector<double>& times) {
  auto sim = testing::make_from_text(scene, overrides);
  auto total = [&] {
    const Energies e = sim->energies();
    return e.kinetic + e.strain + e.interface;
  };
  const double start = total();
  EXPECT_GT(start, 0.0);
  std::vector<double> ratios;
  if (!(start > 0)) return ratios;
  for (double t : times) {
    run_until(*sim, t);
    ratios.push_back(total() / start);
  }
  return ratios;
}

// The bars with the law `law_keys` and `force_limit` as given, bar a starting at
// `velocity_a` and b at `velocity_b`. Requires (K + U + U_int) / E0, which the
// continuum keeps at 1, below 1 + `band` at each of 12 readings over 3 ms
// (24 000 steps) and within `band` of 1 at the end.
void expect_undamped_bars_keep_energy(const char* label, const std::string& law_keys,
                                      const std::string& velocity_a, const std::string& velocity_b,
                                      bool force_limit, double band,
                                      const std::string& extra_blocks = "") {
  const std::string scene =
      undamped_bars_scene("force_limit = " + std::string(force_limit ? "true" : "false") + "\n" +
                          law_keys + "\n" + extra_blocks);
  std::vector<double> times;
  for (int k = 1; k <= 12; ++k) times.push_back(0.25 * k);
  const std::vector<double> e = undamped_bars_energy(
      scene, {"body[0].velocity=" + velocity_a, "body[1].velocity=" + velocity_b}, times);
  ASSERT_EQ(e.size(), times.size());
  const double largest = *std::max_element(e.begin(), e.end()), last = e.back();
  std::printf("[undamped interface, %s] (K + U + U_int) / E0: largest %.4f, at 3 ms %.4f\n", label,
              largest, last);
  EXPECT_LT(largest, 1.0 + band) << label;
  EXPECT_NEAR(last, 1.0, band) << label;
}

// The bars of expect_undamped_bars_keep_energy, read every 0.01 ms: the mean of
// (K + U + U_int) / E0 over the third millisecond (100 readings) within `band`
// of 1. At ωΔt = 0.5 the reading itself swings (U_int is the start-of-step
// spring's; the explicit scheme's readings span 0.96-1.33 over 10 ms), so the
// mean over many periods is what tells growth or loss from that swing.
void expect_undamped_bars_mean_energy(const char* label, const std::string& law_keys, double band) {
  std::vector<double> times;
  for (int k = 201; k <= 300; ++k) times.push_back(0.01 * k);
  const std::vector<double> e =
      undamped_bars_energy(undamped_bars_scene(law_keys),
                           {"body[0].velocity=[0.1,0.0]", "body[1].velocity=[-0.1,0.0]"}, times);
  ASSERT_EQ(e.size(), times.size());
  double sum = 0;
  for (double v : e) sum += v;
  std::printf("[undamped interface, %s] (K + U + U_int) / E0, mean over 2-3 ms: %.4f\n", label,
              sum / 100);
  EXPECT_NEAR(sum / 100, 1.0, band) << label;
}

// The normal spring under the defaults (docs/interface_validation.md
// Finding 14): Dn = 100 MPa/mm (omega dt = 0.16), the bars closing at 0.1
// mm/ms, then Dn = 1000 (omega dt = 0.5). The opening reads the motion
// MUSL's strain reads (kernels/separation_shift.hpp) and the force limit
// leaves a spring this soft alone (kernels/mm_interface.hpp
// spring_beyond_one_step). Measured: largest / at 3 ms 1.03 / 1.03 (Dn =
// 100) and 1.20 / 1.09 (Dn = 1000); before, 3.19 at 3 ms and, at Dn =
// 1000, the energy check stopped the run at 0.1 ms. Required: within 10 %
// and 25 %.
TEST(ValidationInterface, UndampedInterfaceVibrationKeepsItsEnergy) {
  expect_undamped_bars_keep_energy("normal, Dn 100", "Dn = 100.0\nDt = 0.0", "[0.1,0.0]",
                                   "[-0.1,0.0]", true, 0.1);
  expect_undamped_bars_keep_energy("normal, Dn 1000", "Dn = 1000.0\nDt = 0.0", "[0.1,0.0]",
                                   "[-0.1,0.0]", true, 0.25);
}

// The tangential spring under the defaults: Dn perfect, Dt = 100 MPa/mm,
// the bars sliding along the interface at 0.1 mm/ms, every node's x
// velocity fixed: u = (0, u_y(x, t)), a one-dimensional shear vibration.
// (Free, the sliding pair has angular momentum and spins as a whole, 0.25
// rad by 3 ms, which the displacement separation against a fixed normal
// does not model: 4.6 E0, Finding 14.) Measured: largest / at 3 ms 1.04 /
// 1.04; before, 8.22 at 3 ms. Required: within 10 %.
TEST(ValidationInterface, UndampedInterfaceShearVibrationKeepsItsEnergy) {
  expect_undamped_bars_keep_energy(
      "tangential", "Dn = \"perfect\"\nDt = 100.0", "[0.0,0.1]", "[0.0,-0.1]", true, 0.1,
      "[[boundary]]\nwhere = { min = [-1.0, -1.0], max = [3.0, 1.5] }\nfix = [\"x\"]\n");
}

// The same bars with integration = "exact" (ALGORITHM §4.5, docs/multimaterial.md
// §11): the force k C(θ) (s - s*) + Δf keeps the sampled oscillator's energy under
// MPM's velocity-then-position update, and the exact spring reads the separation
// shift. Before (docs/interface_validation.md Finding 15) its force also landed the
// start-of-step velocity on s(Δt), a dashpot of k Δt / 3: 0.18 E0 at 0.25 ms and
// 0.000 from 1.5 ms on at Dn = 100; without the shift, 3.11 at 3 ms. Required: as
// the explicit scheme, within 10 % (Dn = 100, Dt = 100); at Dn = 1000, where
// single readings swing from 0.97 to 1.32 under either scheme over 10 ms, the
// mean over the third millisecond within 15 % of 1, for both schemes (mean
// 1.10 in `mmpm run` 10-ms runs, windows of 2 ms: explicit 1.096-1.128, exact
// 1.101-1.139).
TEST(ValidationInterface, UndampedInterfaceVibrationKeepsItsEnergyUnderExactIntegration) {
  const std::string exact = "\nintegration = \"exact\"";
  expect_undamped_bars_keep_energy("normal, exact, Dn 100", "Dn = 100.0\nDt = 0.0" + exact,
                                   "[0.1,0.0]", "[-0.1,0.0]", true, 0.1);
  expect_undamped_bars_mean_energy("normal, exact, Dn 1000", "Dn = 1000.0\nDt = 0.0" + exact, 0.15);
  expect_undamped_bars_mean_energy("normal, explicit, Dn 1000", "Dn = 1000.0\nDt = 0.0", 0.15);
  expect_undamped_bars_keep_energy(
      "tangential, exact", "Dn = \"perfect\"\nDt = 100.0" + exact, "[0.0,0.1]", "[0.0,-0.1]", true,
      0.1, "[[boundary]]\nwhere = { min = [-1.0, -1.0], max = [3.0, 1.5] }\nfix = [\"x\"]\n");
}

// Without the force limit the opening reads x - x0 (the shift needs the
// limit, Stepper::shifts_separation) and the MUSL growth of Finding 14
// remains: 3.19 E0 (normal, Dn = 100) and 8.22 E0 (tangential, Dt = 100)
// after 3 ms. Required: within 10 %.
TEST(ValidationInterface, UndampedInterfaceWithoutForceLimitKeepsItsEnergy) {
  MMPM_KNOWN_LIMITATION(
      "without the force limit, MUSL with FLIP pumps energy into an undamped interface spring: "
      "K + U + U_int = 3.19 E0 (normal, Dn = 100) and 8.22 E0 (tangential, Dt = 100) after 3 ms");
  expect_undamped_bars_keep_energy("normal, no limit", "Dn = 100.0\nDt = 0.0", "[0.1,0.0]",
                                   "[-0.1,0.0]", false, 0.1);
  expect_undamped_bars_keep_energy(
      "tangential, no limit", "Dn = \"perfect\"\nDt = 100.0", "[0.0,0.1]", "[0.0,-0.1]", false, 0.1,
      "[[boundary]]\nwhere = { min = [-1.0, -1.0], max = [3.0, 1.5] }\nfix = [\"x\"]\n");
}

// ---------------------------------------------------------------------------
// (g) A stress wave through the interface (docs/validation.md §5c)
// ---------------------------------------------------------------------------
// inputs/wave_interface.toml: bars A (x 0-20) and B (x 20-40), 1 mm high,
// plane stress, nu = 0 (1D), A: E = 1e3, rho = 1e-3 (c = 1000 mm/ms, Z = 1),
// a traction on A's left face ramping to 0.01 MPa over 0.002 ms, the interface
// on the grid line x = 20, the scene's defaults (uGIMP, MUSL, pure FLIP, no
// damping, force limit on). The particle columns seeded at x = 10 (incident,
// then incident + reflected) and x_b in B (transmitted) are read every 0.001
// ms against (V 5c.2-5c.5), up to a time before any other reflection arrives.
struct WaveHistory {
  std::vector<double> time, incident, transmitted;  // mean displacements [mm]
};

// Mean displacement component c of the particles seeded within 0.1 mm of x0:
// the two particle columns either side of x0 at 2 particles per cell (h >= 0.125).
double column_mean_displacement(const Simulation& sim, double x0, int c) {
  const double mean = testing::seeded_mean_displacement(sim, 0, x0, 0.1, c);
  EXPECT_TRUE(std::isfinite(mean)) << "no particle column at x = " << x0;
  return mean;
}

// A pressure wave crosses the normal spring Dn (Dt perfect); a shear wave
// (traction along y, every node's x velocity fixed so that u = (0, u_y(x, t))
// as in the exact plane wave, the free faces' shear carried by the supports)
// crosses the tangential spring Dt (Dn perfect).
enum class Wave { pressure, shear };

// wave_interface.toml as a 3D scene: the bars 1 x 1 mm in cross-section, the
// grid 3 mm across in z as in y.
std::string wave_scene_in_3d(std::string text) {
  const std::vector<std::pair<std::string, std::string>> edits = {
      {"dimension = 2", "dimension = 3"},
      {"plane     = \"stress\"\n", ""},
      {"thickness = 1.0\n", ""},
      {"origin  = [-1.0, -1.0]", "origin  = [-1.0, -1.0, -1.0]"},
      {"min      = [0.0, 0.0]", "min      = [0.0, 0.0, 0.0]"},
      {"max      = [20.0, 1.0]", "max      = [20.0, 1.0, 1.0]"},
      {"min      = [20.0, 0.0]", "min      = [20.0, 0.0, 0.0]"},
      {"max      = [40.0, 1.0]", "max      = [40.0, 1.0, 1.0]"},
      {"normal_vector = [1.0, 0.0]", "normal_vector = [1.0, 0.0, 0.0]"},
      {"traction = [0.01, 0.0]", "traction = [0.01, 0.0, 0.0]"}};
  for (const auto& [from, to] : edits) {
    const std::size_t at = text.find(from);
    if (at == std::string::npos) throw std::runtime_error("wave_interface.toml: no '" + from + "'");
    text.replace(at, from.size(), to);
  }
  return text;
}

WaveHistory run_wave(Wave kind, double h, double D, double x_b, double t_end,
                     const std::vector<std::string>& extra = {}, int dimension = 2) {
  const std::string cells =
      std::to_string(std::lround(42.0 / h)) + "," + std::to_string(std::lround(3.0 / h));
  std::vector<std::string> ov = {
      dimension == 2 ? "grid.cell=[" + num(h) + "," + num(h) + "]"
                     : "grid.cell=[" + num(h) + "," + num(h) + "," + num(h) + "]",
      "grid.cells=[" + cells + (dimension == 2 ? "" : "," + std::to_string(std::lround(3.0 / h))) +
          "]"};
  std::string text = mmpm_test::read_text(input_path("wave_interface.toml"));
  if (dimension == 3) text = wave_scene_in_3d(text);
  if (kind == Wave::pressure) {
    ov.push_back("interaction[0].Dn=" + stiffness_value(D));
  } else {
    ov.insert(ov.end(), {"interaction[0].Dn=\"perfect\"", "interaction[0].Dt=" + stiffness_value(D),
                         "load[0].traction=[0.0,0.01]"});
    text += "\n[[boundary]]\nwhere = { min = [-1.0, -1.0], max = [41.0, 2.0] }\nfix = [\"x\"]\n";
  }
  ov.insert(ov.end(), extra.begin(), extra.end());
  auto sim = testing::make_from_text(text, ov);
  const int c = kind == Wave::pressure ? 0 : 1;
  WaveHistory w;
  for (int k = 1; 0.001 * k <= t_end + 1e-12; ++k) {
    run_until(*sim, 0.001 * k);
    w.time.push_back(sim->time());
    w.incident.push_back(column_mean_displacement(*sim, 10.0, c));
    w.transmitted.push_back(column_mean_displacement(*sim, x_b, c));
  }
  return w;
}

// The exact wave of (V 5c.2-5c.5): bars of density 1e-3 and moduli M_a, M_b
// (E for the pressure wave, G = E/2 for the shear wave at nu = 0), the
// interface's stiffness D along the wave's motion, the traction 0.01 MPa.
struct WaveSolution {
  double c_a, Z_a, c_b, Z_b, v0, ramp = 0.002;
  analytic::InterfaceWave law;
  WaveSolution(double M_a, double M_b, double D)
      : c_a(std::sqrt(M_a / 1e-3)),
        Z_a(1e-3 * c_a),
        c_b(std::sqrt(M_b / 1e-3)),
        Z_b(1e-3 * c_b),
        v0(0.01 / Z_a),
        law(analytic::interface_wave(Z_a, Z_b, D)) {}
  double W(double s, double tau) const {
    return analytic::lagged_ramp_displacement(s, v0, ramp, tau);
  }
  double transmitted(double t, double x_b) const {
    return law.transmission * W(t - 20.0 / c_a - (x_b - 20.0) / c_b, law.tau);
  }
  // At x = 10: the incident ramp, then its reflection from x = 20.
  double incident(double t) const {
    const double back = t - 30.0 / c_a;
    return W(t - 10.0 / c_a, 0.0) + W(back, 0.0) - Z_b / Z_a * law.transmission * W(back, law.tau);
  }
};

struct WaveErrors {
  double transmitted = 0, incident = 0;  // largest error / largest exact value
};
WaveErrors wave_errors(const WaveHistory& w, const WaveSolution& exact, double x_b) {
  double et = 0, mt = 0, ei = 0, mi = 0;
  for (std::size_t k = 0; k < w.time.size(); ++k) {
    const double ut = exact.transmitted(w.time[k], x_b), ui = exact.incident(w.time[k]);
    et = std::max(et, std::abs(w.transmitted[k] - ut)), mt = std::max(mt, std::abs(ut));
    ei = std::max(ei, std::abs(w.incident[k] - ui)), mi = std::max(mi, std::abs(ui));
  }
  return {et / mt, ei / mi};
}

// Equal bars (T0 = 1, tau = 1/(2 Dn)): Dn = perfect, 10, 100, 1000 at h =
// 0.25 and 0.125 mm; x_b = 30, 0.05 ms. Measured (transmitted / incident +
// reflected error, %): h 0.25: 0.86/0.17, 0.95/0.36, 1.14/0.32, 1.19/0.24; h
// 0.125: 0.39/0.10, 0.64/0.15, 0.58/0.14, 0.53/0.12 -- about first order, and
// the perfect interface's share shows most of it is the discretised wave (its
// front and the load's face), not the interface. The delay the interface
// adds, u_perfect - u_Dn at 0.05 ms against T0 (W(s, 0) - W(s, tau)), reads
// +0.85 / +0.08 / -11.3 % (h 0.25) and +0.33 / -0.18 / -5.0 % (h 0.125) for
// Dn = 10 / 100 / 1000: at Dn = 1000 (tau = 0.0005 ms, 4 steps) the
// stiff-interface bias of this file's header shortens it, and refining
// halves it.
// Required: transmitted within 1.5 % (h 0.25) and 0.8 % (h 0.125), each
// smaller by 0.75x on refining; incident + reflected within 0.5 % and 0.25 %;
// the delay within 1 % for Dn = 10 and 100, and at Dn = 1000 within 6 % at h
// = 0.125 with its error below 0.6x that at h = 0.25.
TEST(ValidationInterface, WaveThroughANormalInterfaceIsDelayedByTau) {
  const std::array<double, 4> stiffness = {analytic::kInf, 10.0, 100.0, 1000.0};
  const std::array<double, 2> cells = {0.25, 0.125};
  std::array<std::array<double, 4>, 2> transmitted{}, delay_error{};
  for (std::size_t r = 0; r < cells.size(); ++r) {
    const double h = cells[r];
    const WaveHistory perfect = run_wave(Wave::pressure, h, analytic::kInf, 30.0, 0.05);
    for (std::size_t i = 0; i < stiffness.size(); ++i) {
      const double Dn = stiffness[i];
      const WaveHistory w = i == 0 ? perfect : run_wave(Wave::pressure, h, Dn, 30.0, 0.05);
      const WaveSolution exact(1e3, 1e3, Dn);
      const WaveErrors e = wave_errors(w, exact, 30.0);
      transmitted[r][i] = e.transmitted;
      double delay = 0, want = 0;
      if (i > 0) {
        const double t = w.time.back();
        delay = perfect.transmitted.back() - w.transmitted.back();
        want = WaveSolution(1e3, 1e3, analytic::kInf).transmitted(t, 30.0) -
               exact.transmitted(t, 30.0);
        delay_error[r][i] = delay / want - 1.0;
      }
      std::printf(
          "[wave] h %.3f Dn %-8g transmitted %.2f %%, incident + reflected %.2f %%, delay %.4e "
          "(exact %.4e, %+.2f %%)\n",
          h, Dn, 100 * e.transmitted, 100 * e.incident, delay, want, 100 * delay_error[r][i]);
      EXPECT_LT(e.transmitted, r == 0 ? 0.015 : 0.008) << "h " << h << " Dn " << Dn;
      EXPECT_LT(e.incident, r == 0 ? 0.005 : 0.0025) << "h " << h << " Dn " << Dn;
      if (i == 1 || i == 2) {
        EXPECT_LT(std::abs(delay_error[r][i]), 0.01) << "h " << h << " Dn " << Dn;
      }
    }
  }
  for (std::size_t i = 0; i < stiffness.size(); ++i)
    EXPECT_LT(transmitted[1][i], 0.75 * transmitted[0][i]) << "Dn " << stiffness[i];
  EXPECT_LT(std::abs(delay_error[1][3]), 0.06);
  EXPECT_LT(std::abs(delay_error[1][3]), 0.6 * std::abs(delay_error[0][3]));
}

// Unequal bars, Dn = 100 and perfect, h = 0.25: B four times stiffer (E_b =
// 4000, Z_b = 2: T0 = 2/3, tau = 1/150 ms; x_b = 25 up to 0.035 ms, before
// B's far-end reflection returns) and four times softer (E_b = 250, Z_b =
// 0.5: T0 = 4/3, tau = 1/300 ms; x_b = 25 up to 0.05 ms). Measured
// (transmitted / incident + reflected, %): stiffer 1.20/0.39 (perfect
// 0.73/0.27), softer 1.39/0.28 (perfect 0.76/0.26). Required: within 1.6 %
// and 0.5 %.
TEST(ValidationInterface, WaveThroughAnInterfaceIntoAStifferOrASofterBar) {
  struct Case {
    double E_b, t_end;
  };
  for (const Case c : {Case{4000.0, 0.035}, Case{250.0, 0.05}}) {
    for (const double Dn : {100.0, analytic::kInf}) {
      const WaveHistory w =
          run_wave(Wave::pressure, 0.25, Dn, 25.0, c.t_end, {"material[1].E=" + num(c.E_b)});
      const WaveSolution exact(1e3, c.E_b, Dn);
      const WaveErrors e = wave_errors(w, exact, 25.0);
      std::printf(
          "[wave] E_b %g Dn %g (T0 %.3f, tau %.4g ms): transmitted %.2f %%, incident + "
          "reflected %.2f %%\n",
          c.E_b, Dn, exact.law.transmission, exact.law.tau, 100 * e.transmitted, 100 * e.incident);
      EXPECT_LT(e.transmitted, 0.016) << "E_b " << c.E_b << " Dn " << Dn;
      EXPECT_LT(e.incident, 0.005) << "E_b " << c.E_b << " Dn " << Dn;
    }
  }
}

// The same wave under every option that changes how the interface or the
// step is computed (Dn = 100 and 1000, h = 0.25, x_b = 30): linear, bspline2
// and bspline3 shapes, USL and USF, integration = "exact", separation =
// "extrapolated", no force limit, float, PIC. Measured transmitted errors
// 0.54-1.78 % (B-splines largest, extrapolated smallest; PIC 1.19 / 2.20 %
// at Dn 100 / 1000), incident + reflected 0.24-0.92 %. Required: within 2.5 %
// and 1 %.
TEST(ValidationInterface, WaveThroughAnInterfaceUnderEveryOption) {
  const std::vector<std::string> options = {"grid.shape=\"linear\"",
                                            "grid.shape=\"bspline2\"",
                                            "grid.shape=\"bspline3\"",
                                            "simulation.scheme=\"USL\"",
                                            "simulation.scheme=\"USF\"",
                                            "interaction[0].integration=\"exact\"",
                                            "interaction[0].separation=\"extrapolated\"",
                                            "interaction[0].force_limit=false",
                                            "simulation.precision=\"float\"",
                                            "simulation.flip=0.0"};
  for (const std::string& option : options) {
    for (const double Dn : {100.0, 1000.0}) {
      const WaveHistory w = run_wave(Wave::pressure, 0.25, Dn, 30.0, 0.05, {option});
      const WaveErrors e = wave_errors(w, WaveSolution(1e3, 1e3, Dn), 30.0);
      std::printf("[wave] %s Dn %g: transmitted %.2f %%, incident + reflected %.2f %%\n",
                  option.c_str(), Dn, 100 * e.transmitted, 100 * e.incident);
      EXPECT_LT(e.transmitted, 0.025) << option << " Dn " << Dn;
      EXPECT_LT(e.incident, 0.01) << option << " Dn " << Dn;
    }
  }
}

// The pressure wave in 3D (bars 1 x 1 mm, h = 0.25, 8 particles per cell,
// Dn = 100 and perfect): the same histories as the 2D runs -- measured
// identical to the last bit -- so also within 1.5 % and 0.5 % of the exact
// wave. Required: within 1e-9 of the 2D history (relative to its largest
// value) and within 1.5 % / 0.5 % of (V 5c.5).
TEST(ValidationInterface, WaveThroughAnInterfaceIn3DIsThe2DWave) {
  for (const double Dn : {100.0, analytic::kInf}) {
    const WaveHistory flat = run_wave(Wave::pressure, 0.25, Dn, 30.0, 0.05);
    const WaveHistory solid = run_wave(Wave::pressure, 0.25, Dn, 30.0, 0.05, {}, 3);
    ASSERT_EQ(flat.time.size(), solid.time.size());
    double largest = 0, differ = 0;
    for (std::size_t k = 0; k < flat.time.size(); ++k) {
      largest = std::max(largest, std::abs(flat.transmitted[k]));
      differ = std::max({differ, std::abs(flat.transmitted[k] - solid.transmitted[k]),
                         std::abs(flat.incident[k] - solid.incident[k])});
    }
    const WaveErrors e = wave_errors(solid, WaveSolution(1e3, 1e3, Dn), 30.0);
    std::printf(
        "[wave 3D] Dn %g: transmitted %.2f %%, incident + reflected %.2f %%, 3D - 2D %.2e "
        "of the largest\n",
        Dn, 100 * e.transmitted, 100 * e.incident, differ / largest);
    EXPECT_LT(differ, 1e-9 * largest) << "Dn " << Dn;
    EXPECT_LT(e.transmitted, 0.015) << "Dn " << Dn;
    EXPECT_LT(e.incident, 0.005) << "Dn " << Dn;
  }
}

// A shear wave through the tangential spring (c_s = sqrt(G/rho) = 707 mm/ms,
// Z = 0.707, tau = 1/(2 Dt)): Dt = perfect, 10, 100, 1000 at h = 0.25 and
// 0.125, x_b = 30 up to 0.07 ms (B's far-end reflection returns to x = 30 at
// 0.0707 ms). Measured (transmitted / incident + reflected, %) at h 0.25:
// 0.68/0.19, 0.72/0.32, 0.93/0.33, 1.13/0.19. Required: as the pressure wave,
// within 1.5 % and 0.5 % at h = 0.25, each transmitted error smaller by 0.75x
// at h = 0.125.
TEST(ValidationInterface, ShearWaveThroughATangentialInterfaceIsDelayedByTau) {
  const std::array<double, 4> stiffness = {analytic::kInf, 10.0, 100.0, 1000.0};
  for (const double Dt : stiffness) {
    const WaveSolution exact(500.0, 500.0, Dt);
    std::array<double, 2> transmitted{};
    for (const double h : {0.25, 0.125}) {
      const WaveErrors e = wave_errors(run_wave(Wave::shear, h, Dt, 30.0, 0.07), exact, 30.0);
      std::printf(
          "[shear wave] h %.3f Dt %g (tau %.4g ms): transmitted %.2f %%, incident + "
          "reflected %.2f %%\n",
          h, Dt, exact.law.tau, 100 * e.transmitted, 100 * e.incident);
      transmitted[h == 0.25 ? 0 : 1] = e.transmitted;
      EXPECT_LT(e.transmitted, h == 0.25 ? 0.015 : 0.008) << "h " << h << " Dt " << Dt;
      EXPECT_LT(e.incident, h == 0.25 ? 0.005 : 0.0025) << "h " << h << " Dt " << Dt;
    }
    EXPECT_LT(transmitted[1], 0.75 * transmitted[0]) << "Dt " << Dt;
  }
}

}  // namespace
}  // namespace mmpm
