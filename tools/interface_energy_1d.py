#!/usr/bin/env python3
"""An independent 1D model of two bars joined by an imperfect interface.

Written apart from the solver (numpy, a few dozen lines) to tell whether the
energy an undamped interface gains under MUSL, or loses under USL, is the
solver's or the algorithm's (docs/interface_validation.md, Finding 14).

Two bars of `--cells` cells each, linear shape functions, `--ppc` particles
per cell, no Poisson effect, closing at +-v0. Each bar has its own grid field
(ALGORITHM §1). At every node both fields reach, a linear normal spring
(ALGORITHM §3.2, P-3) acts: F = D A delta, with delta = x_b - x_a from the
extrapolated displacements (P-11, the displacement method) and A from (P-20).
The grid update, FLIP particle update and the strain update follow the
scheme asked for (ALGORITHM §2). Prints K + U + U_int over its start.

Variants that test a cause:
  --delta nodal        delta integrated at the node from the updated nodal
                       velocities (a history the paper's method does not keep)
  --force consistent   the spring's force given to the particles as
                       -dE/du_p and scattered back with S (a variational force)
  --displacement remap MUSL only: the displacement that delta reads moves with
                       the re-extrapolated velocity that the strain reads
  --displacement anchored
                       MUSL only: that displacement reset every step to the
                       particle's x - x0 at the step's start plus the step's
                       re-extrapolated move
  --scheme usf         the stress from the start-of-step velocities v^n (after
                       pass A), then the forces
  --displacement shift USF only: the displacement moves with dt S v^n, the
                       motion USF's strain reads (MUSL's remap, for USF)
  --displacement ahead USF only: x - x0 plus this step's dt S v^n on each
                       particle before the opening is extrapolated (the
                       stress of the step already holds it)
  --displacement shift-ahead
                       USF only: both
  --force-limit        the paper's clip (ALGORITHM 4.4): where the spring's
                       force exceeds f_lim the node sticks (both fields'
                       momenta to the centre of mass in pass A, outside the
                       FLIP increment, and their velocities after the update
                       and on MUSL's re-extrapolated velocities) and stores no
                       energy
  --limit-gate         with --force-limit: clip only a spring beyond the one-step
                       bound, D A dt^2 > 2 m_red (omega dt > sqrt 2), as the
                       solver does (docs/multimaterial.md 8.1)

Usage: /usr/bin/python3 tools/interface_energy_1d.py --Dn 100 --ppc 2 --end 3
"""
import argparse

import numpy as np


class Bars:
    """The two bars' constants: seeds, particle mass and volume, the step and the grid."""

    def __init__(self, a):
        self.h, self.E, self.Dn = a.h, a.E, a.Dn
        dx = a.h / a.ppc
        seeds = np.arange(dx / 2, a.cells * a.h, dx)
        self.X = [seeds, seeds + a.cells * a.h]
        self.Vp = dx
        self.mp = 1e-3 * dx  # density 1e-3
        self.dt = a.cfl * a.h / np.sqrt(a.E / 1e-3)
        speed = abs(a.v0) + abs(getattr(a, "drift", 0.0))
        pad = int(np.ceil(speed * getattr(a, "end", 0.0) / a.h)) + 2
        self.nodes = 2 * a.cells + 1 + 2 * pad
        self.origin = -pad * a.h

    def weights(self, x):
        """Linear shape functions S and their gradients, particles x nodes."""
        t = (x - self.origin) / self.h
        i = np.floor(t).astype(int)
        f = t - i
        W = np.zeros((len(x), self.nodes))
        G = np.zeros((len(x), self.nodes))
        rows = np.arange(len(x))
        W[rows, i], W[rows, i + 1] = 1 - f, f
        G[rows, i], G[rows, i + 1] = -1 / self.h, 1 / self.h
        return W, G


def step(bars, W, G, v, u, s, a, hist=None, start_displacement=None):
    """One step of both bars on the weights W, G (one pair per bar).

    Returns the new v, u, s, each particle's move, U_int before the step and
    the nodal opening history (for --delta nodal). start_displacement (per
    bar, x - x0 at the step's start) is read by --displacement anchored.
    """
    mp, Vp, dt = bars.mp, bars.Vp, bars.dt
    m = [mp * W[j].sum(0) for j in range(2)]
    vol = [Vp * W[j].sum(0) for j in range(2)]
    both = (m[0] > 0) & (m[1] > 0)
    safe = [np.where(m[j] > 0, m[j], 1.0) for j in range(2)]
    mu = [W[j].T @ (mp * u[j]) for j in range(2)]
    momenta = [W[j].T @ (mp * v[j]) for j in range(2)]  # P2G, before pass A
    delta = np.where(both, mu[1] / safe[1] - mu[0] / safe[0], 0.0)
    if a.delta == "nodal":
        delta = np.where(both, hist, 0.0)
    if a.scheme == "usf" and a.displacement in ("ahead", "shift-ahead"):
        # USF's stress this step holds dt G v^n, so the opening takes the same
        # step's move dt S v^n on each particle before it is extrapolated.
        velocity = [np.where(m[j] > 0, momenta[j] / safe[j], 0.0) for j in range(2)]
        ahead = [W[j].T @ (mp * (u[j] + dt * (W[j] @ velocity[j]))) for j in range(2)]
        delta = np.where(both, ahead[1] / safe[1] - ahead[0] / safe[0], 0.0)
    area = np.where(both, np.sqrt(2 * (vol[0] + vol[1]) * np.minimum(vol[0], vol[1])) / bars.h, 0.0)
    F = bars.Dn * area * delta  # on a, toward b (+x)
    limited = np.zeros(bars.nodes, dtype=bool)
    if a.force_limit:  # ALGORITHM 4.4 (P-23..P-27), before the internal forces (pass A)
        m_red = np.where(both, m[0] * m[1] / (safe[0] + safe[1]), 0.0)
        dp_a = m_red * np.where(both, momenta[1] / safe[1] - momenta[0] / safe[0], 0.0)
        f_lim = 2 * m_red * delta / dt ** 2 + 2 * dp_a / dt
        limited = both & (np.abs(F) > np.abs(f_lim))
        if a.limit_gate:  # only a spring stiffer than the one-step bound (omega dt > sqrt 2)
            limited &= np.abs(F) > np.abs(2 * m_red * delta / dt ** 2)
        F = np.where(limited, 0.0, F)
    energy_int = 0.5 * (bars.Dn * area * delta ** 2 * ~limited).sum()
    fi = [F, -F]
    if a.force == "consistent":  # -dE/du_p on the particles, scattered with S
        fi = [sign * (W[j].T @ (mp * (W[j] @ (F / safe[j])))) for j, sign in ((0, 1.0), (1, -1.0))]
    vn, un, sn, moves, new_velocity = [], [], [], [], []
    if limited.any():  # pass A: where limited, both fields' momenta to the centre of mass
        vc = (momenta[0] + momenta[1]) / (safe[0] + safe[1])
        momenta = [np.where(limited, m[j] * vc, momenta[j]) for j in range(2)]
    old_velocity = []
    stress = list(s)  # USF updates it before the forces; the caller's s stays
    for j in range(2):
        ok = m[j] > 0
        p = momenta[j]
        if a.scheme == "usf":  # the stress first, from the velocities after pass A
            stress[j] = s[j] + dt * bars.E * (G[j] @ np.where(ok, p / safe[j], 0.0))
        f = -G[j].T @ (Vp * stress[j])
        # The FLIP increment starts after pass A (ALGORITHM 2: pass A's
        # change moves the grid, not the particles' velocities).
        old_velocity.append(np.where(ok, p / safe[j], 0.0))
        v_new = np.where(ok, (p + dt * (f + fi[j])) / safe[j], 0.0)
        new_velocity.append(v_new)
    if limited.any():  # stick where limited: both fields to the centre of mass (pass B)
        mom = sum(m[j] * new_velocity[j] for j in range(2))
        vc = mom / (safe[0] + safe[1])
        new_velocity = [np.where(limited, vc, new_velocity[j]) for j in range(2)]
    v_particles = [v[j] + W[j] @ (new_velocity[j] - old_velocity[j]) for j in range(2)]  # FLIP
    # MUSL's re-extrapolated velocities, stuck again where limited (pass B, strain)
    v_remaps = [np.where(m[j] > 0, (W[j].T @ (mp * v_particles[j])) / safe[j], 0.0) for j in range(2)]
    if limited.any():
        vc = sum(m[j] * v_remaps[j] for j in range(2)) / (safe[0] + safe[1])
        v_remaps = [np.where(limited, vc, v_remaps[j]) for j in range(2)]
    for j in range(2):
        v_new, v_particle, v_remap = new_velocity[j], v_particles[j], v_remaps[j]
        move = dt * (W[j] @ v_new)
        if a.scheme == "usf":  # its stress was updated before the forces
            rate = np.zeros_like(stress[j])
            moved_as_strain = a.displacement in ("shift", "shift-ahead")
            u_new = u[j] + (dt * (W[j] @ old_velocity[j]) if moved_as_strain else move)
        elif a.scheme == "usl":
            rate = G[j] @ v_new
            u_new = u[j] + move
        else:  # MUSL: the strain from the re-extrapolated velocity
            rate = G[j] @ v_remap
            remap_move = dt * (W[j] @ v_remap)
            if a.displacement == "anchored":  # the step's start plus its remapped move
                u_new = start_displacement[j] + remap_move
            else:
                u_new = u[j] + (remap_move if a.displacement == "remap" else move)
        vn.append(v_particle)
        un.append(u_new)
        sn.append(stress[j] + dt * bars.E * rate)
        moves.append(move)
    if hist is not None:
        hist = np.where(both, hist + dt * (new_velocity[1] - new_velocity[0]), 0.0)
    return vn, un, sn, moves, energy_int, hist


def run(a):
    bars = Bars(a)
    x = [X.copy() for X in bars.X]
    u = [np.zeros_like(X) for X in bars.X]
    drift = getattr(a, "drift", 0.0)
    v = [np.full_like(bars.X[0], a.v0 + drift), np.full_like(bars.X[1], -a.v0 + drift)]
    # The translation's kinetic energy, which momentum keeps: left out, so
    # the printed ratio is the vibration's energy over its start.
    translation = 0.5 * bars.mp * (len(bars.X[0]) + len(bars.X[1])) * drift ** 2
    s = [np.zeros_like(X) for X in bars.X]
    hist = np.zeros(bars.nodes)
    energies = []
    for n in range(int(a.end / bars.dt)):
        if n > 0 and any(xj.min() < bars.origin + bars.h or
                         xj.max() > bars.origin + (bars.nodes - 2) * bars.h for xj in x):
            raise SystemExit(f"diverged: a particle left the grid at t = {n * bars.dt:.4g} ms "
                             f"(energy {energies[-1] / energies[0]:.3g} E0)")
        WG = [bars.weights(xj) for xj in x]
        K = sum(0.5 * bars.mp * (vj ** 2).sum() for vj in v)
        U = sum(0.5 * bars.Vp * (sj ** 2).sum() / bars.E for sj in s)
        start = [x[j] - bars.X[j] for j in range(2)]
        v, u, s, moves, energy_int, hist = step(bars, [w for w, _ in WG], [g for _, g in WG], v, u, s,
                                                a, hist, start)
        energies.append(K + U + energy_int - translation)
        x = [x[j] + moves[j] for j in range(2)]
    e = np.array(energies)
    return e / e[0]


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--Dn", type=float, default=100.0)
    p.add_argument("--E", type=float, default=1e3)
    p.add_argument("--h", type=float, default=0.25)
    p.add_argument("--cells", type=int, default=4)
    p.add_argument("--ppc", type=int, default=2)
    p.add_argument("--cfl", type=float, default=0.5)
    p.add_argument("--v0", type=float, default=0.1)
    p.add_argument("--end", type=float, default=3.0)
    p.add_argument("--drift", type=float, default=0.0,
                   help="a velocity added to both bars: the pair drifts through the grid "
                        "(its kinetic energy is left out of the ratio)")
    p.add_argument("--scheme", choices=["musl", "usl", "usf"], default="musl")
    p.add_argument("--delta", choices=["extrapolated", "nodal"], default="extrapolated")
    p.add_argument("--force", choices=["nodal", "consistent"], default="nodal")
    p.add_argument("--displacement", default="grid",
                   choices=["grid", "remap", "anchored", "shift", "ahead", "shift-ahead"])
    p.add_argument("--force-limit", action="store_true", help="the paper's clip (ALGORITHM 4.4)")
    p.add_argument("--limit-gate", action="store_true",
                   help="with --force-limit: clip only where D A dt^2 > 2 m_red (omega dt > sqrt 2)")
    a = p.parse_args()
    e = run(a)
    print(f"Dn {a.Dn:g} ppc {a.ppc} cfl {a.cfl:g} {a.scheme} delta={a.delta} force={a.force} "
          f"displacement={a.displacement}: (K+U+U_int)/E0 at {a.end:g} ms {e[-1]:.4f}, max {e.max():.4f}")


if __name__ == "__main__":
    main()
