#!/usr/bin/env python3
"""USF with linear shapes under load, reduced to one dimension (docs/validation.md §3.11).

A bar standing on a fixed base node under ramped gravity and grid damping, the
1D form of the block that `mmpm` stops on (E the confined modulus M of the
2D block, 2 particles per cell, h = 0.25 mm). Three orderings of the same
step are run side by side:

  USF        the textbook order (Bardenhagen 2002), as mmpm runs it: the
             strain of step n+1 from the momenta extrapolated at x^n, with
             the gradients at x^n;
  USF-prev   the same, but the gradients taken at x^{n-1}, where the
             particles were while the motion those momenta carry happened;
  MUSL       mmpm's default.

Textbook USF goes unstable at cfl 0.5 and 0.3 (and at 0.1 with FLIP it
drifts); USF-prev runs at every cfl and agrees with MUSL. That is the
evidence for the cause written in §3.11: the strain of a motion is read in
the cell the particle ended in, not the one it moved through, and with linear
shapes the two differ by a jump of the gradient at every crossing.

Run: python3 tools/usf_cell_crossing.py   (numpy; about 10 s)
"""
import numpy as np

H = 0.25          # cell (mm)
E = 134.6         # confined modulus of E = 100, nu = 0.3 (MPa)
RHO = 1.0e-3      # g/mm^3
GRAVITY = 110.0   # mm/ms^2, ramped in over RAMP
RAMP = 0.5        # ms
DAMPING = 20.0    # grid damping, 1/ms
LENGTH = 16.0     # bar length (mm), on the base node at Y0
Y0 = 3.0
PPC = 2


def run(order, cfl, flip, end=1.0):
    nodes = int((Y0 + LENGTH + 2) / H) + 4
    n = int(LENGTH / H) * PPC
    x = Y0 + (np.arange(n) + 0.5) * H / PPC
    volume = np.full(n, H / PPC)
    mass = RHO * volume
    v = np.zeros(n)
    stress = np.zeros(n)
    dt = cfl * H / np.sqrt(E / RHO)
    base = int(round(Y0 / H))
    x_prev = x.copy()
    scatter = lambda cell, w: np.bincount(cell, w, minlength=nodes)[:nodes]
    t, peak_kinetic = 0.0, 0.0
    while t < end:
        g = -GRAVITY * min(1.0, (t + 0.5 * dt) / RAMP)
        cell = np.floor(x / H).astype(int)
        w1 = x / H - cell
        w0 = 1.0 - w1
        m_i = scatter(cell, mass * w0) + scatter(cell + 1, mass * w1)
        p_i = scatter(cell, mass * v * w0) + scatter(cell + 1, mass * v * w1)
        heavy = m_i > 0

        def velocity(p):
            out = np.zeros(nodes)
            out[heavy] = p[heavy] / m_i[heavy]
            out[base] = 0.0
            return out

        v_i = velocity(p_i)
        if order in ("USF", "USF-prev"):
            at = cell if order == "USF" else np.floor(x_prev / H).astype(int)
            stress += E * dt * (v_i[at + 1] - v_i[at]) / H
        f_i = scatter(cell, volume * stress / H) - scatter(cell + 1, volume * stress / H) + m_i * g
        a_i = np.zeros(nodes)
        a_i[heavy] = f_i[heavy] / m_i[heavy]
        a_i -= DAMPING * v_i
        a_i[base] = 0.0
        v_new = v_i + dt * a_i
        v_new[base] = 0.0
        v_pic = v_new[cell] * w0 + v_new[cell + 1] * w1
        dv = v_new - v_i
        v = flip * (v + dv[cell] * w0 + dv[cell + 1] * w1) + (1.0 - flip) * v_pic
        x_prev = x.copy()
        x = x + dt * v_pic
        if order == "MUSL":
            v_i = velocity(scatter(cell, mass * v * w0) + scatter(cell + 1, mass * v * w1))
            stress += E * dt * (v_i[cell + 1] - v_i[cell]) / H
        t += dt
        kinetic = 0.5 * np.sum(mass * v * v)
        if not np.isfinite(kinetic) or kinetic > 10.0 or x.max() > (nodes - 3) * H:
            return f"unstable at t = {t:.3f} ms"
        if t > 0.6:
            peak_kinetic = max(peak_kinetic, kinetic)
    top = x[-1] - (Y0 + LENGTH - 0.5 * H / PPC)
    exact = -RHO * GRAVITY * LENGTH**2 / (2.0 * E)
    return f"top u {top:+.5f} mm (static {exact:+.5f}), peak K after 0.6 ms {peak_kinetic:.1e} mJ"


def main():
    for cfl in (0.5, 0.3, 0.1):
        for flip in (0.0, 1.0):
            for order in ("USF", "USF-prev", "MUSL"):
                print(f"cfl {cfl}  flip {flip:.0f}  {order:9s} {run(order, cfl, flip)}")


if __name__ == "__main__":
    main()
