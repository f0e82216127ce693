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

Usage: /usr/bin/python3 tools/interface_energy_1d.py --Dn 100 --ppc 2 --end 3
"""
import argparse

import numpy as np


def run(a):
    h, E, rho = a.h, a.E, 1e-3
    dx = h / a.ppc
    x = [np.arange(dx / 2, a.cells * h, dx)]
    x.append(x[0] + a.cells * h)
    u = [np.zeros_like(x[0]), np.zeros_like(x[1])]
    x_ref = [x[0].copy(), x[1].copy()]
    v = [np.full_like(x[0], a.v0), np.full_like(x[1], -a.v0)]
    s = [np.zeros_like(x[0]), np.zeros_like(x[1])]
    Vp = dx
    mp = rho * Vp
    dt = a.cfl * h / np.sqrt(E / rho)
    pad = int(np.ceil(a.v0 * a.end / h)) + 2
    nn = 2 * a.cells + 1 + 2 * pad
    x0n = -pad * h
    hist = np.zeros(nn)

    def weights(xp):
        i = np.floor((xp - x0n) / h).astype(int)
        f = (xp - x0n) / h - i
        return i, np.stack([1 - f, f], 1), np.stack([-np.ones_like(f) / h, np.ones_like(f) / h], 1)

    def scatter(i, w, q):
        out = np.zeros(nn)
        for k in range(2):
            np.add.at(out, i + k, w[:, k] * q)
        return out

    def gather(i, w, g):
        return (w * g[np.stack([i, i + 1], 1)]).sum(1)

    energies = []
    for step in range(int(a.end / dt)):
        if step > 0 and any(xj.min() < x0n + h or xj.max() > x0n + (nn - 2) * h for xj in x):
            raise SystemExit(f"diverged: a particle left the grid at t = {step * dt:.4g} ms "
                             f"(energy {energies[-1] / energies[0]:.3g} E0)")
        fields = []
        for j in range(2):
            i, w, g = weights(x[j])
            m = scatter(i, w, np.full_like(x[j], mp))
            fields.append(dict(i=i, w=w, g=g, m=m, p=scatter(i, w, mp * v[j]),
                               mu=scatter(i, w, mp * u[j]), vol=scatter(i, w, np.full_like(x[j], Vp)),
                               f=sum(np.bincount(i + k, -g[:, k] * Vp * s[j], minlength=nn)
                                     for k in range(2))))
        a_, b_ = fields
        both = (a_["m"] > 0) & (b_["m"] > 0)
        safe = lambda q: np.where(both, q, 1.0)
        delta = np.where(both, b_["mu"] / safe(b_["m"]) - a_["mu"] / safe(a_["m"]), 0.0)
        if a.delta == "nodal":
            delta = np.where(both, hist, 0.0)
        area = np.where(both, np.sqrt(2 * (a_["vol"] + b_["vol"]) * np.minimum(a_["vol"], b_["vol"])) / h, 0.0)
        F = a.Dn * area * delta  # on a, toward b (+x)
        energy_int = 0.5 * (a.Dn * area * delta ** 2).sum()
        fi = [F, -F]
        if a.force == "consistent":
            for j, sign in ((0, 1.0), (1, -1.0)):
                fl = fields[j]
                share = sum(F[fl["i"] + k] * fl["w"][:, k] / np.where(fl["m"][fl["i"] + k] > 0, fl["m"][fl["i"] + k], 1)
                            for k in range(2)) * mp
                fi[j] = scatter(fl["i"], fl["w"], sign * share)
        K = sum(0.5 * mp * (vj ** 2).sum() for vj in v)
        U = sum(0.5 * Vp * (sj ** 2).sum() / E for sj in s)
        energies.append(K + U + energy_int)
        new_velocity = []
        for j in range(2):
            fl = fields[j]
            ok = fl["m"] > 0
            m = np.where(ok, fl["m"], 1.0)
            v_old = np.where(ok, fl["p"] / m, 0.0)
            v_new = np.where(ok, (fl["p"] + dt * (fl["f"] + fi[j])) / m, 0.0)
            new_velocity.append(v_new)
            i, w, g = fl["i"], fl["w"], fl["g"]
            v_grid = gather(i, w, v_new)
            v[j] = v[j] + gather(i, w, v_new - v_old)  # FLIP
            x[j] = x[j] + dt * v_grid
            if a.scheme == "usl":
                u[j] = u[j] + dt * v_grid
                rate = gather(i, g, v_new)
            else:  # MUSL: strain from the velocities of the updated particles
                mr = scatter(i, w, np.full_like(v[j], mp))
                v_remap = np.where(mr > 0, scatter(i, w, mp * v[j]) / np.where(mr > 0, mr, 1.0), 0.0)
                rate = gather(i, g, v_remap)
                if a.displacement == "anchored":  # this step's start plus its remapped move
                    u[j] = x[j] - dt * v_grid - x_ref[j] + dt * gather(i, w, v_remap)
                else:
                    u[j] = u[j] + dt * (gather(i, w, v_remap) if a.displacement == "remap" else v_grid)
            s[j] = s[j] + dt * E * rate
        hist = np.where(both, hist + dt * (new_velocity[1] - new_velocity[0]), 0.0)
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
    p.add_argument("--scheme", choices=["musl", "usl"], default="musl")
    p.add_argument("--delta", choices=["extrapolated", "nodal"], default="extrapolated")
    p.add_argument("--force", choices=["nodal", "consistent"], default="nodal")
    p.add_argument("--displacement", choices=["grid", "remap", "anchored"], default="grid")
    a = p.parse_args()
    e = run(a)
    print(f"Dn {a.Dn:g} ppc {a.ppc} cfl {a.cfl:g} {a.scheme} delta={a.delta} force={a.force} "
          f"displacement={a.displacement}: (K+U+U_int)/E0 at {a.end:g} ms {e[-1]:.4f}, max {e.max():.4f}")


if __name__ == "__main__":
    main()
