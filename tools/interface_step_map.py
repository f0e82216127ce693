#!/usr/bin/env python3
"""Spectral radius of one step of 1D FLIP MPM with an imperfect interface.

The companion of tools/interface_energy_1d.py (docs/interface_validation.md,
Finding 14): the same two bars and interface spring (ALGORITHM §3.2, P-3,
P-11, P-20), with the particles' weights frozen at their seeds, so that a
step is a linear map of the particle velocities, displacements and
stresses. A spectral radius above 1 is a mode that grows every step,
whatever the start; the growth per ms is ln(radius) / dt.

Usage: /usr/bin/python3 tools/interface_step_map.py [--ppc 2] [--Dn 10 100 1000 1e4]
"""
import argparse

import numpy as np


def step_matrix(Dn, ppc, cells, h, E, rho, cfl, scheme, displacement):
    dx = h / ppc
    seeds = np.arange(dx / 2, cells * h, dx)
    X = [seeds, seeds + cells * h]
    n = [len(X[0]), len(X[1])]
    Vp = dx
    mp = rho * Vp
    dt = cfl * h / np.sqrt(E / rho)
    nodes = 2 * cells + 3
    origin = -h
    W, G = [], []
    for j in range(2):
        i = np.floor((X[j] - origin) / h).astype(int)
        f = (X[j] - origin) / h - i
        w = np.zeros((n[j], nodes))
        g = np.zeros((n[j], nodes))
        rows = np.arange(n[j])
        w[rows, i], w[rows, i + 1] = 1 - f, f
        g[rows, i], g[rows, i + 1] = -1 / h, 1 / h
        W.append(w)
        G.append(g)
    m = [mp * W[j].sum(0) for j in range(2)]
    vol = [Vp * W[j].sum(0) for j in range(2)]
    both = (m[0] > 0) & (m[1] > 0)
    area = np.where(both, np.sqrt(2 * (vol[0] + vol[1]) * np.minimum(vol[0], vol[1])) / h, 0.0)
    safe = [np.where(m[j] > 0, m[j], 1.0) for j in range(2)]

    def step(state):
        parts = np.split(state, np.cumsum([n[0], n[1], n[0], n[1], n[0]]))
        v, u, s = parts[0:2], parts[2:4], parts[4:6]
        mu = [W[j].T @ (mp * u[j]) for j in range(2)]
        delta = np.where(both, mu[1] / safe[1] - mu[0] / safe[0], 0.0)
        F = Dn * area * delta  # on a, toward b
        vn, un, sn = [], [], []
        for j, fi in ((0, F), (1, -F)):
            p = W[j].T @ (mp * v[j])
            f = -G[j].T @ (Vp * s[j])
            ok = m[j] > 0
            v_old = np.where(ok, p / safe[j], 0.0)
            v_new = np.where(ok, (p + dt * (f + fi)) / safe[j], 0.0)
            v_particle = v[j] + W[j] @ (v_new - v_old)  # FLIP
            if scheme == "usl":
                rate = G[j] @ v_new
                move = W[j] @ v_new
            else:  # MUSL: the strain from the re-extrapolated velocity
                v_remap = np.where(ok, (W[j].T @ (mp * v_particle)) / safe[j], 0.0)
                rate = G[j] @ v_remap
                move = W[j] @ (v_remap if displacement == "remap" else v_new)
            vn.append(v_particle)
            un.append(u[j] + dt * move)
            sn.append(s[j] + dt * E * rate)
        return np.concatenate(vn + un + sn)

    size = 3 * (n[0] + n[1])
    return np.column_stack([step(e) for e in np.eye(size)]), dt


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--Dn", type=float, nargs="+", default=[10.0, 100.0, 1e3, 1e4])
    p.add_argument("--ppc", type=int, default=2)
    p.add_argument("--cells", type=int, default=4)
    p.add_argument("--h", type=float, default=0.25)
    p.add_argument("--E", type=float, default=1e3)
    p.add_argument("--cfl", type=float, default=0.5)
    a = p.parse_args()
    for scheme, displacement in (("musl", "grid"), ("musl", "remap"), ("usl", "grid")):
        for Dn in a.Dn:
            M, dt = step_matrix(Dn, a.ppc, a.cells, a.h, a.E, 1e-3, a.cfl, scheme, displacement)
            radius = np.abs(np.linalg.eigvals(M)).max()
            print(f"{scheme} displacement={displacement:5s} Dn {Dn:8g}: spectral radius "
                  f"{radius:.8f}, growth {np.log(radius) / dt:+9.3f} per ms")


if __name__ == "__main__":
    main()
