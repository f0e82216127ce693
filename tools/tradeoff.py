#!/usr/bin/python3
"""Speed against accuracy: error of each validation case against its exact
answer, as a function of cost, over a grid of solver settings.

For each case the tool runs `mmpm sweep` once per (cell level, knob): the
knob takes each of its values while every other setting stays at the
case's base (a star design around the base, repeated at each cell size).
Every run's error comes from its run.h5 / summary.json and the reference
from tools/analytic.py. It writes, per case,

    results/tradeoff/<case>/points.csv   settings, error, wall_s, ns/particle-step
    results/tradeoff/<case>/tradeoff.png error vs wall time and vs ns/particle-step,
                                          the Pareto front marked
and results/tradeoff/summary.md: for each case the cheapest settings within
1 % and within 0.1 % of the reference (the README's "Choosing settings").

    tools/tradeoff.py [--cases series_bars,dls,sphere,incline] [--quick]
                      [--jobs 2] [--mmpm build/mmpm] [--out results/tradeoff]
"""
import argparse
import csv
import json
import math
import os
import subprocess
import sys
import tomllib

import h5py
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import analytic  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


# ---------------------------------------------------------------- measurements
def final_snapshot(run_dir):
    with h5py.File(os.path.join(run_dir, "run.h5"), "r") as f:
        g = f["particles"]
        step = sorted(g.keys())[-1]
        return {k: g[step][k][()] for k in g[step].keys()}


def summary(run_dir):
    with open(os.path.join(run_dir, "summary.json")) as f:
        return json.load(f)


def scene_of(run_dir):
    with open(os.path.join(run_dir, "scene.toml"), "rb") as f:
        return tomllib.load(f)


def series_bars_error(run_dir):
    """Compliance u_top / P of two bars joined by a normal interface (docs/validation.md §1)."""
    sc = scene_of(run_dir)
    snap = final_snapshot(run_dir)
    x, d = snap["position"], snap["displacement"]
    y0 = x[:, 1] - d[:, 1]
    top = np.isclose(y0, y0.max())
    u_top = d[top, 1].mean()
    mat = sc["material"][0]
    width = sc["body"][0]["max"][0] - sc["body"][0]["min"][0]
    t = sc["simulation"].get("thickness", 1.0)
    traction = sc["load"][0]["traction"][1]
    P = traction * width * t
    L1 = sc["body"][0]["max"][1] - sc["body"][0]["min"][1]
    L2 = y0.max() - sc["body"][1]["min"][1]  # the load acts on the top particle row
    Dn = sc["interaction"][0]["Dn"]
    Dn = math.inf if Dn == "perfect" else float(Dn)
    ref = analytic.series_bars(mat["E"], L1, mat["E"], L2, Dn, width * t, P)["compliance"]
    return u_top / P, ref


def dls_error(run_dir):
    """Stiffness k = P^2 / (2U) of the double lap shear specimen vs the shear-lag solution."""
    sc = scene_of(run_dir)
    e = summary(run_dir)["energy"]
    U = e["strain"] + e["interface"]
    t = sc["simulation"].get("thickness", 1.0)
    P = 2.0 * 1.0 * t  # central layer: 2 MPa on 1 mm x depth
    Dt = sc["interaction"][0]["Dt"]
    Dt = math.inf if Dt == "perfect" else float(Dt)
    geom = analytic.DlsGeometry()
    geom.depth = t
    return P * P / (2 * U), analytic.dls_stiffness(Dt, geom)


def sphere_error(run_dir):
    """Bulk modulus from energy, K = 2U / (9 l^3 eps0^2) (P-35), vs the CSA solution."""
    sc = scene_of(run_dir)
    e = summary(run_dir)["energy"]
    U = e["strain"] + e["interface"]
    mats = {m["name"]: m for m in sc["material"]}
    glass, poly = mats["glass"], mats["polymer"]
    l = 1.0
    eps0 = None
    for b in sc["boundary"]:
        disp = b.get("displacement")
        if disp and max(abs(v) for v in disp) > 0:
            eps0 = max(abs(v) for v in disp) / l
    a = next(b for b in sc["body"] if b["shape"] == "sphere")["radius"]
    phi = math.pi * a ** 3 / 6.0 / l ** 3
    D = sc["interaction"][0]["Dn"]
    D = math.inf if D == "perfect" else float(D)
    ref = analytic.csa_bulk(analytic.bulk_modulus(glass["E"], glass["nu"]),
                            analytic.bulk_modulus(poly["E"], poly["nu"]),
                            analytic.shear_modulus(poly["E"], poly["nu"]), phi, a, D)
    return 2 * U / (9 * l ** 3 * eps0 ** 2), ref


def incline_error(run_dir):
    """Acceleration of a block sliding on a rigid floor under gravity tilted by theta."""
    sc = scene_of(run_dir)
    snap = final_snapshot(run_dir)
    s = summary(run_dir)
    mat = np.asarray(snap["material"]).reshape(-1)
    block = mat == 0
    ux = snap["displacement"][block, 0].mean()
    t = s["end_time"]
    g = next(l for l in sc["load"] if l["kind"] == "gravity")["acceleration"]
    G = math.hypot(g[0], g[1])
    sin_t, cos_t = g[0] / G, -g[1] / G
    mu = sc["interaction"][0].get("friction", 0.0)
    ref = max(0.0, G * (sin_t - mu * cos_t))
    ramp = next(l for l in sc["load"] if l["kind"] == "gravity").get("ramp", 0.0)
    # u = a t^2 / 2 for a load at once; a linear ramp of length r removes a r t / 2 - a r^2 / 6.
    a = ux / (0.5 * t * t - 0.5 * ramp * t + ramp * ramp / 6.0)
    return a, ref


# --------------------------------------------------------------------- cases
# base: overrides applied to every run; knobs: key -> values (TOML text).
CASES = {
    "series_bars": dict(
        scene="inputs/series_bars.toml", measure=series_bars_error, cell_levels=[1.0, 0.5],
        knobs={
            "grid.shape": ['"linear"', '"gimp"', '"bspline2"'],
            "simulation.cfl": ["0.2", "0.5", "0.9"],
            "simulation.scheme": ['"USL"', '"USF"', '"MUSL"'],
            "simulation.flip": ["1.0", "0.99", "0.9"],
            "simulation.precision": ['"double"', '"float"'],
            "grid.damping": ["10.0", "20.0", "40.0"],
            "interaction[0].area": ['"paper"', '"closed"'],
        }),
    "dls": dict(
        scene="inputs/dls.toml", measure=dls_error, cell_levels=[1.0, 0.5],
        knobs={
            "interaction[0].normal": ['"specified"', '"mvg"', '"avg"'],
            "interaction[0].min_volume": ["0.0", "0.85"],
            "simulation.cfl": ["0.3", "0.5", "0.9"],
            "simulation.flip": ["1.0", "0.99", "0.9"],
            "simulation.precision": ['"double"', '"float"'],
            "grid.damping": ["50.0", "100.0", "200.0"],
            "interaction[0].area": ['"paper"', '"closed"'],
        }),
    "sphere": dict(
        scene="inputs/sphere_in_cube.toml", measure=sphere_error, cell_levels=[1.0],
        knobs={
            "simulation.cfl": ["0.3", "0.5"],
            "simulation.precision": ['"double"', '"float"'],
            "interaction[0].integration": ['"explicit"', '"exact"'],
            "interaction[0].area": ['"paper"', '"closed"'],
        }),
    "incline": dict(
        scene="inputs/incline_block.toml", measure=incline_error, cell_levels=[1.0, 0.5],
        knobs={
            "interaction[0].normal": ['"rigid"', '"mvg"', '"avg"'],
            "simulation.cfl": ["0.3", "0.5", "0.9"],
            "simulation.flip": ["1.0", "0.99"],
            "simulation.precision": ['"double"', '"float"'],
            "grid.shape": ['"linear"', '"gimp"'],
        }),
}


def cell_overrides(scene_path, factor):
    """grid.cell scaled by factor, grid.cells scaled to keep the grid's extent."""
    with open(scene_path, "rb") as f:
        g = tomllib.load(f)["grid"]
    cell = [c * factor for c in g["cell"]]
    cells = [int(round(n / factor)) for n in g["cells"]]
    fmt = lambda v: "[" + ",".join(repr(x) for x in v) + "]"
    return [f"grid.cell={fmt(cell)}", f"grid.cells={fmt(cells)}"]


def run_sweep(mmpm, scene, param, values, sets, out, jobs):
    cmd = [mmpm, "sweep", scene, "--param", param, "--values", ",".join(values),
           "--jobs", str(jobs), "--out", out, "--quiet"]
    for s in sets:
        cmd += ["--set", s]
    subprocess.run(cmd, check=False)
    rows = []
    with open(os.path.join(out, "sweep.csv")) as f:
        for row in csv.DictReader(f):
            rows.append(row)
    return rows


def pareto(points):
    """Indices of the points no other point beats in both cost and error."""
    order = sorted(range(len(points)), key=lambda i: (points[i][0], points[i][1]))
    front, best = [], math.inf
    for i in order:
        if points[i][1] < best:
            front.append(i)
            best = points[i][1]
    return front


def plot(case, rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    for ax, key, label in ((axes[0], "wall_s", "wall time (s)"),
                           (axes[1], "ns_per_particle_step", "ns per particle-step")):
        pts = [(float(r[key]), max(float(r["rel_error"]), 1e-7)) for r in rows]
        front = set(pareto(pts))
        for i, (c, e) in enumerate(pts):
            ax.loglog(c, e, "o", color="C3" if i in front else "C0", ms=6 if i in front else 4)
        fr = sorted(pts[i] for i in front)
        ax.loglog([p[0] for p in fr], [p[1] for p in fr], "-", color="C3", lw=1, label="Pareto front")
        ax.axhline(1e-2, color="grey", ls=":", lw=0.8)
        ax.axhline(1e-3, color="grey", ls="--", lw=0.8)
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.set_xlabel(label)
        ax.set_ylabel("relative error")
        ax.legend()
    fig.suptitle(f"{case}: error against cost")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cases", default="series_bars,dls,incline,sphere")
    ap.add_argument("--quick", action="store_true", help="one cell level, two knobs per case")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--mmpm", default=os.path.join(ROOT, "build", "mmpm"))
    ap.add_argument("--out", default=os.path.join(ROOT, "results", "tradeoff"))
    args = ap.parse_args()
    report = ["# Choosing settings (tools/tradeoff.py)", "",
              "| case | reference | cheapest within 1 % | cheapest within 0.1 % |", "| --- | --- | --- | --- |"]
    for case in args.cases.split(","):
        spec = CASES[case]
        scene = os.path.join(ROOT, spec["scene"])
        if not os.path.exists(scene):
            print(f"{case}: {spec['scene']} missing, skipped")
            continue
        levels = spec["cell_levels"][:1] if args.quick else spec["cell_levels"]
        knobs = dict(list(spec["knobs"].items())[:2]) if args.quick else spec["knobs"]
        rows = []
        for level in levels:
            sets = cell_overrides(scene, level) if level != 1.0 else []
            for param, values in knobs.items():
                out = os.path.join(args.out, case, f"cell{level:g}", param.replace("[", "_").replace("]", ""))
                for r in run_sweep(args.mmpm, scene, param, values, sets, out, args.jobs):
                    if r["status"] != "ok":
                        print(f"{case} {param}={r['value']}: failed", file=sys.stderr)
                        continue
                    try:
                        got, ref = spec["measure"](r["directory"])
                    except Exception as e:  # a run without the data a measure needs
                        print(f"{case} {param}={r['value']}: {e}", file=sys.stderr)
                        continue
                    rows.append(dict(case=case, cell_factor=level, knob=param, value=r["value"],
                                     measured=got, reference=ref,
                                     rel_error=abs(got - ref) / abs(ref) if ref else abs(got),
                                     wall_s=r["wall_s"], ns_per_particle_step=r["ns_per_particle_step"],
                                     steps=r["steps"]))
        if not rows:
            continue
        os.makedirs(os.path.join(args.out, case), exist_ok=True)
        with open(os.path.join(args.out, case, "points.csv"), "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
            w.writeheader()
            w.writerows(rows)
        plot(case, rows, os.path.join(args.out, case, "tradeoff.png"))

        def cheapest(tol):
            ok = [r for r in rows if r["rel_error"] <= tol]
            if not ok:
                return "none reached"
            r = min(ok, key=lambda r: float(r["wall_s"]))
            return (f"cell x{r['cell_factor']:g}, {r['knob']}={r['value']} "
                    f"({float(r['wall_s']):.2f} s, err {100 * r['rel_error']:.3f} %)")
        report.append(f"| {case} | {rows[0]['reference']:.6g} | {cheapest(1e-2)} | {cheapest(1e-3)} |")
        print(f"{case}: {len(rows)} runs -> {os.path.join(args.out, case)}")
    with open(os.path.join(args.out, "summary.md"), "w") as f:
        f.write("\n".join(report) + "\n")
    print("\n".join(report))


if __name__ == "__main__":
    main()
