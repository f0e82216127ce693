// Closed-form and reference solutions for validating mmpm.
//
// Every function states its units (mm, ms, g  =>  N, MPa, mJ = N*mm) and the
// equation of docs/validation.md it implements, written "(V n.m)". The same
// formulas exist in Python in tools/analytic.py (figure scripts, tables).
//
// Interface stiffnesses D (MPa/mm) may be +infinity (perfect interface) or 0
// (debonded); the functions return the corresponding limits.
#pragma once

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

namespace mmpm::analytic {

inline constexpr double kInf = std::numeric_limits<double>::infinity();

/// Compliance 1/D (mm/MPa) of an interface stiffness D (MPa/mm); 1/inf = 0, 1/0 = inf.
inline double compliance_of(double D) {
  if (!(D >= 0.0)) throw std::invalid_argument("interface stiffness must be >= 0");
  return D == kInf ? 0.0 : (D == 0.0 ? kInf : 1.0 / D);
}

// ---------------------------------------------------------------------------
// §0  Isotropic elastic constants and lateral-constraint states
// ---------------------------------------------------------------------------

/// Bulk modulus K = E / (3(1-2nu))  [MPa]  (V 0.1)
inline double bulk_modulus(double E, double nu) {
  return E / (3.0 * (1.0 - 2.0 * nu));
}
/// Shear modulus G = E / (2(1+nu))  [MPa]  (V 0.1)
inline double shear_modulus(double E, double nu) {
  return E / (2.0 * (1.0 + nu));
}
/// Constrained (P-wave, oedometric) modulus M = E(1-nu)/((1+nu)(1-2nu)) = K + 4G/3  [MPa]  (V 0.2)
inline double constrained_modulus(double E, double nu) {
  return E * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu));
}
/// Plane-strain (one lateral strain zero) axial modulus E/(1-nu^2)  [MPa]  (V 0.3)
inline double plane_strain_modulus(double E, double nu) {
  return E / (1.0 - nu * nu);
}

/// Lateral state of a bar/strip/block loaded along one axis (V 0.4):
///  - uniaxial_stress:        both lateral stresses zero (1D bar; 2D plane stress with
///                            free sides; 3D with free sides)                     -> E
///  - one_lateral_constraint: one lateral strain zero, the other lateral stress zero
///                            (2D plane strain with free sides; 2D plane stress
///                            with roller sides)                                   -> E/(1-nu^2)
///  - confined:               both lateral strains zero (2D plane strain with roller
///                            sides; 3D with rollers on all sides)                 -> M
enum class Lateral { uniaxial_stress, one_lateral_constraint, confined };

/// Effective axial modulus for a lateral state  [MPa]  (V 0.4)
inline double axial_modulus(double E, double nu, Lateral s) {
  switch (s) {
    case Lateral::uniaxial_stress:
      return E;
    case Lateral::one_lateral_constraint:
      return plane_strain_modulus(E, nu);
    case Lateral::confined:
      return constrained_modulus(E, nu);
  }
  return E;
}

/// Transversely isotropic material, axis A along the load, loaded in 2D plane strain with
/// the free lateral direction in-plane and the out-of-plane (T) strain zero:
/// E_eff = E_A / (1 - nu_A^2 E_T/E_A)  [MPa]  (V 0.5).  nu_A = -eps_T/eps_A for an axial load.
inline double transverse_axial_plane_strain(double EA, double ET, double nuA) {
  return EA / (1.0 - nuA * nuA * ET / EA);
}

/// Longitudinal bar wave speed c = sqrt(modulus/rho)  [mm/ms = m/s]; modulus in MPa,
/// rho in g/mm^3 (V 3.1)
inline double wave_speed(double modulus, double rho) {
  return std::sqrt(modulus / rho);
}

// ---------------------------------------------------------------------------
// §1  Two bars in series joined by a normal imperfect interface (static)
// ---------------------------------------------------------------------------

struct SeriesBars {
  double compliance;      ///< C = L1/(E1 A) + L2/(E2 A) + 1/(Dn A)   [mm/N]   (V 1.3)
  double elongation;      ///< P C: end-to-end displacement             [mm]     (V 1.4)
  double stress;          ///< sigma = P/A                               [MPa]
  double jump;            ///< interface opening delta_n = sigma/Dn      [mm]     (V 1.2)
  double U_bar1, U_bar2;  ///< strain energies sigma^2 A L_i /(2 E_i)    [mJ]     (V 1.5)
  double U_interface;     ///< 1/2 Dn delta^2 A = sigma^2 A/(2 Dn)      [mJ]     (V 1.5)
  double U_total;         ///< = P^2 C / 2                               [mJ]     (V 1.6)
};

/// Two bars (axial moduli E1, E2 [MPa], lengths L1, L2 [mm], common cross-section A [mm^2];
/// in 2D A = width * thickness) under end load P [N], joined by a normal interface Dn
/// [MPa/mm] (inf = perfect). E_i are the *effective* axial moduli of (V 0.4): E for a 1D bar
/// or a plane-stress strip with free sides, E/(1-nu^2) for a plane-strain strip with free
/// sides, M for a laterally confined strip.  (V 1.1-1.6)
inline SeriesBars series_bars(double E1, double L1, double E2, double L2, double Dn, double A,
                              double P) {
  SeriesBars r{};
  const double cn = compliance_of(Dn);
  r.stress = P / A;
  r.compliance = L1 / (E1 * A) + L2 / (E2 * A) + cn / A;
  r.elongation = P * r.compliance;
  r.jump = r.stress * cn;
  r.U_bar1 = r.stress * r.stress * A * L1 / (2.0 * E1);
  r.U_bar2 = r.stress * r.stress * A * L2 / (2.0 * E2);
  r.U_interface = 0.5 * r.stress * r.stress * A * cn;
  r.U_total = r.U_bar1 + r.U_bar2 + r.U_interface;
  return r;
}

// ---------------------------------------------------------------------------
// §2  Two blocks in simple shear with a tangential interface
// ---------------------------------------------------------------------------

struct ShearStack {
  double top_displacement;      ///< tau (H1/G1 + H2/G2 + 1/Dt)          [mm]   (V 2.2)
  double jump;                  ///< tangential slip delta_t = tau/Dt    [mm]   (V 2.1)
  double gamma1, gamma2;        ///< engineering shear strains tau/G_i   [-]
  double U_strain_per_area;     ///< tau^2 (H1/G1 + H2/G2)/2             [mJ/mm^2 = N/mm] (V 2.3)
  double U_interface_per_area;  ///< tau^2/(2 Dt)                        [N/mm] (V 2.3)
  double U_per_area;            ///< = tau * top_displacement / 2        [N/mm] (V 2.3)
};

/// Block 1 (height H1 [mm], shear modulus G1 [MPa]) on a fixed base, block 2 (H2, G2) on
/// top, interface Dt [MPa/mm] between them, uniform shear traction tau [MPa] on the top
/// (complementary shear on the sides or periodic sides).  (V 2.1-2.3)
inline ShearStack shear_stack(double G1, double H1, double G2, double H2, double Dt, double tau) {
  ShearStack r{};
  const double ct = compliance_of(Dt);
  r.gamma1 = tau / G1;
  r.gamma2 = tau / G2;
  r.jump = tau * ct;
  r.top_displacement = tau * (H1 / G1 + H2 / G2 + ct);
  r.U_strain_per_area = 0.5 * tau * tau * (H1 / G1 + H2 / G2);
  r.U_interface_per_area = 0.5 * tau * tau * ct;
  r.U_per_area = r.U_strain_per_area + r.U_interface_per_area;
  return r;
}

// ---------------------------------------------------------------------------
// §3  Bar vibration, block stiffness, gravity settling
// ---------------------------------------------------------------------------

/// Angular frequency of mode n = 1, 2, ... of a fixed(x=0)-free(x=L) bar:
/// omega_n = (2n-1) pi c / (2L)  [rad/ms]  (V 3.3)
inline double fixed_free_omega(int n, double L, double c) {
  return (2.0 * n - 1.0) * std::numbers::pi * c / (2.0 * L);
}
/// Fundamental period T1 = 4L/c  [ms]  (V 3.4)
inline double fixed_free_period(double L, double c) {
  return 4.0 * L / c;
}

/// Tip amplitude for the initial velocity v(x,0) = v0 sin(pi x/(2L)), u(x,0) = 0:
/// u_tip,max = v0/omega_1 = 2 L v0/(pi c)  [mm]  (V 3.5)
inline double fixed_free_sine_tip_amplitude(double v0, double L, double c) {
  return 2.0 * L * v0 / (std::numbers::pi * c);
}
/// u(x,t) for the sine initial velocity: (v0/omega_1) sin(pi x/2L) sin(omega_1 t)  [mm]  (V 3.5)
inline double fixed_free_sine_displacement(double v0, double L, double c, double x, double t) {
  const double w = fixed_free_omega(1, L, c);
  return v0 / w * std::sin(std::numbers::pi * x / (2.0 * L)) * std::sin(w * t);
}

/// Tip amplitude for a uniform initial velocity v0 (u(x,0) = 0): v0 L / c  [mm]  (V 3.7)
inline double fixed_free_uniform_tip_amplitude(double v0, double L, double c) {
  return v0 * L / c;
}
/// Exact (d'Alembert) tip displacement for a uniform initial velocity v0: a triangle wave of
/// period 4L/c, u_tip = v0 t on [0, L/c], v0 (2L/c - t) on [L/c, 3L/c], v0 (t - 4L/c) on
/// [3L/c, 4L/c]  [mm]  (V 3.7)
inline double fixed_free_uniform_tip(double v0, double L, double c, double t) {
  const double T = fixed_free_period(L, c);
  const double tau = L / c;
  double s = std::fmod(t, T);
  if (s < 0.0) s += T;
  if (s <= tau) return v0 * s;
  if (s <= 3.0 * tau) return v0 * (2.0 * tau - s);
  return v0 * (s - T);
}
/// The same tip history as the modal series truncated to n_modes terms (V 3.6):
/// u_tip = (8 v0 L/(pi^2 c)) sum_n (-1)^(n+1) sin(omega_n t)/(2n-1)^2  [mm]
inline double fixed_free_uniform_tip_series(double v0, double L, double c, double t, int n_modes) {
  double s = 0.0;
  for (int n = 1; n <= n_modes; ++n) {
    const double k = 2.0 * n - 1.0;
    s += ((n % 2) ? 1.0 : -1.0) * std::sin(fixed_free_omega(n, L, c) * t) / (k * k);
  }
  return 8.0 * v0 * L / (std::numbers::pi * std::numbers::pi * c) * s;
}

/// Static axial stiffness of a block, k = E_eff A / L  [N/mm]; E_eff from (V 0.4),
/// A loaded area [mm^2] (2D: width * thickness), L length along the load [mm]  (V 3.8)
inline double block_stiffness(double E_eff, double A, double L) {
  return E_eff * A / L;
}

/// Gravity column (height h [mm], density rho [g/mm^3], gravity g [mm/ms^2], e.g. 9.81e-3)
/// on a base at y = 0: sigma_yy(y) = -rho g (h - y)  [MPa]  (V 3.9)
inline double gravity_stress_yy(double rho, double g, double h, double y) {
  return -rho * g * (h - y);
}
/// Settled vertical displacement u_y(y) = -(rho g / E_eff)(h y - y^2/2)  [mm]  (V 3.10)
inline double gravity_displacement(double rho, double g, double h, double E_eff, double y) {
  return -rho * g / E_eff * (h * y - 0.5 * y * y);
}
/// Settled top displacement u_y(h) = -rho g h^2 / (2 E_eff)  [mm]  (V 3.10)
inline double gravity_top_displacement(double rho, double g, double h, double E_eff) {
  return -rho * g * h * h / (2.0 * E_eff);
}
/// Strain energy of the settled column, rho^2 g^2 A h^3 / (6 E_eff)  [mJ]; A = cross-section
/// [mm^2]. Equals half the work of gravity (V 3.11).
inline double gravity_strain_energy(double rho, double g, double h, double E_eff, double A) {
  return rho * rho * g * g * A * h * h * h / (6.0 * E_eff);
}

// ---------------------------------------------------------------------------
// §4  Double lap shear (DLS): generalized shear lag with an imperfect interface
// ---------------------------------------------------------------------------

/// Symmetric three-layer DLS specimen (docs/validation.md §4.1 sketch):
/// a central layer (thickness t_c) loaded at its bottom end by P, two outer layers
/// (thickness t_o each) loaded at their top ends by P/2 each, bonded over length L by two
/// tangential interfaces Dt; the central layer extends end_c below the bond, the outer
/// layers end_o above it. Out-of-plane depth `depth` (2D thickness). Paper defaults.
struct DlsGeometry {
  double t_c = 1.0;    ///< central layer thickness [mm]
  double t_o = 1.0;    ///< each outer layer thickness [mm]
  double L = 25.0;     ///< bond length [mm]
  double end_c = 5.0;  ///< unbonded (free) length of the central layer [mm]
  double end_o = 5.0;  ///< unbonded (free) length of each outer layer [mm]
  double depth = 1.0;  ///< out-of-plane depth (2D thickness) [mm]
};

/// Layer properties along the bond: E = effective axial modulus (V 0.4/0.5), G = in-plane
/// shear modulus (G_A for grain along the bond). G = kInf gives the classical Volkersen
/// model with rigid-in-shear adherends.  [MPa]
struct DlsMaterials {
  double E_c = 10000.0, E_o = 10000.0;
  double G_c = 500.0, G_o = 500.0;
};

struct DlsResult {
  double P;               ///< total load (= sigma_c t_c depth)                    [N]
  double compliance_eff;  ///< c = 1/Dt + t_o/(3G_o) + t_c/(6G_c)                  [mm/MPa] (V 4.5)
  double beta;            ///< shear-lag parameter sqrt(S/c)                        [1/mm]   (V 4.7)
  double N_inf;           ///< outer-layer force far from the bond ends, per depth  [N/mm]   (V 4.8)
  double tau0, tauL;    ///< interface shear traction at y = 0 and y = L          [MPa]    (V 4.10)
  double displacement;  ///< relative displacement of the load points             [mm]     (V 4.12)
  double U;             ///< total energy = P * displacement / 2                  [mJ]     (V 4.13)
  double U_interface;   ///< interface energy (both interfaces)                   [mJ]     (V 4.14)
  double U_adherend_shear;  ///< adherend shear strain energy                         [mJ] (V 4.14)
  double U_axial;  ///< axial strain energy incl. free ends                  [mJ]     (V 4.15)
  double k;        ///< stiffness P^2/(2U)                                   [N/mm]   (V 4.16)
  double interface_fraction;  ///< U_interface / U
};

/// Shear-lag field solution of the DLS specimen. Fields are per unit depth; y runs along
/// the bond from the loaded end of the central layer (y = 0) to the loaded end of the outer
/// layers (y = L). sigma_c is the applied stress on the central layer's end [MPa].
class DlsShearLag {
 public:
  DlsShearLag(const DlsGeometry& g, const DlsMaterials& m, double Dt, double sigma_c = 2.0)
      : g_(g), m_(m), ct_(compliance_of(Dt)) {
    P_ = sigma_c * g.t_c;  // per unit depth [N/mm]
    S_ = 1.0 / (m.E_o * g.t_o) + 2.0 / (m.E_c * g.t_c);
    c_ = ct_ + g.t_o / (3.0 * m.G_o) + g.t_c / (6.0 * m.G_c);
    Ninf_ = P_ / (m.E_c * g.t_c) / S_;
    R_ = 0.5 * P_ - Ninf_;
    perfect_ = (c_ == 0.0);
    debonded_ = (c_ == kInf);
    beta_ = perfect_ ? kInf : (debonded_ ? 0.0 : std::sqrt(S_ / c_));
    x_ = beta_ * g.L;
  }

  double load_per_depth() const { return P_; }
  double beta() const { return beta_; }
  double N_inf() const { return Ninf_; }
  double compliance_eff() const { return c_; }

  /// Axial force per depth in ONE outer layer, N_o(y)  [N/mm]  (V 4.9)
  double N_outer(double y) const {
    if (perfect_) return (y <= 0.0) ? 0.0 : (y >= g_.L ? 0.5 * P_ : Ninf_);
    if (debonded_) throw std::domain_error("DLS: debonded interface carries no load");
    return Ninf_ + R_ * sinh_ratio(beta_ * y) - Ninf_ * sinh_ratio(beta_ * (g_.L - y));
  }
  /// Axial force per depth in the central layer, N_c = P - 2 N_o  [N/mm]  (V 4.2)
  double N_central(double y) const { return P_ - 2.0 * N_outer(y); }
  /// Interface shear traction tau(y) = dN_o/dy (same on both interfaces)  [MPa]  (V 4.10)
  double tau(double y) const {
    if (perfect_) throw std::domain_error("DLS: perfect interface has singular end tractions");
    if (debonded_) throw std::domain_error("DLS: debonded interface carries no load");
    return beta_ * (R_ * cosh_ratio(beta_ * y) + Ninf_ * cosh_ratio(beta_ * (g_.L - y)));
  }
  /// Displacement jump across each interface, tau/Dt  [mm]  (V 4.4)
  double jump(double y) const { return ct_ == 0.0 ? 0.0 : tau(y) * ct_; }

  DlsResult result() const {
    DlsResult r{};
    const double B = g_.depth;
    r.P = P_ * B;
    r.compliance_eff = c_;
    r.beta = beta_;
    r.N_inf = Ninf_;
    const double Eto = m_.E_o * g_.t_o, Etc = m_.E_c * g_.t_c;
    const double free_ends = P_ * g_.end_c / Etc + 0.5 * P_ * g_.end_o / Eto;  // (V 4.12)
    if (debonded_) {
      r.displacement = kInf;
      r.U = kInf;
      r.U_interface = kInf;
      r.k = 0.0;
      r.interface_fraction = 1.0;
      return r;
    }
    double int_No, ctau0, int_tau2;
    if (perfect_) {
      int_No = Ninf_ * g_.L;
      ctau0 = 0.0;
      int_tau2 = 0.0;  // only ever multiplied by zero compliances
      r.tau0 = r.tauL = kInf;
    } else {
      const double x = x_, b = beta_, L = g_.L;
      int_No = Ninf_ * L + (R_ - Ninf_) * std::tanh(0.5 * x) / b;  // (V 4.11)
      // c * tau(0) = sqrt(S c) (N_inf coth x + R / sinh x)        (V 4.10)
      ctau0 = std::sqrt(S_ * c_) * (Ninf_ / std::tanh(x) + R_ / std::sinh(x));
      r.tau0 = tau(0.0);
      r.tauL = tau(L);
      // int_0^L tau^2 dy  (V 4.14); every term positive, stable for all x > 0
      const double sh = std::sinh(x);
      const double inv_sh2 = 1.0 / (sh * sh);  // 0 for large x (sinh -> inf)
      const double cosh_over_sh2 = 1.0 / (sh * std::tanh(x));
      int_tau2 = b * b *
                 ((R_ * R_ + Ninf_ * Ninf_) * (0.5 * L * inv_sh2 + 0.5 / (b * std::tanh(x))) +
                  R_ * Ninf_ * (L * cosh_over_sh2 + 1.0 / (b * sh)));
    }
    const double disp = free_ends + int_No / Eto + ctau0;  // (V 4.12)
    r.displacement = disp;
    r.U = 0.5 * P_ * disp * B;           // (V 4.13)
    r.U_interface = ct_ * int_tau2 * B;  // (V 4.14)
    r.U_adherend_shear = (perfect_ ? 0.0 : (c_ - ct_) * int_tau2) * B;
    r.U_axial = r.U - r.U_interface - r.U_adherend_shear;  // (V 4.15)
    r.k = P_ * B / disp;                                   // (V 4.16)
    r.interface_fraction = r.U_interface / r.U;
    return r;
  }

  /// Strain energy in the unbonded ends (central + both outer), exact  [mJ]  (V 4.15)
  double free_end_energy() const {
    const double Eto = m_.E_o * g_.t_o, Etc = m_.E_c * g_.t_c;
    return (0.5 * P_ * P_ * g_.end_c / Etc + 0.25 * P_ * P_ * g_.end_o / Eto) * g_.depth;
  }

 private:
  // sinh(u)/sinh(x) and cosh(u)/sinh(x) for 0 <= u <= x, overflow-free for large x.
  double sinh_ratio(double u) const {
    if (x_ < 30.0) return std::sinh(u) / std::sinh(x_);
    return std::exp(u - x_) * (-std::expm1(-2.0 * u)) / (-std::expm1(-2.0 * x_));
  }
  double cosh_ratio(double u) const {
    if (x_ < 30.0) return std::cosh(u) / std::sinh(x_);
    return std::exp(u - x_) * (1.0 + std::exp(-2.0 * u)) / (-std::expm1(-2.0 * x_));
  }

  DlsGeometry g_;
  DlsMaterials m_;
  double ct_;  // interface compliance 1/Dt [mm/MPa]
  double P_{}, S_{}, c_{}, Ninf_{}, R_{}, beta_{}, x_{};
  bool perfect_{}, debonded_{};
};

/// DLS stiffness k = P^2/(2U)  [N/mm] for interface stiffness Dt [MPa/mm]  (V 4.16)
inline double dls_stiffness(double Dt, const DlsGeometry& g = {}, const DlsMaterials& m = {}) {
  return DlsShearLag(g, m, Dt).result().k;
}

/// Stiffness from a measured total energy: k = P^2/(2U)  [N/mm]  (paper §3 / V 4.16)
inline double stiffness_from_energy(double P, double U) {
  return P * P / (2.0 * U);
}

// ---------------------------------------------------------------------------
// §5  Composite spheres assemblage (CSA) bulk modulus with an imperfect interface
// ---------------------------------------------------------------------------

/// Hashin's perfect-interface CSA bulk modulus (= Hashin-Shtrikman lower bound for a stiff
/// inclusion)  [MPa]  (V 5.9)
inline double csa_bulk_perfect(double Ki, double Km, double Gm, double phi) {
  const double q = 3.0 * Km + 4.0 * Gm;
  return Km + phi * (Ki - Km) * q / (q + 3.0 * (1.0 - phi) * (Ki - Km));
}
/// Debonded (Dn -> 0) limit: the hollow-sphere assemblage K = 4 Gm Km (1-phi)/(3 phi Km + 4 Gm)
/// [MPa]  (V 5.10)
inline double csa_bulk_void(double Km, double Gm, double phi) {
  return 4.0 * Gm * Km * (1.0 - phi) / (3.0 * phi * Km + 4.0 * Gm);
}
/// Equivalent bulk modulus of inclusion + interface: 1/Ke = 1/Ki + 3/(a Dn)  [MPa]  (V 5.7)
inline double csa_equivalent_inclusion_bulk(double Ki, double a, double Dn) {
  return Ki / (1.0 + 3.0 * Ki * compliance_of(Dn) / a);
}
/// CSA bulk modulus with a normal interface stiffness Dn [MPa/mm]: inclusion bulk modulus Ki,
/// radius a [mm]; matrix Km, Gm; inclusion volume fraction phi  [MPa]  (V 5.8)
inline double csa_bulk(double Ki, double Km, double Gm, double phi, double a, double Dn) {
  return csa_bulk_perfect(csa_equivalent_inclusion_bulk(Ki, a, Dn), Km, Gm, phi);
}

struct CsaSolution {
  double a, b;     ///< inclusion and outer radii [mm], b = a phi^(-1/3)
  double A;        ///< inclusion u = A r                 [-]
  double B, C;     ///< matrix u = B r + C/r^2            [-], [mm^3]
  double sigma_a;  ///< radial stress at r = a            [MPa]
  double jump;     ///< [u_r](a) = u_m(a) - u_i(a) = sigma_a/Dn   [mm]
  double sigma_b;  ///< radial stress at r = b            [MPa]
  double U_inclusion, U_matrix, U_interface, U_total;  ///< energies of one sphere [mJ]
  double K_energy;    ///< 2U/(9 V eps0^2), V = 4 pi b^3/3   [MPa]  (V 5.11)
  double K_pressure;  ///< sigma_b/(3 eps0)                  [MPa]  (V 5.11)
};

/// Full Lame solution of one composite sphere under u_r(b) = eps0 b  (V 5.1-5.6, 5.11)
inline CsaSolution csa_solve(double Ki, double Km, double Gm, double phi, double a, double Dn,
                             double eps0) {
  CsaSolution s{};
  const double cn = compliance_of(Dn);
  s.a = a;
  s.b = a / std::cbrt(phi);
  const double a3 = a * a * a, b3 = s.b * s.b * s.b;
  const double Ke = csa_equivalent_inclusion_bulk(Ki, a, Dn);
  // Matrix: sigma_rr(a) = 3Km B - 4Gm C/a^3 = 3 Ke (B + C/a^3)   [u_m(a)/a = sigma_a/(3Ke)]
  //         B + C/b^3 = eps0
  // => C (4Gm + 3Ke)/a^3 = 3 (Km - Ke) B, solve with the outer condition.   (V 5.5)
  const double r = 3.0 * (Km - Ke) / (4.0 * Gm + 3.0 * Ke);  // C = r a^3 B
  s.B = eps0 / (1.0 + r * a3 / b3);
  s.C = r * a3 * s.B;
  s.sigma_a = 3.0 * Km * s.B - 4.0 * Gm * s.C / a3;
  s.A = s.sigma_a / (3.0 * Ki);
  s.jump = (s.B + s.C / a3 - s.A) * a;  // kinematic form: finite for Dn = 0 and Dn = inf
  s.sigma_b = 3.0 * Km * s.B - 4.0 * Gm * s.C / b3;
  const double pi = std::numbers::pi;
  s.U_inclusion = 0.5 * 9.0 * Ki * s.A * s.A * (4.0 * pi * a3 / 3.0);  // (V 5.6)
  s.U_matrix = 4.5 * Km * s.B * s.B * (4.0 * pi * (b3 - a3) / 3.0) +
               8.0 * pi * Gm * s.C * s.C * (1.0 / a3 - 1.0 / b3);                 // (V 5.6)
  s.U_interface = cn == 0.0 ? 0.0 : 0.5 * s.sigma_a * s.jump * 4.0 * pi * a * a;  // (V 5.6)
  s.U_total = s.U_inclusion + s.U_matrix + s.U_interface;
  const double V = 4.0 * pi * b3 / 3.0;
  s.K_energy = 2.0 * s.U_total / (9.0 * V * eps0 * eps0);
  s.K_pressure = s.sigma_b / (3.0 * eps0);
  return s;
}

/// Bulk modulus from the total static energy of a body of volume V under uniform strain eps0
/// in all directions: K = 2U/(9 V eps0^2)  [MPa]  (P-35)
inline double bulk_from_energy(double U, double V, double eps0) {
  return 2.0 * U / (9.0 * V * eps0 * eps0);
}
/// Bulk modulus from the average pressure: K = P/(3 eps0)  [MPa]  (P-36)
inline double bulk_from_pressure(double P, double eps0) {
  return P / (3.0 * eps0);
}

// ---------------------------------------------------------------------------
// §5c  A stress wave through a normal imperfect interface (dynamic)
// ---------------------------------------------------------------------------

/// A plane wave of particle velocity v_I(t) in bar 1 (impedance Z1 = rho1 c1
/// [MPa ms/mm]) meets a normal interface Dn [MPa/mm] in front of bar 2 (Z2). The
/// transmitted particle velocity obeys  v_T + tau dv_T/dt = T0 v_I  (V 5c.3) with
/// T0 = 2 Z1/(Z1 + Z2) (the bonded transmission) and tau = Z1 Z2/(Dn (Z1 + Z2)) [ms]
/// (V 5c.4); the reflected particle velocity is v_R = v_I - (Z2/Z1) v_T  (V 5c.2).
/// Dn = inf gives tau = 0 (bonded); Dn = 0 gives tau = inf (nothing crosses).
struct InterfaceWave {
  double transmission = 0;  // T0
  double tau = 0;           // ms
};
inline InterfaceWave interface_wave(double Z1, double Z2, double Dn) {
  return {2.0 * Z1 / (Z1 + Z2), Z1 * Z2 / (Z1 + Z2) * compliance_of(Dn)};
}

/// Displacement [mm] carried past a point, s [ms] after the front arrives, by a
/// wave whose particle velocity ramps linearly from 0 to v0 [mm/ms] over t_ramp
/// [ms] and then holds, after a first-order lag tau [ms] (w + tau w' = v, w(0) = 0):
///   s <= t_ramp:  W = a (s^2/2 - tau s + tau^2 (1 - e^(-s/tau))),  a = v0/t_ramp
///   s >  t_ramp:  W = W(t_ramp) + v0 (s - t_ramp) + (w(t_ramp) - v0) tau (1 - e^(-(s -
///   t_ramp)/tau)),
///                 w(t_ramp) = a (t_ramp - tau + tau e^(-t_ramp/tau))           (V 5c.5)
/// tau = 0 is the ramp itself, tau = inf carries nothing; zero for s <= 0. Late in
/// the wave W -> v0 (s - t_ramp/2 - tau): the interface delays it by tau.
inline double lagged_ramp_displacement(double s, double v0, double t_ramp, double tau) {
  if (!(t_ramp > 0.0) || !(tau >= 0.0))
    throw std::invalid_argument("lagged_ramp_displacement: t_ramp > 0 and tau >= 0");
  if (s <= 0.0 || tau == kInf) return 0.0;
  const double a = v0 / t_ramp;
  auto rising = [&](double x) {  // W on [0, t_ramp]
    return tau == 0.0 ? 0.5 * a * x * x
                      : a * (0.5 * x * x - tau * x - tau * tau * std::expm1(-x / tau));
  };
  if (s <= t_ramp) return rising(s);
  const double w_ramp = tau == 0.0 ? v0 : a * (t_ramp - tau + tau * std::exp(-t_ramp / tau));
  const double settle = tau == 0.0 ? 0.0 : -tau * std::expm1(-(s - t_ramp) / tau);
  return rising(t_ramp) + v0 * (s - t_ramp) + (w_ramp - v0) * settle;
}

}  // namespace mmpm::analytic
