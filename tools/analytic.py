#!/usr/bin/env python3
"""Closed-form reference solutions for mmpm validation (Python twin of tests/analytic.hpp).

Units: mm, ms, g  =>  force N, stress MPa, energy mJ (N*mm), density g/mm^3,
interface stiffness D in MPa/mm (math.inf = perfect, 0 = debonded).
Equation labels "(V n.m)" refer to docs/validation.md.

    python3 tools/analytic.py --selftest   # limiting cases + values printed by the C++ twin
    python3 tools/analytic.py --tables     # DLS k vs 1/Dt and CSA K vs 1/D tables

Figure scripts: ``import analytic`` (with tools/ on sys.path) and use
``dls_stiffness``, ``csa_bulk``, ``fixed_free_uniform_tip`` ... or the ``*_curve`` helpers,
which accept numpy arrays.
"""
from __future__ import annotations

import argparse
import math
import sys
from dataclasses import dataclass, field

import numpy as np

INF = math.inf


def compliance_of(D: float) -> float:
    """1/D in mm/MPa with 1/inf = 0 and 1/0 = inf."""
    if not D >= 0.0:
        raise ValueError("interface stiffness must be >= 0")
    if D == INF:
        return 0.0
    if D == 0.0:
        return INF
    return 1.0 / D


# --------------------------------------------------------------------------- §0 constants
def bulk_modulus(E, nu):
    """K = E/(3(1-2nu)) [MPa] (V 0.1)"""
    return E / (3.0 * (1.0 - 2.0 * nu))


def shear_modulus(E, nu):
    """G = E/(2(1+nu)) [MPa] (V 0.1)"""
    return E / (2.0 * (1.0 + nu))


def constrained_modulus(E, nu):
    """M = E(1-nu)/((1+nu)(1-2nu)) [MPa] (V 0.2)"""
    return E * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu))


def plane_strain_modulus(E, nu):
    """E/(1-nu^2) [MPa] (V 0.3)"""
    return E / (1.0 - nu * nu)


LATERAL_STATES = ("uniaxial_stress", "one_lateral_constraint", "confined")


def axial_modulus(E, nu, state):
    """Effective axial modulus for a lateral state (V 0.4); see LATERAL_STATES."""
    if state == "uniaxial_stress":
        return E
    if state == "one_lateral_constraint":
        return plane_strain_modulus(E, nu)
    if state == "confined":
        return constrained_modulus(E, nu)
    raise ValueError(f"unknown lateral state {state!r}")


def transverse_axial_plane_strain(EA, ET, nuA):
    """E_A/(1 - nuA^2 ET/EA) [MPa] (V 0.5)"""
    return EA / (1.0 - nuA * nuA * ET / EA)


def wave_speed(modulus, rho):
    """c = sqrt(modulus/rho) [mm/ms] (V 3.1)"""
    return math.sqrt(modulus / rho)


# --------------------------------------------------------------------------- §1 series bars
def series_bars(E1, L1, E2, L2, Dn, A, P):
    """Two bars in series with a normal interface (V 1.1-1.6). Returns a dict."""
    cn = compliance_of(Dn)
    s = P / A
    C = L1 / (E1 * A) + L2 / (E2 * A) + cn / A
    U1 = s * s * A * L1 / (2 * E1)
    U2 = s * s * A * L2 / (2 * E2)
    Ui = 0.5 * s * s * A * cn
    return dict(compliance=C, elongation=P * C, stress=s, jump=s * cn, U_bar1=U1, U_bar2=U2,
                U_interface=Ui, U_total=U1 + U2 + Ui)


# --------------------------------------------------------------------------- §2 shear stack
def shear_stack(G1, H1, G2, H2, Dt, tau):
    """Simple-shear stack with a tangential interface (V 2.1-2.3). Per unit area."""
    ct = compliance_of(Dt)
    Us = 0.5 * tau * tau * (H1 / G1 + H2 / G2)
    Ui = 0.5 * tau * tau * ct
    return dict(top_displacement=tau * (H1 / G1 + H2 / G2 + ct), jump=tau * ct,
                gamma1=tau / G1, gamma2=tau / G2, U_strain_per_area=Us,
                U_interface_per_area=Ui, U_per_area=Us + Ui)


# --------------------------------------------------------------------------- §3 vibration etc.
def fixed_free_omega(n, L, c):
    """omega_n = (2n-1) pi c/(2L) [rad/ms] (V 3.3)"""
    return (2 * n - 1) * math.pi * c / (2 * L)


def fixed_free_period(L, c):
    """T1 = 4L/c [ms] (V 3.4)"""
    return 4.0 * L / c


def fixed_free_sine_tip_amplitude(v0, L, c):
    """2 L v0/(pi c) [mm] (V 3.5)"""
    return 2.0 * L * v0 / (math.pi * c)


def fixed_free_sine_displacement(v0, L, c, x, t):
    """(v0/omega1) sin(pi x/2L) sin(omega1 t) [mm] (V 3.5); numpy-friendly."""
    w = fixed_free_omega(1, L, c)
    return v0 / w * np.sin(np.pi * np.asarray(x) / (2 * L)) * np.sin(w * np.asarray(t))


def fixed_free_uniform_tip_amplitude(v0, L, c):
    """v0 L/c [mm] (V 3.7)"""
    return v0 * L / c


def fixed_free_uniform_tip(v0, L, c, t):
    """Triangle wave of period 4L/c and amplitude v0 L/c [mm] (V 3.7); numpy-friendly."""
    T = fixed_free_period(L, c)
    tau = L / c
    s = np.mod(np.asarray(t, dtype=float), T)
    return np.where(s <= tau, v0 * s, np.where(s <= 3 * tau, v0 * (2 * tau - s), v0 * (s - T)))


def fixed_free_uniform_tip_series(v0, L, c, t, n_modes=2000):
    """Modal series of the same history (V 3.6)."""
    t = np.asarray(t, dtype=float)
    s = np.zeros_like(t)
    for n in range(1, n_modes + 1):
        k = 2 * n - 1
        s += (1 if n % 2 else -1) * np.sin(fixed_free_omega(n, L, c) * t) / (k * k)
    return 8 * v0 * L / (math.pi ** 2 * c) * s


def block_stiffness(E_eff, A, L):
    """k = E_eff A/L [N/mm] (V 3.8)"""
    return E_eff * A / L


def gravity_stress_yy(rho, g, h, y):
    """-rho g (h - y) [MPa] (V 3.9)"""
    return -rho * g * (h - np.asarray(y))


def gravity_displacement(rho, g, h, E_eff, y):
    """-(rho g/E_eff)(h y - y^2/2) [mm] (V 3.10)"""
    y = np.asarray(y)
    return -rho * g / E_eff * (h * y - 0.5 * y * y)


def gravity_top_displacement(rho, g, h, E_eff):
    """-rho g h^2/(2 E_eff) [mm] (V 3.10)"""
    return -rho * g * h * h / (2 * E_eff)


def gravity_strain_energy(rho, g, h, E_eff, A):
    """rho^2 g^2 A h^3/(6 E_eff) [mJ] (V 3.11)"""
    return rho * rho * g * g * A * h ** 3 / (6 * E_eff)


# --------------------------------------------------------------------------- §4 DLS shear lag
@dataclass
class DlsGeometry:
    t_c: float = 1.0     # central layer thickness [mm]
    t_o: float = 1.0     # each outer layer thickness [mm]
    L: float = 25.0      # bond length [mm]
    end_c: float = 5.0   # free length of the central layer [mm]
    end_o: float = 5.0   # free length of each outer layer [mm]
    depth: float = 1.0   # out-of-plane depth (2D thickness) [mm]


@dataclass
class DlsMaterials:
    E_c: float = 10000.0  # axial moduli along the bond [MPa]
    E_o: float = 10000.0
    G_c: float = 500.0    # in-plane shear moduli [MPa]; inf = classical Volkersen
    G_o: float = 500.0


def dls(Dt, geom: DlsGeometry | None = None, mat: DlsMaterials | None = None, sigma_c=2.0):
    """Generalized shear-lag solution of the symmetric DLS specimen (V 4.1-4.16).

    Returns a dict with P [N], beta [1/mm], N_inf [N/mm], tau0/tauL [MPa], displacement [mm],
    U, U_interface, U_adherend_shear, U_axial [mJ], k [N/mm], interface_fraction.
    """
    g = geom or DlsGeometry()
    m = mat or DlsMaterials()
    ct = compliance_of(Dt)
    P = sigma_c * g.t_c
    S = 1.0 / (m.E_o * g.t_o) + 2.0 / (m.E_c * g.t_c)
    c = ct + g.t_o / (3.0 * m.G_o) + g.t_c / (6.0 * m.G_c)
    Ninf = P / (m.E_c * g.t_c) / S
    R = 0.5 * P - Ninf
    Eto, Etc = m.E_o * g.t_o, m.E_c * g.t_c
    free = P * g.end_c / Etc + 0.5 * P * g.end_o / Eto
    B = g.depth
    out = dict(P=P * B, compliance_eff=c, N_inf=Ninf)
    if c == INF:
        out.update(beta=0.0, displacement=INF, U=INF, U_interface=INF, U_adherend_shear=0.0,
                   U_axial=INF, k=0.0, interface_fraction=1.0, tau0=0.0, tauL=0.0)
        return out
    if c == 0.0:
        int_No, ctau0, int_tau2 = Ninf * g.L, 0.0, 0.0
        beta, tau0, tauL = INF, INF, INF
    else:
        beta = math.sqrt(S / c)
        x = beta * g.L
        int_No = Ninf * g.L + (R - Ninf) * math.tanh(0.5 * x) / beta          # (V 4.11)
        sh = math.sinh(x) if x < 700 else INF
        inv_sh = 1.0 / sh
        coth = 1.0 / math.tanh(x)
        ctau0 = math.sqrt(S * c) * (Ninf * coth + R * inv_sh)                   # (V 4.10)
        tau0 = beta * (R * inv_sh + Ninf * coth)
        tauL = beta * (R * coth + Ninf * inv_sh)
        inv_sh2 = inv_sh * inv_sh
        cosh_over_sh2 = inv_sh * coth
        int_tau2 = beta * beta * ((R * R + Ninf * Ninf) * (0.5 * g.L * inv_sh2 + 0.5 * coth / beta)
                                  + R * Ninf * (g.L * cosh_over_sh2 + inv_sh / beta))  # (V 4.14)
    disp = free + int_No / Eto + ctau0                                            # (V 4.12)
    U = 0.5 * P * disp * B
    Ui = ct * int_tau2 * B
    Ua = (c - ct) * int_tau2 * B if c > 0 else 0.0
    out.update(beta=beta, tau0=tau0, tauL=tauL, displacement=disp, U=U, U_interface=Ui,
               U_adherend_shear=Ua, U_axial=U - Ui - Ua, k=P * B / disp,
               interface_fraction=Ui / U)
    return out


def dls_stiffness(Dt, geom=None, mat=None):
    """k = P^2/(2U) [N/mm] (V 4.16)"""
    return dls(Dt, geom, mat)["k"]


def dls_stiffness_curve(inv_Dt, geom=None, mat=None):
    """k for an array of interface compliances 1/Dt [mm/MPa] (0 = perfect)."""
    inv = np.atleast_1d(np.asarray(inv_Dt, dtype=float))
    return np.array([dls_stiffness(INF if v == 0 else 1.0 / v, geom, mat) for v in inv])


def stiffness_from_energy(P, U):
    """k = P^2/(2U) [N/mm]"""
    return P * P / (2.0 * U)


# --------------------------------------------------------------------------- §5 CSA
def csa_bulk_perfect(Ki, Km, Gm, phi):
    """Hashin CSA, perfect interface (V 5.9) [MPa]"""
    q = 3 * Km + 4 * Gm
    return Km + phi * (Ki - Km) * q / (q + 3 * (1 - phi) * (Ki - Km))


def csa_bulk_void(Km, Gm, phi):
    """Debonded limit 4 Gm Km (1-phi)/(3 phi Km + 4 Gm) (V 5.10) [MPa]"""
    return 4 * Gm * Km * (1 - phi) / (3 * phi * Km + 4 * Gm)


def csa_equivalent_inclusion_bulk(Ki, a, Dn):
    """1/Ke = 1/Ki + 3/(a Dn) (V 5.7) [MPa]"""
    return Ki / (1.0 + 3.0 * Ki * compliance_of(Dn) / a)


def csa_bulk(Ki, Km, Gm, phi, a, Dn):
    """CSA bulk modulus with normal interface stiffness Dn (V 5.8) [MPa]"""
    return csa_bulk_perfect(csa_equivalent_inclusion_bulk(Ki, a, Dn), Km, Gm, phi)


def csa_bulk_curve(inv_D, Ki, Km, Gm, phi, a):
    """K for an array of interface compliances 1/D [mm/MPa]."""
    inv = np.atleast_1d(np.asarray(inv_D, dtype=float))
    Ke = Ki / (1.0 + 3.0 * Ki * inv / a)
    return csa_bulk_perfect(Ke, Km, Gm, phi)


def csa_midpoint_compliance(Ki, Km, Gm, phi, a):
    """1/D at which K is halfway between the debonded and perfect plateaus [mm/MPa]."""
    target = 0.5 * (csa_bulk_perfect(Ki, Km, Gm, phi) + csa_bulk_void(Km, Gm, phi))
    # invert the Hashin formula (a Moebius map of Ke): K - Km = phi d q/(q + 3(1-phi) d)
    q = 3 * Km + 4 * Gm
    y = (target - Km) / phi
    d = y * q / (q - 3 * (1 - phi) * y)  # d = Ke - Km
    Ke = Km + d
    return a * (Ki / Ke - 1.0) / (3.0 * Ki)


def csa_solve(Ki, Km, Gm, phi, a, Dn, eps0):
    """Full Lame solution of one composite sphere, u(b) = eps0 b (V 5.1-5.6, 5.11)."""
    cn = compliance_of(Dn)
    b = a / phi ** (1.0 / 3.0)
    a3, b3 = a ** 3, b ** 3
    Ke = csa_equivalent_inclusion_bulk(Ki, a, Dn)
    r = 3 * (Km - Ke) / (4 * Gm + 3 * Ke)
    B = eps0 / (1 + r * a3 / b3)
    C = r * a3 * B
    sa = 3 * Km * B - 4 * Gm * C / a3
    A = sa / (3 * Ki)
    jump = (B + C / a3 - A) * a
    sb = 3 * Km * B - 4 * Gm * C / b3
    Ui = 0.5 * 9 * Ki * A * A * (4 * math.pi * a3 / 3)
    Um = 4.5 * Km * B * B * (4 * math.pi * (b3 - a3) / 3) + 8 * math.pi * Gm * C * C * (1 / a3 - 1 / b3)
    Uf = 0.0 if cn == 0.0 else 0.5 * sa * jump * 4 * math.pi * a * a
    U = Ui + Um + Uf
    V = 4 * math.pi * b3 / 3
    return dict(a=a, b=b, A=A, B=B, C=C, sigma_a=sa, jump=jump, sigma_b=sb, U_inclusion=Ui,
                U_matrix=Um, U_interface=Uf, U_total=U, K_energy=2 * U / (9 * V * eps0 ** 2),
                K_pressure=sb / (3 * eps0))


def bulk_from_energy(U, V, eps0):
    """K = 2U/(9 V eps0^2) (P-35) [MPa]"""
    return 2 * U / (9 * V * eps0 ** 2)


def bulk_from_pressure(P, eps0):
    """K = P/(3 eps0) (P-36) [MPa]"""
    return P / (3 * eps0)


# --------------------------------------------------------------------------- §5c wave
def interface_wave(Z1, Z2, Dn):
    """(T0, tau): bonded transmission 2 Z1/(Z1+Z2) and lag Z1 Z2/(Dn (Z1+Z2)) [ms] (V 5c.4)"""
    return 2 * Z1 / (Z1 + Z2), Z1 * Z2 / (Z1 + Z2) * compliance_of(Dn)


def lagged_ramp_displacement(s, v0, t_ramp, tau):
    """Displacement [mm] s [ms] after the front of a velocity ramp 0 -> v0 over t_ramp,
    lagged by w + tau w' = v (V 5c.5); zero for s <= 0, tau = inf carries nothing."""
    s = np.maximum(np.asarray(s, dtype=float), 0.0)
    if tau == INF:
        return np.zeros_like(s)
    a = v0 / t_ramp
    if tau == 0.0:
        return np.where(s <= t_ramp, 0.5 * a * s * s, v0 * (s - 0.5 * t_ramp))
    x = np.minimum(s, t_ramp)
    rising = a * (0.5 * x * x - tau * x - tau * tau * np.expm1(-x / tau))
    w_ramp = a * (t_ramp - tau + tau * np.exp(-t_ramp / tau))
    after = np.maximum(s - t_ramp, 0.0)
    return rising + v0 * after + (w_ramp - v0) * (-tau * np.expm1(-after / tau))


# --------------------------------------------------------------------------- paper data
GLASS = dict(E=70000.0, nu=0.25)
POLYMER = dict(E=2400.0, nu=0.33)
PHI_PAPER = 0.1796
A_MICRO = 0.7        # mm
A_NANO = 700e-6      # mm


def paper_csa_moduli():
    return (bulk_modulus(**GLASS), bulk_modulus(**POLYMER), shear_modulus(**POLYMER))


def tables(out=sys.stdout):
    gen = DlsMaterials()
    cls = DlsMaterials(G_c=INF, G_o=INF)
    Eps = transverse_axial_plane_strain(10000.0, 1000.0, 0.2)
    ps = DlsMaterials(E_c=Eps, E_o=Eps)
    print("DLS stiffness k [N/mm per mm depth], P = 2 N/mm; E_A = 10000, G_A = 500 MPa", file=out)
    print(f"{'1/Dt':>6} {'k gen.':>9} {'k class.':>9} {'k gen. p-strain':>16} "
          f"{'U_int/U':>8} {'U_adh/U':>8}", file=out)
    for inv in (0.0, 0.01, 0.02, 0.05, 0.1, 0.2, 0.3, 0.5, 0.7, 1.0):
        D = INF if inv == 0 else 1 / inv
        r = dls(D, mat=gen)
        print(f"{inv:6.2f} {r['k']:9.3f} {dls(D, mat=cls)['k']:9.3f} {dls(D, mat=ps)['k']:16.3f} "
              f"{r['interface_fraction']:8.4f} {r['U_adherend_shear'] / r['U']:8.4f}", file=out)
    Ki, Km, Gm = paper_csa_moduli()
    print(f"\nCSA bulk modulus [MPa]; Ki={Ki:.3f} Km={Km:.3f} Gm={Gm:.3f} phi={PHI_PAPER}", file=out)
    print(f"perfect {csa_bulk_perfect(Ki, Km, Gm, PHI_PAPER):.3f}  "
          f"debonded {csa_bulk_void(Km, Gm, PHI_PAPER):.3f}", file=out)
    for name, a in (("micro a=0.7 mm", A_MICRO), ("nano a=700e-6 mm", A_NANO)):
        print(f"midpoint 1/D ({name}): {csa_midpoint_compliance(Ki, Km, Gm, PHI_PAPER, a):.4g} mm/MPa",
              file=out)
    print(f"{'1/D':>8} {'K micro':>10} {'K nano':>10}", file=out)
    for e in range(-10, 3):
        inv = 10.0 ** e
        print(f"{inv:8.0e} {csa_bulk_curve(inv, Ki, Km, Gm, PHI_PAPER, A_MICRO)[0]:10.3f} "
              f"{csa_bulk_curve(inv, Ki, Km, Gm, PHI_PAPER, A_NANO)[0]:10.3f}", file=out)


# --------------------------------------------------------------------------- self-test
def _close(name, got, want, rtol=1e-9, atol=0.0):
    ok = abs(got - want) <= atol + rtol * abs(want)
    if not ok:
        print(f"FAIL {name}: got {got!r}, want {want!r} (rtol {rtol}, atol {atol})")
    return ok


def selftest() -> int:
    ok = True
    # Hand values (docs/validation.md).
    ok &= _close("M polymer", constrained_modulus(2400, 0.33), 3555.9487, atol=1e-4)
    ok &= _close("E/(1-nu^2)", plane_strain_modulus(2400, 0.33), 2693.3004, atol=1e-4)
    r = series_bars(1000, 10, 1000, 10, 50, 2, 4)
    ok &= _close("bars C", r["compliance"], 0.02) and _close("bars U", r["U_total"], 0.16)
    ok &= _close("bars U=P^2C/2", r["U_total"], 0.5 * 16 * r["compliance"])
    ok &= _close("bars perfect", series_bars(1, 2, 3, 4, INF, 1, 1)["compliance"], 2 + 4 / 3)
    s = shear_stack(500, 2, 1000, 4, 100, 1)
    ok &= _close("shear top", s["top_displacement"], 0.018) and _close("shear Ui", s["U_interface_per_area"], 0.005)
    c = wave_speed(2400, 1.2e-3)
    ok &= _close("period", fixed_free_period(10, c), 0.0282843, atol=1e-7)
    t = np.linspace(0, 1.7 * fixed_free_period(12, 1500), 37)
    ok &= bool(np.max(np.abs(fixed_free_uniform_tip(0.5, 12, 1500, t)
                             - fixed_free_uniform_tip_series(0.5, 12, 1500, t, 4000))) < 2e-4 * 0.5 * 12 / 1500)
    ok &= _close("gravity top", gravity_top_displacement(1.2e-3, 9.81e-3, 100, 2400), -2.4525e-5, atol=1e-12)
    # DLS.
    cls = DlsMaterials(G_c=INF, G_o=INF)
    ok &= _close("DLS classical perfect", dls_stiffness(INF, mat=cls), 12000 / 19)
    ok &= _close("DLS generalized perfect", dls_stiffness(INF), 576.21, atol=0.01)
    ok &= _close("DLS classical 1/Dt=1", dls_stiffness(1.0, mat=cls), 45.4599, atol=2e-4)
    ok &= _close("DLS D=1e12 -> perfect", dls_stiffness(1e12), dls_stiffness(INF), rtol=1e-8)
    ok &= _close("DLS D->0", dls_stiffness(1e-6) / (2 * 25 * 1e-6), 1.0, rtol=3e-3)
    ok &= dls_stiffness(0.0) == 0.0
    ok &= _close("DLS interface share at Dt=1 vs paper 91%", dls(1.0)["interface_fraction"], 0.91, atol=0.01)
    # Values printed by the C++ twin (tests/analytic.hpp).
    ok &= _close("C++ dls gen 1/Dt=0.3", dls_stiffness(1 / 0.3), 124.817259291184, rtol=1e-12)
    ok &= _close("C++ dls cls 1/Dt=0.3", dls_stiffness(1 / 0.3, mat=cls), 125.130040518125, rtol=1e-12)
    r = dls(2.0)
    for key, want in (("U", 0.0240298728357242), ("U_interface", 0.0200098476257489),
                      ("U_adherend_shear", 4.00196952514977e-05), ("tau0", 0.0424497935749165),
                      ("tauL", 0.0400297911079964)):
        ok &= _close(f"C++ dls D=2 {key}", r[key], want, rtol=1e-12)
    Ki, Km, Gm = paper_csa_moduli()
    ok &= _close("CSA perfect", csa_bulk_perfect(Ki, Km, Gm, PHI_PAPER), 3062.04, atol=0.01)
    ok &= _close("CSA void", csa_bulk_void(Km, Gm, PHI_PAPER), 1428.54, atol=0.01)
    ok &= _close("CSA Dn=inf", csa_bulk(Ki, Km, Gm, PHI_PAPER, 0.7, INF), csa_bulk_perfect(Ki, Km, Gm, PHI_PAPER))
    ok &= _close("CSA Dn=0", csa_bulk(Ki, Km, Gm, PHI_PAPER, 0.7, 0.0), csa_bulk_void(Km, Gm, PHI_PAPER))
    ok &= _close("CSA hand 1/D=1e-4", csa_bulk(Ki, Km, Gm, PHI_PAPER, 0.7, 1e4), 2328.73, atol=0.01)
    ok &= _close("C++ csa micro", csa_bulk(Ki, Km, Gm, PHI_PAPER, 0.7, 3e3), 1868.20068062302, rtol=1e-12)
    ok &= _close("C++ csa nano", csa_bulk(Ki, Km, Gm, PHI_PAPER, 7e-4, 3e8), 3018.85932607785, rtol=1e-12)
    sol = csa_solve(Ki, Km, Gm, PHI_PAPER, 0.7, 1e4, 0.005)
    for key, want in (("A", 0.00024549910570742), ("C", 6.50049468680495e-05),
                      ("sigma_b", 34.9310100285937), ("U_interface", 0.363690409275929),
                      ("U_matrix", 1.71392008916269)):
        ok &= _close(f"C++ csa_solve {key}", sol[key], want, rtol=1e-11)
    ok &= _close("CSA K energy = pressure", sol["K_energy"], sol["K_pressure"], rtol=1e-10)
    mid = csa_midpoint_compliance(Ki, Km, Gm, PHI_PAPER, 0.7)
    ok &= _close("CSA midpoint", csa_bulk(Ki, Km, Gm, PHI_PAPER, 0.7, 1 / mid),
                 0.5 * (csa_bulk_perfect(Ki, Km, Gm, PHI_PAPER) + csa_bulk_void(Km, Gm, PHI_PAPER)),
                 rtol=1e-10)
    # §5c: the closed form against a direct integration of w + tau w' = v.
    v0, tr, tau = 0.01, 0.002, 0.005
    ds = 1e-7
    tt = np.arange(0, 0.03, ds)
    vin = v0 * np.minimum(tt / tr, 1.0)
    w = np.zeros_like(tt)
    for k in range(1, len(tt)):
        w[k] = vin[k] + (w[k - 1] - vin[k]) * np.exp(-ds / tau)
    W = np.concatenate(([0.0], np.cumsum(0.5 * (w[1:] + w[:-1]) * ds)))
    ok &= bool(np.max(np.abs(lagged_ramp_displacement(tt, v0, tr, tau) - W)) < 1e-4 * W[-1])
    ok &= _close("wave late lag", float(lagged_ramp_displacement(0.2, v0, tr, tau)),
                 v0 * (0.2 - tr / 2 - tau), rtol=1e-12)
    ok &= _close("wave T0 tau", interface_wave(1.0, 2.0, 100.0)[1], 2.0 / 300.0)
    print("selftest: OK" if ok else "selftest: FAILED")
    return 0 if ok else 1


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--selftest", action="store_true", help="run the self-check")
    ap.add_argument("--tables", action="store_true", help="print the DLS and CSA tables")
    args = ap.parse_args(argv)
    rc = 0
    if args.selftest:
        rc = selftest()
    if args.tables or not args.selftest:
        tables()
    return rc


if __name__ == "__main__":
    sys.exit(main())
