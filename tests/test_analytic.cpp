// Tests of the closed-form reference solutions in tests/analytic.hpp.
//
// Three kinds of checks: (1) spot values derived by hand in docs/validation.md,
// (2) limits (D -> inf reproduces the perfect formulas, D -> 0 the debonded ones),
// (3) internal consistency: energy = P^2 C / 2, energy = pressure, and independent
// discretisations (1D finite elements / finite differences) of the same boundary-value
// problems converging to the closed forms.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>
#include <vector>

#include "analytic.hpp"

namespace an = mmpm::analytic;

namespace {

constexpr double kPi = std::numbers::pi;

// Paper materials (mm, ms, g => MPa).
constexpr double kEpoly = 2400.0, kNuPoly = 0.33;
constexpr double kEglass = 70000.0, kNuGlass = 0.25;
constexpr double kPhi = 0.1796;

double rel(double a, double b) {
  return std::abs(a - b) / std::abs(b);
}

// Composite Simpson rule on [a, b] with n (even) intervals.
double simpson(const std::function<double(double)>& f, double a, double b, int n) {
  const double h = (b - a) / n;
  double s = f(a) + f(b);
  for (int i = 1; i < n; ++i) s += f(a + i * h) * ((i % 2) ? 4.0 : 2.0);
  return s * h / 3.0;
}

// Banded symmetric positive-definite solve (half bandwidth w) by Gaussian elimination
// without pivoting; row i, column j (|i - j| <= w) kept in a band store.
struct Banded {
  int n, w;
  std::vector<double> a;  // row i, column j stored at i*(2w+1) + (j - i + w)
  Banded(int n_, int w_) : n(n_), w(w_), a(static_cast<size_t>(n_) * (2 * w_ + 1), 0.0) {}
  double& at(int i, int j) { return a[static_cast<size_t>(i) * (2 * w + 1) + (j - i + w)]; }
  void fix(int i, std::vector<double>& rhs, double value) {  // Dirichlet u_i = value
    for (int j = std::max(0, i - w); j <= std::min(n - 1, i + w); ++j) {
      if (j == i) continue;
      rhs[j] -= at(j, i) * value;
      at(j, i) = 0.0;
      at(i, j) = 0.0;
    }
    at(i, i) = 1.0;
    rhs[i] = value;
  }
  std::vector<double> solve(std::vector<double> b) {
    for (int k = 0; k < n; ++k) {
      for (int i = k + 1; i <= std::min(n - 1, k + w); ++i) {
        const double f = at(i, k) / at(k, k);
        if (f == 0.0) continue;
        for (int j = k; j <= std::min(n - 1, k + w); ++j) at(i, j) -= f * at(k, j);
        b[i] -= f * b[k];
      }
    }
    std::vector<double> x(n);
    for (int i = n - 1; i >= 0; --i) {
      double s = b[i];
      for (int j = i + 1; j <= std::min(n - 1, i + w); ++j) s -= at(i, j) * x[j];
      x[i] = s / at(i, i);
    }
    return x;
  }
};

}  // namespace

// ---------------------------------------------------------------------------
// §0 elastic constants
// ---------------------------------------------------------------------------

TEST(AnalyticElastic, HandValuesForThePaperPolymer) {
  // docs/validation.md §0: E = 2400, nu = 0.33.
  EXPECT_NEAR(an::bulk_modulus(kEpoly, kNuPoly), 2352.9412, 1e-4);
  EXPECT_NEAR(an::shear_modulus(kEpoly, kNuPoly), 902.2556, 1e-4);
  EXPECT_NEAR(an::constrained_modulus(kEpoly, kNuPoly), 3555.9487, 1e-4);
  EXPECT_NEAR(an::plane_strain_modulus(kEpoly, kNuPoly), 2693.3004, 1e-4);
  // Glass: K = 46666.667, G = 28000.
  EXPECT_NEAR(an::bulk_modulus(kEglass, kNuGlass), 46666.6667, 1e-4);
  EXPECT_NEAR(an::shear_modulus(kEglass, kNuGlass), 28000.0, 1e-9);
}

TEST(AnalyticElastic, ConstrainedModulusIsKPlusFourThirdsG) {
  for (double nu : {0.0, 0.2, 0.33, 0.45}) {
    const double E = 1000.0;
    EXPECT_NEAR(an::constrained_modulus(E, nu),
                an::bulk_modulus(E, nu) + 4.0 / 3.0 * an::shear_modulus(E, nu), 1e-9);
  }
}

TEST(AnalyticElastic, LateralStatesOrderAndDispatch) {
  const double E = kEpoly, nu = kNuPoly;
  const double e1 = an::axial_modulus(E, nu, an::Lateral::uniaxial_stress);
  const double e2 = an::axial_modulus(E, nu, an::Lateral::one_lateral_constraint);
  const double e3 = an::axial_modulus(E, nu, an::Lateral::confined);
  EXPECT_EQ(e1, E);
  EXPECT_EQ(e2, an::plane_strain_modulus(E, nu));
  EXPECT_EQ(e3, an::constrained_modulus(E, nu));
  EXPECT_LT(e1, e2);
  EXPECT_LT(e2, e3);
  // nu = 0: all three coincide.
  EXPECT_DOUBLE_EQ(an::axial_modulus(E, 0.0, an::Lateral::confined), E);
}

TEST(AnalyticElastic, TransverselyIsotropicPlaneStrainAxialModulus) {
  // Wood layers: EA 10000, ET 1000, nuA 0.2 -> 10000/(1 - 0.04*0.1) = 10040.161.
  EXPECT_NEAR(an::transverse_axial_plane_strain(10000.0, 1000.0, 0.2), 10040.1606, 1e-4);
  // Isotropic special case reduces to E/(1-nu^2).
  EXPECT_NEAR(an::transverse_axial_plane_strain(kEpoly, kEpoly, kNuPoly),
              an::plane_strain_modulus(kEpoly, kNuPoly), 1e-9);
}

TEST(AnalyticElastic, InterfaceComplianceLimits) {
  EXPECT_EQ(an::compliance_of(an::kInf), 0.0);
  EXPECT_EQ(an::compliance_of(0.0), an::kInf);
  EXPECT_DOUBLE_EQ(an::compliance_of(4.0), 0.25);
  EXPECT_THROW(an::compliance_of(-1.0), std::invalid_argument);
}

// ---------------------------------------------------------------------------
// §1 bars in series
// ---------------------------------------------------------------------------

TEST(AnalyticSeriesBars, HandValues) {
  // E1 = E2 = 1000 MPa, L1 = L2 = 10 mm, A = 2 mm^2, Dn = 50 MPa/mm, P = 4 N (docs §1).
  const auto r = an::series_bars(1000.0, 10.0, 1000.0, 10.0, 50.0, 2.0, 4.0);
  EXPECT_NEAR(r.compliance, 0.02, 1e-15);
  EXPECT_NEAR(r.elongation, 0.08, 1e-15);
  EXPECT_NEAR(r.stress, 2.0, 1e-15);
  EXPECT_NEAR(r.jump, 0.04, 1e-15);
  EXPECT_NEAR(r.U_bar1, 0.04, 1e-15);
  EXPECT_NEAR(r.U_bar2, 0.04, 1e-15);
  EXPECT_NEAR(r.U_interface, 0.08, 1e-15);
  EXPECT_NEAR(r.U_total, 0.16, 1e-15);
}

TEST(AnalyticSeriesBars, EnergyEqualsHalfPSquaredCompliance) {
  for (double Dn : {1e-3, 0.7, 31.0, 4.0e4, 1e9}) {
    const auto r = an::series_bars(2400.0, 7.0, 70000.0, 3.0, Dn, 1.5, 2.5);
    EXPECT_NEAR(r.U_total, 0.5 * 2.5 * 2.5 * r.compliance, 1e-12 * r.U_total) << Dn;
    EXPECT_NEAR(r.U_total, 0.5 * 2.5 * r.elongation, 1e-12 * r.U_total) << Dn;
  }
}

TEST(AnalyticSeriesBars, PerfectAndDebondedLimits) {
  const double perfect = 7.0 / (2400.0 * 1.5) + 3.0 / (70000.0 * 1.5);
  const auto p = an::series_bars(2400.0, 7.0, 70000.0, 3.0, an::kInf, 1.5, 1.0);
  EXPECT_DOUBLE_EQ(p.compliance, perfect);
  EXPECT_EQ(p.jump, 0.0);
  EXPECT_EQ(p.U_interface, 0.0);
  const auto s = an::series_bars(2400.0, 7.0, 70000.0, 3.0, 1e12, 1.5, 1.0);
  EXPECT_LT(rel(s.compliance, perfect), 1e-9);
  const auto d = an::series_bars(2400.0, 7.0, 70000.0, 3.0, 0.0, 1.5, 1.0);
  EXPECT_EQ(d.compliance, an::kInf);
}

TEST(AnalyticSeriesBars, ConfinedStripIsStifferByMOverE) {
  // Same geometry, perfect interface, one material: compliance ratio = M/E.
  const double E = kEpoly, nu = kNuPoly;
  const auto u = an::series_bars(E, 10.0, E, 10.0, an::kInf, 4.0, 1.0);
  const double M = an::constrained_modulus(E, nu);
  const auto c = an::series_bars(M, 10.0, M, 10.0, an::kInf, 4.0, 1.0);
  EXPECT_NEAR(u.compliance / c.compliance, M / E, 1e-12);
}

// ---------------------------------------------------------------------------
// §2 simple shear stack
// ---------------------------------------------------------------------------

TEST(AnalyticShearStack, HandValues) {
  // G1 = 500, H1 = 2, G2 = 1000, H2 = 4, Dt = 100, tau = 1 (docs §2).
  const auto r = an::shear_stack(500.0, 2.0, 1000.0, 4.0, 100.0, 1.0);
  EXPECT_NEAR(r.top_displacement, 0.018, 1e-15);
  EXPECT_NEAR(r.jump, 0.01, 1e-15);
  EXPECT_NEAR(r.gamma1, 0.002, 1e-15);
  EXPECT_NEAR(r.gamma2, 0.001, 1e-15);
  EXPECT_NEAR(r.U_strain_per_area, 0.004, 1e-15);
  EXPECT_NEAR(r.U_interface_per_area, 0.005, 1e-15);
  EXPECT_NEAR(r.U_per_area, 0.009, 1e-15);
}

TEST(AnalyticShearStack, EnergyIsHalfTractionTimesDisplacementAndLimits) {
  for (double Dt : {0.01, 1.0, 1e3, 1e8}) {
    const auto r = an::shear_stack(902.0, 3.0, 28000.0, 1.0, Dt, 0.37);
    EXPECT_NEAR(r.U_per_area, 0.5 * 0.37 * r.top_displacement, 1e-14 * r.U_per_area);
  }
  const auto p = an::shear_stack(902.0, 3.0, 28000.0, 1.0, an::kInf, 0.37);
  EXPECT_DOUBLE_EQ(p.top_displacement, 0.37 * (3.0 / 902.0 + 1.0 / 28000.0));
  EXPECT_EQ(p.U_interface_per_area, 0.0);
  EXPECT_EQ(an::shear_stack(902.0, 3.0, 28000.0, 1.0, 0.0, 0.37).top_displacement, an::kInf);
}

// ---------------------------------------------------------------------------
// §3 vibration, block stiffness, gravity
// ---------------------------------------------------------------------------

TEST(AnalyticVibration, HandValues) {
  // E = 2400 MPa, rho = 1.2e-3 g/mm^3: c = sqrt(2e6) = 1414.2136 mm/ms; L = 10 mm.
  const double c = an::wave_speed(2400.0, 1.2e-3);
  EXPECT_NEAR(c, 1414.21356, 1e-5);
  EXPECT_NEAR(an::fixed_free_period(10.0, c), 0.0282843, 1e-7);
  EXPECT_NEAR(an::fixed_free_omega(1, 10.0, c), 222.1441, 1e-4);
  EXPECT_NEAR(an::fixed_free_omega(2, 10.0, c), 3.0 * 222.1441, 3e-4);
  // v0 = 1 mm/ms (= 1 m/s): sine amplitude 2Lv0/(pi c) = 4.50158e-3 mm, uniform v0 L/c.
  EXPECT_NEAR(an::fixed_free_sine_tip_amplitude(1.0, 10.0, c), 4.50158e-3, 1e-8);
  EXPECT_NEAR(an::fixed_free_uniform_tip_amplitude(1.0, 10.0, c), 7.07107e-3, 1e-8);
}

TEST(AnalyticVibration, UniformVelocityTriangleWaveEqualsModalSeries) {
  const double v0 = 0.5, L = 12.0, c = 1500.0;
  const double T = an::fixed_free_period(L, c),
               amp = an::fixed_free_uniform_tip_amplitude(v0, L, c);
  for (double f : {0.05, 0.25, 0.4, 0.5, 0.63, 0.75, 0.9, 1.3}) {
    const double t = f * T;
    EXPECT_NEAR(an::fixed_free_uniform_tip(v0, L, c, t),
                an::fixed_free_uniform_tip_series(v0, L, c, t, 4000), 2e-4 * amp)
        << "t/T = " << f;
  }
  EXPECT_NEAR(an::fixed_free_uniform_tip(v0, L, c, 0.25 * T), amp, 1e-15);
  EXPECT_NEAR(an::fixed_free_uniform_tip(v0, L, c, 0.75 * T), -amp, 1e-15);
}

TEST(AnalyticVibration, SineModeEnergyBalance) {
  // Max strain energy (t = T/4) equals the initial kinetic energy rho A v0^2 L / 4.
  const double E = 2400.0, rho = 1.2e-3, L = 10.0, A = 2.0, v0 = 0.8;
  const double c = an::wave_speed(E, rho), T = an::fixed_free_period(L, c);
  const double dx = 1e-6;
  auto strain = [&](double x) {
    return (an::fixed_free_sine_displacement(v0, L, c, x + dx, 0.25 * T) -
            an::fixed_free_sine_displacement(v0, L, c, x - dx, 0.25 * T)) /
           (2.0 * dx);
  };
  const double U =
      simpson([&](double x) { return 0.5 * E * A * strain(x) * strain(x); }, 0.0, L, 400);
  EXPECT_NEAR(U, rho * A * v0 * v0 * L / 4.0, 1e-6 * U);
  EXPECT_NEAR(an::fixed_free_sine_displacement(v0, L, c, L, 0.25 * T),
              an::fixed_free_sine_tip_amplitude(v0, L, c), 1e-15);
}

TEST(AnalyticVibration, FiniteDifferenceWaveEquationAgrees) {
  // Leapfrog on u_tt = c^2 u_xx, u(0)=0, u_x(L)=0 (mirror ghost node).
  const double L = 10.0, c = 1414.2, v0 = 1.0;
  const int N = 400;
  const double h = L / N;
  auto run = [&](bool sine, double courant, double t_end, std::vector<double>& tip_t,
                 std::vector<double>& tip_u) {
    const double dt = courant * h / c;
    std::vector<double> u(N + 1, 0.0), v(N + 1, 0.0), a(N + 1, 0.0);
    for (int i = 1; i <= N; ++i) v[i] = sine ? v0 * std::sin(kPi * i * h / (2.0 * L)) : v0;
    const int steps = static_cast<int>(std::round(t_end / dt));
    for (int s = 0; s < steps; ++s) {
      for (int i = 1; i <= N; ++i) u[i] += dt * v[i];  // v holds v^{n+1/2}
      for (int i = 1; i < N; ++i) a[i] = c * c * (u[i + 1] - 2.0 * u[i] + u[i - 1]) / (h * h);
      a[N] = c * c * 2.0 * (u[N - 1] - u[N]) / (h * h);
      for (int i = 1; i <= N; ++i) v[i] += dt * a[i];
      tip_t.push_back((s + 1) * dt);
      tip_u.push_back(u[N]);
    }
  };
  const double T = an::fixed_free_period(L, c);
  {  // sine initial velocity: amplitude and period
    std::vector<double> t, u;
    run(true, 0.5, T, t, u);
    double umax = 0.0;
    for (double x : u) umax = std::max(umax, x);
    EXPECT_NEAR(umax, an::fixed_free_sine_tip_amplitude(v0, L, c), 1e-3 * umax);
    // First downward zero crossing at T/2.
    double tz = 0.0;
    for (size_t k = 1; k < u.size(); ++k)
      if (u[k - 1] > 0.0 && u[k] <= 0.0) {
        tz = t[k - 1] + (t[k] - t[k - 1]) * u[k - 1] / (u[k - 1] - u[k]);
        break;
      }
    EXPECT_NEAR(tz, 0.5 * T, 2e-3 * T);
  }
  {  // uniform initial velocity: triangle wave (Courant 1 is exact for this scheme)
    std::vector<double> t, u;
    run(false, 1.0, 1.5 * T, t, u);
    const double amp = an::fixed_free_uniform_tip_amplitude(v0, L, c);
    double worst = 0.0;
    for (size_t k = 0; k < u.size(); ++k)
      worst = std::max(worst, std::abs(u[k] - an::fixed_free_uniform_tip(v0, L, c, t[k])));
    EXPECT_LT(worst, 0.01 * amp);
  }
}

TEST(AnalyticBlock, StiffnessHandValues) {
  // E = 2400, nu = 0.33, A = 4 mm^2 (4 mm wide, 1 mm thick), L = 20 mm (docs §3).
  const double E = kEpoly, nu = kNuPoly;
  EXPECT_NEAR(
      an::block_stiffness(an::axial_modulus(E, nu, an::Lateral::uniaxial_stress), 4.0, 20.0), 480.0,
      1e-12);
  EXPECT_NEAR(
      an::block_stiffness(an::axial_modulus(E, nu, an::Lateral::one_lateral_constraint), 4.0, 20.0),
      538.66, 1e-2);
  EXPECT_NEAR(an::block_stiffness(an::axial_modulus(E, nu, an::Lateral::confined), 4.0, 20.0),
              711.19, 1e-2);
}

TEST(AnalyticGravity, HandValues) {
  // rho = 1.2e-3 g/mm^3, g = 9.81e-3 mm/ms^2, h = 100 mm, E = 2400 MPa (docs §3).
  const double rho = 1.2e-3, g = 9.81e-3, h = 100.0, E = 2400.0;
  EXPECT_NEAR(an::gravity_stress_yy(rho, g, h, 0.0), -1.1772e-3, 1e-12);
  EXPECT_NEAR(an::gravity_stress_yy(rho, g, h, h), 0.0, 1e-18);
  EXPECT_NEAR(an::gravity_top_displacement(rho, g, h, E), -2.4525e-5, 1e-12);
  EXPECT_NEAR(an::gravity_displacement(rho, g, h, E, h), -2.4525e-5, 1e-12);
}

TEST(AnalyticGravity, FiniteElementColumnAndEnergy) {
  // 1D linear FE with consistent body-force loads is nodally exact for this ODE.
  const double rho = 2.5e-3, g = 9.81e-3, h = 37.0, E = 3555.9, A = 3.0;
  const int n = 50;
  const double le = h / n, ke = E * A / le, q = -rho * g * A;  // load per length [N/mm]
  Banded K(n + 1, 1);
  std::vector<double> f(n + 1, 0.0);
  for (int e = 0; e < n; ++e) {
    K.at(e, e) += ke;
    K.at(e + 1, e + 1) += ke;
    K.at(e, e + 1) -= ke;
    K.at(e + 1, e) -= ke;
    f[e] += 0.5 * q * le;
    f[e + 1] += 0.5 * q * le;
  }
  K.fix(0, f, 0.0);
  const auto u = K.solve(f);
  double W = 0.0;
  for (int i = 0; i <= n; ++i) {
    EXPECT_NEAR(u[i], an::gravity_displacement(rho, g, h, E, i * le),
                1e-9 * std::abs(an::gravity_top_displacement(rho, g, h, E)));
  }
  // Work of gravity = 2 * strain energy (Clapeyron).
  W = simpson([&](double y) { return -rho * g * A * an::gravity_displacement(rho, g, h, E, y); },
              0.0, h, 100);
  EXPECT_NEAR(an::gravity_strain_energy(rho, g, h, E, A), 0.5 * W, 1e-10 * W);
}

// ---------------------------------------------------------------------------
// §4 double lap shear
// ---------------------------------------------------------------------------

namespace {
an::DlsMaterials classical() {
  an::DlsMaterials m;
  m.G_c = m.G_o = an::kInf;
  return m;
}
}  // namespace

TEST(AnalyticDls, ClassicalPerfectHandValue) {
  // Rigid-in-shear adherends, perfect interface: k = 2 / (31.6667e-4) = 12000/19 N/mm.
  EXPECT_NEAR(an::dls_stiffness(an::kInf, {}, classical()), 12000.0 / 19.0, 1e-9);
}

TEST(AnalyticDls, GeneralizedPerfectHandValue) {
  // docs §4.6: c = 1/1000, beta = sqrt(0.3), Delta = 34.70957e-4 mm -> k = 576.21 N/mm.
  const auto r = an::DlsShearLag({}, {}, an::kInf).result();
  EXPECT_NEAR(r.beta, std::sqrt(0.3), 1e-12);
  EXPECT_NEAR(r.displacement, 34.70957e-4, 1e-9);
  EXPECT_NEAR(r.k, 576.21, 0.01);
  EXPECT_EQ(r.U_interface, 0.0);
}

TEST(AnalyticDls, ClassicalHandValueAtUnitCompliance) {
  // docs §4.6: 1/Dt = 1 mm/MPa, G = inf: Delta = 0.0439949 mm -> k = 45.4599 N/mm.
  const auto r = an::DlsShearLag({}, classical(), 1.0).result();
  EXPECT_NEAR(r.displacement, 0.0439949, 2e-7);
  EXPECT_NEAR(r.k, 45.4599, 2e-4);
}

TEST(AnalyticDls, LimitsInDt) {
  const double k0 = an::dls_stiffness(an::kInf);
  EXPECT_LT(rel(an::dls_stiffness(1e12), k0), 1e-8);
  EXPECT_EQ(an::dls_stiffness(0.0), 0.0);
  // Dt -> 0: uniform shear tau = P/(2L) on both interfaces, k -> 2 L Dt * depth.
  for (double Dt : {1e-4, 1e-6}) EXPECT_NEAR(an::dls_stiffness(Dt) / (2.0 * 25.0 * Dt), 1.0, 3e-3);
  // Very stiff shear-rigid limit reproduces the classical perfect value.
  EXPECT_LT(rel(an::dls_stiffness(1e14, {}, classical()), 12000.0 / 19.0), 1e-6);
  // Monotonic decrease with 1/Dt.
  double prev = k0;
  for (double c = 0.05; c <= 1.0 + 1e-12; c += 0.05) {
    const double k = an::dls_stiffness(1.0 / c);
    EXPECT_LT(k, prev) << c;
    prev = k;
  }
}

TEST(AnalyticDls, FieldBoundaryConditionsAndEquilibrium) {
  for (double Dt : {0.5, 3.0, 50.0, 2000.0}) {
    const an::DlsShearLag s({}, {}, Dt);
    const double P = s.load_per_depth();
    EXPECT_NEAR(s.N_outer(0.0), 0.0, 1e-12) << Dt;
    EXPECT_NEAR(s.N_outer(25.0), 0.5 * P, 1e-12) << Dt;
    EXPECT_NEAR(s.N_central(0.0), P, 1e-12);
    EXPECT_NEAR(s.N_central(25.0), 0.0, 1e-12);
    // Each interface transfers P/2.
    EXPECT_NEAR(simpson([&](double y) { return s.tau(y); }, 0.0, 25.0, 20000), 0.5 * P, 1e-8);
    // ODE residual N_o'' = beta^2 (N_o - N_inf) at interior points.
    const double b = s.beta(), hh = 1e-3;
    for (double y : {1.0, 7.3, 12.5, 20.0, 24.0}) {
      const double d2 = (s.N_outer(y + hh) - 2.0 * s.N_outer(y) + s.N_outer(y - hh)) / (hh * hh);
      EXPECT_NEAR(d2, b * b * (s.N_outer(y) - s.N_inf()), 1e-5 * b * b * P) << Dt << " " << y;
    }
  }
}

TEST(AnalyticDls, EnergyPartitionMatchesFieldIntegrals) {
  // U = P Delta / 2 (Clapeyron) must equal the sum of the energies integrated from the fields.
  for (double Dt : {0.8, 5.0, 40.0}) {
    const an::DlsGeometry g;
    const an::DlsMaterials m;
    const an::DlsShearLag s(g, m, Dt);
    const auto r = s.result();
    const double axial_bond = simpson(
        [&](double y) {
          const double No = s.N_outer(y), Nc = s.N_central(y);
          return Nc * Nc / (2.0 * m.E_c * g.t_c) + 2.0 * No * No / (2.0 * m.E_o * g.t_o);
        },
        0.0, g.L, 20000);
    const double shear = simpson([&](double y) { return s.tau(y) * s.tau(y); }, 0.0, g.L, 20000);
    const double U_int = shear / Dt;  // two interfaces x tau^2/(2 Dt)
    const double U_adh = shear * (g.t_o / (3.0 * m.G_o) + g.t_c / (6.0 * m.G_c));
    const double U_sum = axial_bond + s.free_end_energy() + U_int + U_adh;
    EXPECT_NEAR(U_sum, r.U, 1e-8 * r.U) << Dt;
    EXPECT_NEAR(U_int, r.U_interface, 1e-8 * r.U) << Dt;
    EXPECT_NEAR(U_adh, r.U_adherend_shear, 1e-8 * r.U) << Dt;
    EXPECT_NEAR(axial_bond + s.free_end_energy(), r.U_axial, 1e-8 * r.U) << Dt;
    EXPECT_NEAR(an::stiffness_from_energy(r.P, r.U), r.k, 1e-10 * r.k);
  }
}

TEST(AnalyticDls, DiscreteSpringChainModelConverges) {
  // Independent discretisation: linear bar elements for the central layer and the two outer
  // layers (lumped together), trapezoid-lumped shear springs of stiffness 2/c per length,
  // central end fixed, load P on the outer end. k_FE -> k_closed as O(h^2).
  const an::DlsGeometry g;
  const an::DlsMaterials m;
  for (double Dt : {0.5, 10.0, an::kInf}) {
    const an::DlsShearLag s(g, m, Dt);
    const double c = s.compliance_eff(), P = s.load_per_depth();
    const double h = 0.01;
    const int nb = static_cast<int>(std::round(g.L / h));       // bond elements
    const int ncf = static_cast<int>(std::round(g.end_c / h));  // central free elements
    const int nof = static_cast<int>(std::round(g.end_o / h));  // outer free elements
    // DOF numbering: central nodes 0..ncf-1 (free part), then bond nodes j=0..nb interleaved
    // (central, outer), then outer free nodes.
    const int n = ncf + 2 * (nb + 1) + nof;
    auto cdof = [&](int i) { return i < ncf ? i : ncf + 2 * (i - ncf); };  // i = 0..ncf+nb
    auto odof = [&](int j) {  // j = 0..nb+nof (outer node index from y = 0)
      return j <= nb ? ncf + 2 * j + 1 : ncf + 2 * (nb + 1) + (j - nb - 1);
    };
    Banded K(n, 2);
    std::vector<double> f(n, 0.0);
    const double kc = m.E_c * g.t_c / h, ko = 2.0 * m.E_o * g.t_o / h;
    auto add_bar = [&](int a, int b, double k) {
      K.at(a, a) += k;
      K.at(b, b) += k;
      K.at(a, b) -= k;
      K.at(b, a) -= k;
    };
    for (int i = 0; i < ncf + nb; ++i) add_bar(cdof(i), cdof(i + 1), kc);
    for (int j = 0; j < nb + nof; ++j) add_bar(odof(j), odof(j + 1), ko);
    for (int j = 0; j <= nb; ++j) {
      const double w = (j == 0 || j == nb) ? 0.5 * h : h;
      add_bar(cdof(ncf + j), odof(j), w * 2.0 / c);
    }
    f[odof(nb + nof)] = P;
    K.fix(cdof(0), f, 0.0);
    const auto u = K.solve(f);
    const double k_fe = P / u[odof(nb + nof)] * g.depth;
    EXPECT_NEAR(k_fe, s.result().k, 2e-4 * s.result().k) << Dt;
  }
}

TEST(AnalyticDls, ConsistentWithThePaperStatements) {
  // Paper §3: stiffness "changes by over a factor of five" for 1/Dt in [0, 1] and the
  // interface energy reaches 91% of the total at Dt = 1 MPa/mm (MPM and FEA results).
  const auto r0 = an::DlsShearLag({}, {}, an::kInf).result();
  const auto r1 = an::DlsShearLag({}, {}, 1.0).result();
  EXPECT_GT(r0.k / r1.k, 5.0);
  EXPECT_NEAR(r1.interface_fraction, 0.91, 0.01);
  // Stiffness is proportional to the out-of-plane depth.
  an::DlsGeometry g2;
  g2.depth = 2.5;
  EXPECT_NEAR(an::dls_stiffness(3.0, g2), 2.5 * an::dls_stiffness(3.0), 1e-10);
}

// ---------------------------------------------------------------------------
// §5 composite spheres assemblage
// ---------------------------------------------------------------------------

namespace {
struct Csa {
  double Ki = an::bulk_modulus(kEglass, kNuGlass);
  double Km = an::bulk_modulus(kEpoly, kNuPoly);
  double Gm = an::shear_modulus(kEpoly, kNuPoly);
};
}  // namespace

TEST(AnalyticCsa, HandValuesPerfectAndDebonded) {
  const Csa p;
  EXPECT_NEAR(an::csa_bulk_perfect(p.Ki, p.Km, p.Gm, kPhi), 3062.04, 0.01);
  EXPECT_NEAR(an::csa_bulk_void(p.Km, p.Gm, kPhi), 1428.54, 0.01);
  // The paper's volume fraction: (pi/6) 0.7^3 = 0.17959.
  EXPECT_NEAR(kPi / 6.0 * 0.343, kPhi, 1e-4);
}

TEST(AnalyticCsa, PerfectEqualsHashinShtrikmanLowerBoundForm) {
  const Csa p;
  for (double phi : {0.01, 0.1796, 0.4, 0.6}) {
    const double hs =
        p.Km + phi / (1.0 / (p.Ki - p.Km) + 3.0 * (1.0 - phi) / (3.0 * p.Km + 4.0 * p.Gm));
    EXPECT_NEAR(an::csa_bulk_perfect(p.Ki, p.Km, p.Gm, phi), hs, 1e-9 * hs) << phi;
  }
}

TEST(AnalyticCsa, LimitsInDn) {
  const Csa p;
  const double Kp = an::csa_bulk_perfect(p.Ki, p.Km, p.Gm, kPhi);
  const double Kv = an::csa_bulk_void(p.Km, p.Gm, kPhi);
  for (double a : {0.7, 700e-6}) {
    EXPECT_DOUBLE_EQ(an::csa_bulk(p.Ki, p.Km, p.Gm, kPhi, a, an::kInf), Kp);
    EXPECT_NEAR(an::csa_bulk(p.Ki, p.Km, p.Gm, kPhi, a, 0.0), Kv, 1e-9 * Kv);
    EXPECT_LT(rel(an::csa_bulk(p.Ki, p.Km, p.Gm, kPhi, a, 1e16), Kp), 1e-8);
    EXPECT_LT(rel(an::csa_bulk(p.Ki, p.Km, p.Gm, kPhi, a, 1e-12), Kv), 1e-8);
  }
  // Monotonic in Dn, bounded by the two limits.
  double prev = Kv;
  for (int e = 2; e >= -10; --e) {
    const double K = an::csa_bulk(p.Ki, p.Km, p.Gm, kPhi, 0.7, std::pow(10.0, -e));
    EXPECT_GT(K, prev);
    EXPECT_LT(K, Kp);
    prev = K;
  }
}

TEST(AnalyticCsa, DependsOnlyOnRadiusTimesDn) {
  // Nano (a = 700 nm) at Dn equals micro (a = 700 um) at Dn/1000: curves shift 3 decades.
  const Csa p;
  for (double D : {1e3, 1e5, 1e7, 1e9}) {
    EXPECT_NEAR(an::csa_bulk(p.Ki, p.Km, p.Gm, kPhi, 700e-6, D),
                an::csa_bulk(p.Ki, p.Km, p.Gm, kPhi, 0.7, D / 1000.0), 1e-9);
  }
}

TEST(AnalyticCsa, HandValueAtUnitAD) {
  // docs §5.5: a = 0.7, 1/Dn = 1e-4: Ke = 46666.67/(1 + 20) = 2222.22 -> K = 2328.73.
  const Csa p;
  EXPECT_NEAR(an::csa_equivalent_inclusion_bulk(p.Ki, 0.7, 1e4), 2222.222, 1e-3);
  EXPECT_NEAR(an::csa_bulk(p.Ki, p.Km, p.Gm, kPhi, 0.7, 1e4), 2328.73, 0.01);
}

TEST(AnalyticCsa, EnergyPressureAndInterfaceConsistency) {
  const Csa p;
  const double eps0 = 0.005;
  for (double D : {0.0, 1e2, 1e4, 1e6, an::kInf}) {
    const auto s = an::csa_solve(p.Ki, p.Km, p.Gm, kPhi, 0.7, D, eps0);
    const double K = an::csa_bulk(p.Ki, p.Km, p.Gm, kPhi, 0.7, D);
    EXPECT_NEAR(s.K_energy, K, 1e-10 * K) << D;
    EXPECT_NEAR(s.K_pressure, K, 1e-10 * K) << D;
    EXPECT_NEAR(s.B * s.b + s.C / (s.b * s.b), eps0 * s.b, 1e-15);  // outer displacement BC
    // Traction continuity and interface law.
    EXPECT_NEAR(3.0 * p.Ki * s.A, s.sigma_a, 1e-9 * std::abs(s.sigma_b));
    if (D != an::kInf && D != 0.0) {
      EXPECT_NEAR(s.jump * D, s.sigma_a, 1e-9 * std::abs(s.sigma_b));
    }
    if (D == an::kInf) {
      EXPECT_NEAR(s.jump, 0.0, 1e-15);
    }
    if (D == 0.0) {
      EXPECT_NEAR(s.sigma_a, 0.0, 1e-9 * std::abs(s.sigma_b));
    }
    EXPECT_NEAR(an::bulk_from_energy(s.U_total, 4.0 * kPi * std::pow(s.b, 3) / 3.0, eps0), K,
                1e-10 * K);
    EXPECT_NEAR(an::bulk_from_pressure(s.sigma_b, eps0), K, 1e-10 * K);
  }
}

TEST(AnalyticCsa, RadialFiniteElementsAgree) {
  // Independent check: spherically symmetric linear FE (2-point Gauss in r, weight 4 pi r^2),
  // a split node at r = a joined by a spring Dn 4 pi a^2, u(0) = 0, u(b) = eps0 b.
  const Csa p;
  const double Gi = an::shear_modulus(kEglass, kNuGlass);
  const double eps0 = 0.005;
  for (double a : {0.7, 700e-6}) {
    for (double invD : {1e-8, 1e-6, 1e-4, 1e-2}) {
      const double D = 1.0 / invD, b = a / std::cbrt(kPhi);
      const int ni = 400, nm = 600;
      const int n = (ni + 1) + (nm + 1);
      Banded K(n, 1);
      std::vector<double> f(n, 0.0);
      auto element = [&](int d0, double r0, double r1, double Kb, double G) {
        const double lam = Kb - 2.0 * G / 3.0;
        const double D11 = lam + 2.0 * G, D12 = 2.0 * lam, D22 = 4.0 * lam + 4.0 * G;
        const double le = r1 - r0, gp = 1.0 / std::sqrt(3.0);
        for (double xi : {-gp, gp}) {
          const double r = 0.5 * (r0 + r1) + 0.5 * le * xi, w = 0.5 * le * 4.0 * kPi * r * r;
          const double N[2] = {(r1 - r) / le, (r - r0) / le}, dN[2] = {-1.0 / le, 1.0 / le};
          for (int i = 0; i < 2; ++i)
            for (int j = 0; j < 2; ++j) {
              const double er_i = dN[i], et_i = N[i] / r, er_j = dN[j], et_j = N[j] / r;
              K.at(d0 + i, d0 + j) +=
                  w * (D11 * er_i * er_j + D12 * (er_i * et_j + et_i * er_j) + D22 * et_i * et_j);
            }
        }
      };
      for (int e = 0; e < ni; ++e) element(e, a * e / ni, a * (e + 1) / ni, p.Ki, Gi);
      for (int e = 0; e < nm; ++e)
        element(ni + 1 + e, a + (b - a) * e / nm, a + (b - a) * (e + 1) / nm, p.Km, p.Gm);
      const double ks = D * 4.0 * kPi * a * a;
      K.at(ni, ni) += ks;
      K.at(ni + 1, ni + 1) += ks;
      K.at(ni, ni + 1) -= ks;
      K.at(ni + 1, ni) -= ks;
      // Keep the matrix for the energy: U = 1/2 u.K.u computed from element energies is
      // equivalent to 1/2 * reaction * u_b; use the reaction from an unmodified copy.
      Banded K0 = K;
      K.fix(0, f, 0.0);
      K.fix(n - 1, f, eps0 * b);
      const auto u = K.solve(f);
      double reaction = 0.0;
      for (int j = n - 2; j <= n - 1; ++j) reaction += K0.at(n - 1, j) * u[j];
      const double U = 0.5 * reaction * eps0 * b;
      const double K_fe = an::bulk_from_energy(U, 4.0 * kPi * b * b * b / 3.0, eps0);
      const double K_an = an::csa_bulk(p.Ki, p.Km, p.Gm, kPhi, a, D);
      EXPECT_NEAR(K_fe, K_an, 2e-5 * K_an) << "a = " << a << " 1/D = " << invD;
      const auto s = an::csa_solve(p.Ki, p.Km, p.Gm, kPhi, a, D, eps0);
      EXPECT_NEAR(u[ni + 1] - u[ni], s.jump, 1e-4 * std::abs(s.jump) + 1e-15);
    }
  }
}

TEST(AnalyticCsa, ConsistentWithThePaperStatements) {
  // Paper §3: at Dt = Dn = 1e6 MPa/mm a nanocomposite is "near the plateau for a completely
  // debonded interface" and a microcomposite "near the theoretical limit for a perfect interface".
  const Csa p;
  const double Kp = an::csa_bulk_perfect(p.Ki, p.Km, p.Gm, kPhi);
  const double Kv = an::csa_bulk_void(p.Km, p.Gm, kPhi);
  const double micro = an::csa_bulk(p.Ki, p.Km, p.Gm, kPhi, 0.7, 1e6);
  const double nano = an::csa_bulk(p.Ki, p.Km, p.Gm, kPhi, 700e-6, 1e6);
  EXPECT_LT((Kp - micro) / (Kp - Kv), 0.01);
  EXPECT_LT((nano - Kv) / (Kp - Kv), 0.15);
}

// ---------------------------------------------------------------------------
// §5c  A stress wave through an imperfect interface
// ---------------------------------------------------------------------------

TEST(AnalyticWave, HandValuesAndLimits) {
  const auto equal = an::interface_wave(1.0, 1.0, 100.0);
  EXPECT_DOUBLE_EQ(equal.transmission, 1.0);
  EXPECT_DOUBLE_EQ(equal.tau, 0.005);
  const auto stiffer = an::interface_wave(1.0, 2.0, 100.0);
  EXPECT_DOUBLE_EQ(stiffer.transmission, 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(stiffer.tau, 1.0 / 150.0);
  EXPECT_EQ(an::interface_wave(1.0, 2.0, an::kInf).tau, 0.0);
  EXPECT_EQ(an::interface_wave(1.0, 2.0, 0.0).tau, an::kInf);
  // The Python twin (tools/analytic.py) prints 1.411260104448198e-4 for these.
  EXPECT_NEAR(an::lagged_ramp_displacement(0.02, 0.01, 0.002, 0.005), 1.411260104448198e-4, 1e-17);
  EXPECT_DOUBLE_EQ(an::lagged_ramp_displacement(0.02, 0.01, 0.002, 0.0), 1.9e-4);
  EXPECT_DOUBLE_EQ(an::lagged_ramp_displacement(0.001, 0.01, 0.002, 0.0), 0.5 * 5.0 * 1e-6);
  // Late in the wave the lag is a delay by tau: v0 (s - t_r/2 - tau).
  EXPECT_NEAR(an::lagged_ramp_displacement(0.2, 0.01, 0.002, 0.005), 0.01 * (0.2 - 0.001 - 0.005),
              1e-15);
  EXPECT_EQ(an::lagged_ramp_displacement(-0.1, 0.01, 0.002, 0.005), 0.0);
  EXPECT_EQ(an::lagged_ramp_displacement(0.1, 0.01, 0.002, an::kInf), 0.0);
}

// (V 5c.2-5c.6) against an independent discretisation: two 1D bars as lumped
// masses and springs (leapfrog at Courant number 1/2 in each bar: at 1 the
// interface spring on a half-mass end node exceeds the explicit bound), bar
// 1's last node and bar 2's first joined by the interface spring D (each with
// half a cell's mass), the ramped traction on bar 1's first node, bar 2's far
// end free. Cells 0.01 mm in bar 1 (c_2/c_1 times that in bar 2), 20 mm bars,
// the ramp 200 cells long. Measured: the displacements at x = 10 and x = 25
// within 1.0-1.9e-5 of the largest; required 1e-4.
TEST(AnalyticWave, MassSpringBarsAgree) {
  struct Case {
    double E2, D, t_end;
  };
  for (const Case k : {Case{1000.0, 100.0, 0.05}, Case{1000.0, 10.0, 0.05},
                       Case{4000.0, 100.0, 0.035}, Case{250.0, 1000.0, 0.05}}) {
    const double rho = 1e-3, E1 = 1000.0, L = 20.0, p = 0.01, t_r = 0.002;
    const double c1 = std::sqrt(E1 / rho), c2 = std::sqrt(k.E2 / rho);
    const double dx1 = 0.01, dt = 0.5 * dx1 / c1, dx2 = 2.0 * c2 * dt;
    const int n1 = int(std::lround(L / dx1)), n2 = int(std::lround(L / dx2));
    // Nodes 0..n1 of bar 1, then 0..n2 of bar 2.
    std::vector<double> u(std::size_t(n1 + n2 + 2), 0.0), v(u.size(), 0.0), m(u.size());
    for (int i = 0; i <= n1; ++i) m[std::size_t(i)] = rho * dx1 * (i == 0 || i == n1 ? 0.5 : 1.0);
    for (int j = 0; j <= n2; ++j)
      m[std::size_t(n1 + 1 + j)] = rho * dx2 * (j == 0 || j == n2 ? 0.5 : 1.0);
    const auto Z1 = rho * c1, Z2 = rho * c2;
    const auto law = an::interface_wave(Z1, Z2, k.D);
    const auto W = [&](double s, double tau) {
      return an::lagged_ramp_displacement(s, p / Z1, t_r, tau);
    };
    const std::size_t probe1 = std::size_t(std::lround(10.0 / dx1));
    const std::size_t probe2 = std::size_t(n1 + 1 + std::lround(5.0 / dx2));
    std::vector<double> f(u.size());
    double error = 0, largest = 0;
    const int steps = int(std::lround(k.t_end / dt));
    for (int n = 0; n < steps; ++n) {
      const double t = n * dt;
      std::fill(f.begin(), f.end(), 0.0);
      f[0] += p * std::min(t / t_r, 1.0);
      for (int i = 0; i < n1; ++i) {  // bar 1's elements
        const double s = E1 * (u[std::size_t(i + 1)] - u[std::size_t(i)]) / dx1;
        f[std::size_t(i)] += s, f[std::size_t(i + 1)] -= s;
      }
      for (int j = 0; j < n2; ++j) {  // bar 2's elements
        const std::size_t a = std::size_t(n1 + 1 + j);
        const double s = k.E2 * (u[a + 1] - u[a]) / dx2;
        f[a] += s, f[a + 1] -= s;
      }
      const double traction = k.D * (u[std::size_t(n1 + 1)] - u[std::size_t(n1)]);
      f[std::size_t(n1)] += traction, f[std::size_t(n1 + 1)] -= traction;
      for (std::size_t i = 0; i < u.size(); ++i) {
        v[i] += dt * f[i] / m[i];
        u[i] += dt * v[i];
      }
      const double time = (n + 1) * dt;
      const double back = time - (2 * L - 10.0) / c1;
      const double exact1 =
          W(time - 10.0 / c1, 0.0) + W(back, 0.0) - Z2 / Z1 * law.transmission * W(back, law.tau);
      const double exact2 = law.transmission * W(time - L / c1 - 5.0 / c2, law.tau);
      error = std::max({error, std::abs(u[probe1] - exact1), std::abs(u[probe2] - exact2)});
      largest = std::max({largest, std::abs(exact1), std::abs(exact2)});
    }
    std::printf("[mass-spring bars] E2 %g D %g: largest error %.2e of the largest displacement\n",
                k.E2, k.D, error / largest);
    EXPECT_LT(error, 1e-4 * largest) << "E2 " << k.E2 << " D " << k.D;
  }
}
