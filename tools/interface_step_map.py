#!/usr/bin/env python3
"""Spectral radius of one step of 1D FLIP MPM with an imperfect interface.

The companion of tools/interface_energy_1d.py (docs/interface_validation.md,
Finding 14): that tool's own step (interface_energy_1d.step), the same two
bars and interface spring (ALGORITHM §3.2, P-3, P-11, P-20), with the
particles' weights frozen at their seeds, so that a step is a linear map of the particle velocities, displacements and
stresses. A spectral radius above 1 is a mode that grows every step,
whatever the start; the growth per ms is ln(radius) / dt.

Usage: /usr/bin/python3 tools/interface_step_map.py [--ppc 2] [--Dn 10 100 1000 1e4]
"""
import argparse
import os
import sys
from types import SimpleNamespace

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from interface_energy_1d import Bars, step  # noqa: E402  (the same step, weights frozen)


def step_matrix(Dn, ppc, cells, h, E, cfl, scheme, displacement):
    a = SimpleNamespace(Dn=Dn, ppc=ppc, cells=cells, h=h, E=E, cfl=cfl, v0=0.0, scheme=scheme,
                        delta="extrapolated", force="nodal", displacement=displacement,
                        force_limit=False)
    bars = Bars(a)
    W, G = zip(*(bars.weights(X) for X in bars.X))
    n = [len(X) for X in bars.X]

    def linear_step(state):
        parts = np.split(state, np.cumsum([n[0], n[1], n[0], n[1], n[0]]))
        v, u, s, _, _, _ = step(bars, W, G, parts[0:2], parts[2:4], parts[4:6], a)
        return np.concatenate(v + u + s)

    size = 3 * (n[0] + n[1])
    return np.column_stack([linear_step(e) for e in np.eye(size)]), bars.dt


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
            M, dt = step_matrix(Dn, a.ppc, a.cells, a.h, a.E, a.cfl, scheme, displacement)
            radius = np.abs(np.linalg.eigvals(M)).max()
            print(f"{scheme} displacement={displacement:5s} Dn {Dn:8g}: spectral radius "
                  f"{radius:.8f}, growth {np.log(radius) / dt:+9.3f} per ms")


if __name__ == "__main__":
    main()
