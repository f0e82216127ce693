#!/usr/bin/python3
"""Re-create the result figures of Nairn (2013) with mmpm and the exact solutions.

    tools/figure.py FIG [--quick] [--jobs N] [--mmpm build/mmpm] [--out results/figures]

FIG is one of fig5 fig7 fig8 fig9 fig10 fig11 fig12 fig13 (or "all"). Each figure runs the
`mmpm sweep`s it needs into results/figures/<fig>/<series>/ (skipped when a finished
sweep with the same command is already there, also in another figure's folder), then
writes results/figures/<fig>/<fig>.png and <fig>.csv (one row per MPM point).

  fig5   two-layer interface energy density vs 1/Dt, several cell sizes (no exact curve)
  fig7   DLS stiffness k = P^2/(2U) vs 1/Dt: SN, MVG, AVG against shear-lag theory
  fig8   two-layer energy density, interface on a grid line vs on cell midplanes
  fig9   DLS stiffness vs rotation angle, regular mesh and dy = 2 dx (h-perp of P-22)
  fig10  two-layer energy density: SN / MVG / AVG, grid / mid, Omega_min screening, Dn = Dt
  fig11  DLS stiffness with the interfaces on cell midplanes: normal methods and fixes
  fig12  sphere in cube: K from energy (P-35) vs 1/D, cell sizes, shorter dt, no force limit
  fig13  sphere in cube: K from mean pressure (P-36) vs 1/D, micro- and nanoparticle

--quick uses coarse cells and few values (each figure a few minutes on 2 cores);
without it the resolutions approach the paper's (hours for fig12/13).

Derived quantities (units mm, ms, g -> N, MPa, mJ):
  interface energy density [N/m^2 = J/m^3] = U_interface [mJ] / V [mm^3] * 1e6
      (1 mJ/mm^3 = 1e-3 J / 1e-9 m^3 = 1e6 J/m^3); two-layer V = 8 x 20 x 4 = 640 mm^3
  DLS k [N/mm] = P^2 / (2 (U_strain + U_interface)), P = 2 N (1 mm depth)
  K_energy = 2 U / (9 l^3 eps0^2)  (P-35);  K_pressure = <sigma> / (3 eps0)  (P-36) with
      <sigma> = mean over the faces x=l, y=l, z=l of (normal reaction / l^2), read from
      the run.h5 series reaction_box3_x, reaction_box4_y, reaction_box5_z.
"""
from __future__ import annotations

import argparse
import csv
import json
import math
import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field

import numpy as np

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

try:
    import h5py  # noqa: E402
except ImportError:  # pragma: no cover
    h5py = None

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)
import analytic as an  # noqa: E402

INPUTS = os.path.join(ROOT, "inputs")
TWO_LAYER_VOLUME = 8.0 * 20.0 * 4.0  # mm^3
DLS_P = 2.0  # N
EPS0 = 0.005


def fmt(v: float) -> str:
    """A TOML number."""
    if isinstance(v, str):
        return v
    if math.isinf(v):
        return '"perfect"'
    s = repr(float(v))
    return s


def vec(*v) -> str:
    return "[" + ",".join(fmt(x) for x in v) + "]"


# --------------------------------------------------------------------------- running sweeps
@dataclass
class Sweep:
    """One `mmpm sweep` (one series of a figure)."""
    name: str                 # series folder name (unique within the figure)
    scene: str                # file in inputs/
    param: str
    values: list              # TOML value strings
    sets: list = field(default_factory=list)
    x: list | None = None     # x coordinate of each value in the figure (default: float(value))
    label: str = ""
    meta: dict = field(default_factory=dict)

    def command(self, mmpm, outdir, jobs, threads):
        cmd = [mmpm, "sweep", os.path.join(INPUTS, self.scene), "--param", self.param,
               "--values", ",".join(self.values), "--jobs", str(jobs), "--out", outdir,
               "--quiet"]
        if threads:
            cmd += ["--threads", str(threads)]
        for s in self.sets:
            cmd += ["--set", s]
        return cmd

    def key(self):
        return json.dumps({"scene": self.scene, "param": self.param, "values": self.values,
                           "sets": self.sets}, sort_keys=True)


class Runner:
    def __init__(self, mmpm, jobs, root, force=False):
        self.mmpm, self.jobs, self.root, self.force = mmpm, max(1, jobs), root, force

    def _done(self, d, sw):
        try:
            with open(os.path.join(d, "task.json")) as f:
                if f.read() != sw.key():
                    return False
            with open(os.path.join(d, "sweep.csv")) as f:
                return len(list(csv.DictReader(f))) == len(sw.values)
        except OSError:
            return False

    def _cached(self, sw):
        """A finished sweep with the same command anywhere under the figures folder."""
        if not os.path.isdir(self.root):
            return None
        for fig in sorted(os.listdir(self.root)):
            fd = os.path.join(self.root, fig)
            if not os.path.isdir(fd):
                continue
            for s in sorted(os.listdir(fd)):
                d = os.path.join(fd, s)
                if os.path.isdir(d) and self._done(d, sw):
                    return d
        return None

    def _run(self, sw, d, jobs, threads):
        os.makedirs(d, exist_ok=True)
        cmd = sw.command(self.mmpm, d, jobs, threads)
        print("  $", " ".join(cmd), flush=True)
        r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        if r.returncode not in (0, 3):  # 3: some runs failed (recorded in sweep.csv)
            print(r.stdout)
            raise SystemExit(f"mmpm sweep failed ({r.returncode}) for {sw.name}")
        with open(os.path.join(d, "task.json"), "w") as f:
            f.write(sw.key())
        return d

    def run(self, fig, sweeps):
        """Runs the sweeps of a figure; returns {name: folder}."""
        out = {}
        pending = []
        for sw in sweeps:
            d = os.path.join(self.root, fig, sw.name)
            if not self.force and self._done(d, sw):
                out[sw.name] = d
                continue
            c = None if self.force else self._cached(sw)
            if c:
                print(f"  (reusing {os.path.relpath(c, ROOT)} for {sw.name})")
                out[sw.name] = c
                continue
            pending.append((sw, d))
        many = [(s, d) for s, d in pending if len(s.values) >= self.jobs]
        few = [(s, d) for s, d in pending if len(s.values) < self.jobs]
        for sw, d in many:  # one sweep at a time, its values in parallel
            out[sw.name] = self._run(sw, d, self.jobs, None)
        if few:  # short sweeps side by side, one thread each
            with ThreadPoolExecutor(self.jobs) as ex:
                futs = {ex.submit(self._run, sw, d, 1, 1): sw.name for sw, d in few}
                for f, name in futs.items():
                    out[name] = f.result()
        return out


def read_sweep(d, sw: Sweep):
    """Rows of a finished sweep with float energies, plus the x coordinate."""
    rows = []
    with open(os.path.join(d, "sweep.csv")) as f:
        for k, r in enumerate(csv.DictReader(f)):
            row = dict(r)
            row["x"] = sw.x[k] if sw.x is not None else float(sw.values[k].strip('"'))
            row["ok"] = r["status"] == "ok"
            for key in ("kinetic", "strain", "interface", "external_work", "damping", "wall_s",
                        "force_limited_nodes"):
                try:
                    row[key] = float(r[key])
                except (ValueError, KeyError):
                    row[key] = float("nan")
            row["dir"] = os.path.join(d, str(k))
            rows.append(row)
    return rows


def series_last(run_dir, names):
    """Last value of run.h5 series columns."""
    if h5py is None:
        raise SystemExit("h5py is needed (Debian: python3-h5py)")
    with h5py.File(os.path.join(run_dir, "run.h5"), "r") as f:
        s = f["series"]
        return {n: float(s[n][-1]) for n in names}


def write_csv(path, header, rows):
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(header)
        for r in rows:
            w.writerow(r)
    print("wrote", os.path.relpath(path, ROOT))


def save(fig, path):
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)
    print("wrote", os.path.relpath(path, ROOT))


# --------------------------------------------------------------------------- two-layer
def two_layer_sets(h, midplane=False, normal="specified", omega_min=0.0, Dn='"perfect"',
                   end_time=0.8):
    x0 = -1.0 - (0.5 * h if midplane else 0.0)
    return [f"grid.cell={vec(h, h)}", f"grid.origin={vec(x0, -1.0)}",
            f"grid.cells=[{int(round(10 / h))},{int(round(22 / h))}]",
            "boundary[0].where={min=[-2.0,-2.0],max=[10.0,0.0]}",
            f'interaction[0].normal="{normal}"', f"interaction[0].min_volume={fmt(omega_min)}",
            f"interaction[0].Dn={Dn}", f"simulation.end_time={fmt(end_time)}",
            "output.every=0.0"]


def two_layer_dt_values(inv):
    return [fmt(1.0 / v) for v in inv]


def energy_density(row):
    return row["interface"] / TWO_LAYER_VOLUME * 1e6  # N/m^2


def plot_two_layer(fig_name, runner, outdir, series, title):
    dirs = runner.run(fig_name, series)
    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    rows = []
    markers = "osD^v<>ph*"
    for i, sw in enumerate(series):
        data = read_sweep(dirs[sw.name], sw)
        xs = [r["x"] for r in data if r["ok"]]
        ys = [energy_density(r) for r in data if r["ok"]]
        for r in data:
            rows.append([sw.label, r["x"], energy_density(r) if r["ok"] else "", r["interface"],
                         r["strain"], r["kinetic"], r["status"], r["dir"]])
        ax.plot(xs, ys, marker=markers[i % len(markers)], ls=sw.meta.get("ls", "-"), label=sw.label,
                mfc=sw.meta.get("mfc", None))
    ax.set_xlabel("1/Dt (mm/MPa)")
    ax.set_ylabel("interface energy density (N/m$^2$)")
    ax.set_title(title, fontsize=10)
    ax.set_xlim(0, 1.02)
    ax.set_ylim(bottom=0)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    save(fig, os.path.join(outdir, f"{fig_name}.png"))
    write_csv(os.path.join(outdir, f"{fig_name}.csv"),
              ["series", "inv_Dt_mm_per_MPa", "energy_density_N_per_m2", "U_interface_mJ",
               "U_strain_mJ", "kinetic_mJ", "status", "run"], rows)


def fig5(runner, quick, outdir):
    inv = [0.1, 0.3, 0.6, 1.0] if quick else [0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0]
    hs = [0.5] if quick else [0.5, 0.25]
    series = [Sweep(f"h{h}", "two_layer.toml", "interaction[0].Dt", two_layer_dt_values(inv),
                    two_layer_sets(h), x=inv, label=f"2D MPM, {h} mm cells (SN, grid line)")
              for h in hs]
    plot_two_layer("fig5", runner, outdir, series,
                   "Fig. 5: two-layer interface energy density, Dn = perfect (no exact curve)")


def fig8(runner, quick, outdir):
    inv = [0.1, 0.3, 0.6, 1.0] if quick else [0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0]
    h = 0.5 if quick else 0.25
    series = [Sweep("grid", "two_layer.toml", "interaction[0].Dt", two_layer_dt_values(inv),
                    two_layer_sets(h), x=inv, label=f"grid line (corrected A_i), {h} mm"),
              Sweep("mid", "two_layer.toml", "interaction[0].Dt", two_layer_dt_values(inv),
                    two_layer_sets(h, midplane=True), x=inv,
                    label=f"cell midplanes (corrected A_i), {h} mm", meta={"ls": "--"})]
    plot_two_layer("fig8", runner, outdir, series,
                   "Fig. 8: interface on a grid line vs on cell midplanes (SN)")


def fig10(runner, quick, outdir):
    inv = [0.1, 0.4, 1.0] if quick else [0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0]
    h = 0.5 if quick else 0.25
    v = two_layer_dt_values(inv)
    spec = [("sn_grid", "SN (grid)", dict()),
            ("mvg_grid", "MVG (grid)", dict(normal="mvg")),
            ("avg_grid", "AVG (grid)", dict(normal="avg")),
            ("sn_mid", "SN (mid)", dict(midplane=True)),
            ("mvg_mid", "MVG (mid)", dict(midplane=True, normal="mvg")),
            ("avg_mid", "AVG (mid)", dict(midplane=True, normal="avg")),
            ("mvg_mid_om", "MVG (mid, $\\Omega_{min}$=0.75 A$_{cell}$)",
             dict(midplane=True, normal="mvg", omega_min=0.75)),
            ("avg_mid_om", "AVG (mid, $\\Omega_{min}$=0.75 A$_{cell}$)",
             dict(midplane=True, normal="avg", omega_min=0.75))]
    series = [Sweep(n, "two_layer.toml", "interaction[0].Dt", v, two_layer_sets(h, **kw), x=inv,
                    label=lab) for n, lab, kw in spec]
    # Dn = Dt: the swept key sets Dt, so Dn follows per value through separate sweeps.
    for n, lab, normal in (("mvg_mid_dn", "MVG (mid, Dn=Dt)", "mvg"), ("avg_mid_dn", "AVG (mid, Dn=Dt)", "avg")):
        for k, val in enumerate(v):
            series.append(Sweep(f"{n}_{k}", "two_layer.toml", "interaction[0].Dt", [val],
                                two_layer_sets(h, midplane=True, normal=normal, Dn=val), x=[inv[k]],
                                label=lab, meta={"group": n, "ls": ":"}))
    dirs = runner.run("fig10", series)
    fig, ax = plt.subplots(figsize=(6.8, 4.8))
    rows, groups = [], {}
    for sw in series:
        g = sw.meta.get("group", sw.name)
        groups.setdefault(g, (sw.label, sw.meta.get("ls", "-"), []))
        for r in read_sweep(dirs[sw.name], sw):
            groups[g][2].append(r)
    markers = "osD^v<>ph*"
    for i, (g, (lab, ls, data)) in enumerate(groups.items()):
        data.sort(key=lambda r: r["x"])
        ok = [r for r in data if r["ok"]]
        ax.plot([r["x"] for r in ok], [energy_density(r) for r in ok], marker=markers[i % 10], ls=ls,
                label=lab)
        for r in data:
            rows.append([lab, r["x"], energy_density(r) if r["ok"] else "", r["interface"], r["strain"],
                         r["status"], r["dir"]])
    ax.set_xlabel("1/Dt (mm/MPa)")
    ax.set_ylabel("interface energy density (N/m$^2$)")
    ax.set_title(f"Fig. 10: normal methods, two-layer, {h} mm cells (no exact curve)", fontsize=10)
    ax.set_xlim(0, 1.02)
    ax.set_ylim(bottom=0)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    save(fig, os.path.join(outdir, "fig10.png"))
    write_csv(os.path.join(outdir, "fig10.csv"),
              ["series", "inv_Dt_mm_per_MPa", "energy_density_N_per_m2", "U_interface_mJ", "U_strain_mJ",
               "status", "run"], rows)


# --------------------------------------------------------------------------- DLS
def dls_sets(h, hy=None, midplane=False, normal="specified", omega_min=0.0, Dn='"perfect"',
             end_time=0.25):
    hy = hy or h
    x0 = -1.0 - (0.5 * h if midplane else 0.0)
    return [f"grid.cell={vec(h, hy)}", f"grid.origin={vec(x0, -1.0)}",
            f"grid.cells=[{int(round(5 / h))},{int(round(37 / hy))}]",
            f'interaction[0].normal="{normal}"', f"interaction[0].min_volume={fmt(omega_min)}",
            f"interaction[0].Dn={Dn}", f"simulation.end_time={fmt(end_time)}"]


def dls_k(row):
    return an.stiffness_from_energy(DLS_P, row["strain"] + row["interface"])


def inv_values(inv):
    return ['"perfect"' if v == 0 else fmt(1.0 / v) for v in inv]


def plot_dls_vs_dt(fig_name, runner, outdir, series, title):
    dirs = runner.run(fig_name, series)
    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    xs = np.linspace(0, 1.0, 201)
    ax.plot(xs, an.dls_stiffness_curve(xs), "k-", lw=1.5, label="shear lag (generalized, G$_A$=500)")
    cls = an.DlsMaterials(G_c=an.INF, G_o=an.INF)
    ax.plot(xs, an.dls_stiffness_curve(xs, mat=cls), "k:", lw=1, label="shear lag (classical)")
    rows = []
    markers = "osD^v<>ph*"
    groups = {}
    for sw in series:
        g = sw.meta.get("group", sw.name)
        groups.setdefault(g, (sw.label, []))
        groups[g][1].extend(read_sweep(dirs[sw.name], sw))
    for i, (g, (lab, data)) in enumerate(groups.items()):
        data.sort(key=lambda r: r["x"])
        ok = [r for r in data if r["ok"]]
        ax.plot([r["x"] for r in ok], [dls_k(r) for r in ok], marker=markers[i % 10], ls="none",
                mfc="none", ms=7, label=lab)
        for r in data:
            D = an.INF if r["x"] == 0 else 1 / r["x"]
            ex = an.dls(D)
            k = dls_k(r) if r["ok"] else float("nan")
            U = r["strain"] + r["interface"]
            rows.append([lab, r["x"], k if r["ok"] else "", ex["k"], (k / ex["k"] - 1) * 100 if r["ok"] else "",
                         r["interface"] / U if r["ok"] and U > 0 else "", ex["interface_fraction"],
                         r["status"], r["dir"]])
    ax.set_xlabel("1/Dt (mm/MPa)")
    ax.set_ylabel("stiffness k = P$^2$/(2U) (N/mm)")
    ax.set_title(title, fontsize=10)
    ax.set_xlim(-0.02, 1.02)
    ax.set_ylim(0, 650)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    save(fig, os.path.join(outdir, f"{fig_name}.png"))
    write_csv(os.path.join(outdir, f"{fig_name}.csv"),
              ["series", "inv_Dt_mm_per_MPa", "k_mpm_N_per_mm", "k_shear_lag", "error_percent",
               "interface_share_mpm", "interface_share_theory", "status", "run"], rows)


def fig7(runner, quick, outdir):
    if quick:
        h, inv, inv_other = 0.5, [0.0, 0.05, 0.2, 0.5, 1.0], [0.0, 0.2, 1.0]
    else:
        h = 0.25
        inv = inv_other = [0.0, 0.01, 0.02, 0.05, 0.1, 0.2, 0.3, 0.5, 0.7, 1.0]
    methods = [("sn", "SN", "specified", inv), ("mvg", "MVG", "mvg", inv_other), ("avg", "AVG", "avg", inv_other)]
    series = [Sweep(n, "dls.toml", "interaction[0].Dt", inv_values(v), dls_sets(h, normal=m), x=v,
                    label=f"MPM {lab}, {h} mm cells (grid line)") for n, lab, m, v in methods]
    plot_dls_vs_dt("fig7", runner, outdir, series, "Fig. 7: DLS stiffness vs interface compliance")


def fig11(runner, quick, outdir):
    inv = [0.0, 0.1, 0.5, 1.0] if quick else [0.0, 0.02, 0.05, 0.1, 0.2, 0.3, 0.5, 0.7, 1.0]
    h = 0.5 if quick else 0.25
    v = inv_values(inv)
    series = [Sweep("sn_mid", "dls.toml", "interaction[0].Dt", v, dls_sets(h, midplane=True), x=inv,
                    label="SN (mid)"),
              Sweep("mvg_mid", "dls.toml", "interaction[0].Dt", v, dls_sets(h, midplane=True, normal="mvg"),
                    x=inv, label="MVG (mid)"),
              Sweep("avg_mid", "dls.toml", "interaction[0].Dt", v, dls_sets(h, midplane=True, normal="avg"),
                    x=inv, label="AVG (mid)"),
              Sweep("mvg_mid_om", "dls.toml", "interaction[0].Dt", v,
                    dls_sets(h, midplane=True, normal="mvg", omega_min=0.85), x=inv,
                    label="MVG (mid, $\\Omega_{min}$=0.85 A$_{cell}$)"),
              Sweep("avg_mid_om", "dls.toml", "interaction[0].Dt", v,
                    dls_sets(h, midplane=True, normal="avg", omega_min=0.85), x=inv,
                    label="AVG (mid, $\\Omega_{min}$=0.85 A$_{cell}$)")]
    for n, lab, normal in (("mvg_mid_dn", "MVG (mid, Dn=Dt)", "mvg"), ("avg_mid_dn", "AVG (mid, Dn=Dt)", "avg")):
        for k, val in enumerate(v):
            series.append(Sweep(f"{n}_{k}", "dls.toml", "interaction[0].Dt", [val],
                                dls_sets(h, midplane=True, normal=normal, Dn=val), x=[inv[k]], label=lab,
                                meta={"group": n}))
    plot_dls_vs_dt("fig11", runner, outdir, series,
                   f"Fig. 11: DLS with interfaces on cell midplanes, {h} mm cells")


def rotated_dls_sets(theta, hx, hy, end_time=0.25):
    """Overrides that turn the whole DLS specimen by theta degrees about its centre."""
    a = math.radians(theta)
    c = (1.5, 17.5)
    corners = [(x, y) for x in (0.0, 3.0) for y in (0.0, 35.0)]
    rot = [(c[0] + math.cos(a) * (x - c[0]) - math.sin(a) * (y - c[1]),
            c[1] + math.sin(a) * (x - c[0]) + math.cos(a) * (y - c[1])) for x, y in corners]
    lo = [min(p[i] for p in rot) for i in (0, 1)]
    hi = [max(p[i] for p in rot) for i in (0, 1)]
    h = (hx, hy)
    # Keep the grid aligned with the unrotated specimen's lines (x = 0, y = 0 on nodes).
    org = [math.floor(lo[i] / h[i]) * h[i] - 2 * h[i] for i in (0, 1)]
    n = [int(math.ceil((hi[i] - org[i]) / h[i])) + 2 for i in (0, 1)]
    ax = (-math.sin(a), math.cos(a))
    nv = (math.cos(a), math.sin(a))
    s = [f"body[{k}].rotate={fmt(theta)}" for k in (1, 2)]
    s += [f"material[{k}].axis={vec(*ax)}" for k in (0, 1)]
    s += [f"interaction[0].normal_vector={vec(*nv)}", f"grid.cell={vec(hx, hy)}",
          f"grid.origin={vec(*org)}", f"grid.cells=[{n[0]},{n[1]}]", f"simulation.end_time={fmt(end_time)}",
          "interaction[0].Dt=10.0"]
    return s


def fig9(runner, quick, outdir):
    angles = [0, 30, 60, 90] if quick else [0, 10, 20, 30, 40, 45, 50, 60, 70, 80, 90]
    meshes = [("regular", 0.5, 0.5), ("dy2dx", 0.5, 1.0)] if quick else [("regular", 0.25, 0.25),
                                                                         ("dy2dx", 0.25, 0.5)]
    series = []
    for name, hx, hy in meshes:
        for th in angles:
            series.append(Sweep(f"{name}_{th}", "dls.toml", "body[0].rotate", [fmt(float(th))],
                                rotated_dls_sets(th, hx, hy), x=[float(th)],
                                label=(f"regular mesh {hx} mm" if name == "regular"
                                       else f"$\\Delta$y = 2$\\Delta$x ({hx} x {hy} mm), h$_\\perp$ method 1"),
                                meta={"group": name}))
    dirs = runner.run("fig9", series)
    k_exact = an.dls_stiffness(10.0)
    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    ax.axhline(k_exact, color="k", lw=1.5, label=f"shear lag, 1/Dt = 0.1 ({k_exact:.1f} N/mm)")
    groups, rows = {}, []
    for sw in series:
        groups.setdefault(sw.meta["group"], (sw.label, []))
        groups[sw.meta["group"]][1].extend(read_sweep(dirs[sw.name], sw))
    for i, (g, (lab, data)) in enumerate(groups.items()):
        data.sort(key=lambda r: r["x"])
        ok = [r for r in data if r["ok"]]
        ax.plot([r["x"] for r in ok], [dls_k(r) for r in ok], marker="os"[i % 2], ls="-" if i == 0 else ":",
                label=lab)
        for r in data:
            k = dls_k(r) if r["ok"] else ""
            rows.append([lab, r["x"], k, k_exact, (k / k_exact - 1) * 100 if r["ok"] else "", r["status"],
                         r["dir"]])
    ax.set_xlabel("rotation angle (degrees)")
    ax.set_ylabel("stiffness k (N/mm)")
    ax.set_title("Fig. 9: rotated DLS specimen, 1/Dt = 0.1 mm/MPa", fontsize=10)
    ax.set_xlim(-3, 93)
    ax.set_ylim(140, 280)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    save(fig, os.path.join(outdir, "fig9.png"))
    write_csv(os.path.join(outdir, "fig9.csv"),
              ["series", "angle_deg", "k_mpm_N_per_mm", "k_shear_lag", "error_percent", "status", "run"], rows)


# --------------------------------------------------------------------------- sphere in cube
KI, KM, GM = an.paper_csa_moduli()
PHI = math.pi / 6 * 0.7 ** 3


def cube_sets(h, ppc=2, scale=1.0, force_limit=True, cfl=None, end_time=0.015, integration="explicit",
              separation="displacement"):
    """Overrides for inputs/sphere_in_cube.toml; `scale` shrinks every length (and time)."""
    s = scale
    n = int(round(1.3 / h))
    out = [f"grid.cell={vec(h * s, h * s, h * s)}", f"grid.origin={vec(-0.1 * s, -0.1 * s, -0.1 * s)}",
           f"grid.cells=[{n},{n},{n}]", f"body[0].particles_per_cell={ppc}",
           f"body[1].particles_per_cell={ppc}",
           f"interaction[0].force_limit={'true' if force_limit else 'false'}",
           f'interaction[0].integration="{integration}"', f"simulation.end_time={fmt(end_time * s)}",
           f'interaction[0].separation="{separation}"']
    if cfl:
        out.append(f"simulation.cfl={fmt(cfl)}")
    if s != 1.0:
        out += [f"body[0].max={vec(s, s, s)}", f"body[1].radius={fmt(0.7 * s)}",
                f"body[1].clip={{min=[0.0,0.0,0.0],max={vec(s, s, s)}}}",
                f"grid.damping={fmt(1500.0 / s)}"]
        lo, hi = -0.1 * s, 1.2 * s
        boxes = [([lo, lo, lo], [0.0, hi, hi], "x"), ([lo, lo, lo], [hi, 0.0, hi], "y"),
                 ([lo, lo, lo], [hi, hi, 0.0], "z"), ([s, lo, lo], [hi, hi, hi], "x"),
                 ([lo, s, lo], [hi, hi, hi], "y"), ([lo, lo, s], [hi, hi, hi], "z")]
        for k, (a, b, _) in enumerate(boxes):
            out.append(f"boundary[{k}].where={{min={vec(*a)},max={vec(*b)}}}")
        for k, d in ((3, 0), (4, 1), (5, 2)):
            disp = [0.0, 0.0, 0.0]
            disp[d] = EPS0 * s
            out += [f"boundary[{k}].displacement={vec(*disp)}", f"boundary[{k}].ramp={fmt(0.003 * s)}"]
    return out


def cube_series(name, inv, label, dn_sets, **kw):
    """One series of 1/D values; Dn and Dt equal, so one sweep per value."""
    out = []
    for k, v in enumerate(inv):
        D = fmt(1.0 / v)
        out.append(Sweep(f"{name}_{k}", "sphere_in_cube.toml", "interaction[0].Dn", [D],
                         cube_sets(**kw) + [f"interaction[0].Dt={D}"] + dn_sets, x=[v], label=label,
                         meta={"group": name, "scale": kw.get("scale", 1.0)}))
    return out


def cube_moduli(row, scale):
    U = row["strain"] + row["interface"]
    l3 = scale ** 3
    Ke = an.bulk_from_energy(U, l3, EPS0)
    r = series_last(row["dir"], ["reaction_box3_x", "reaction_box4_y", "reaction_box5_z"])
    p = (r["reaction_box3_x"] + r["reaction_box4_y"] + r["reaction_box5_z"]) / 3.0 / scale ** 2
    return Ke, an.bulk_from_pressure(p, EPS0)


def plot_cube(fig_name, runner, outdir, series, which, title, nano=False):
    dirs = runner.run(fig_name, series)
    fig, ax = plt.subplots(figsize=(6.8, 4.8))
    lo = 1e-10 if nano else 1e-9
    xs = np.logspace(math.log10(lo), -1, 300)
    ax.plot(xs, an.csa_bulk_curve(xs, KI, KM, GM, PHI, an.A_MICRO), "k-", lw=1.5,
            label="CSA, r = 700 $\\mu$m (V 5.8)")
    if nano:
        ax.plot(xs, an.csa_bulk_curve(xs, KI, KM, GM, PHI, an.A_NANO), "k--", lw=1.5,
                label="CSA, r = 700 nm")
    ax.axhline(an.csa_bulk_perfect(KI, KM, GM, PHI), color="gray", ls=":", lw=1, label="CSA perfect")
    groups, rows = {}, []
    for sw in series:
        groups.setdefault(sw.meta["group"], (sw.label, sw.meta["scale"], []))
        groups[sw.meta["group"]][2].extend(read_sweep(dirs[sw.name], sw))
    markers = "osD^v<>ph*"
    for i, (g, (lab, scale, data)) in enumerate(groups.items()):
        data.sort(key=lambda r: r["x"])
        ok, bad = [], []
        for r in data:
            a = an.A_MICRO * scale
            ex = an.csa_bulk(KI, KM, GM, PHI, a, 1.0 / r["x"])
            if r["ok"]:
                Ke, Kp = cube_moduli(r, scale)
                ok.append((r["x"], Ke if which == "energy" else Kp))
                rows.append([lab, r["x"], Ke, Kp, ex, (Ke / ex - 1) * 100, (Kp / ex - 1) * 100,
                             r["interface"] / (r["strain"] + r["interface"]), int(r["force_limited_nodes"]),
                             r["status"], r["dir"]])
            else:
                bad.append(r["x"])
                why = (r.get("message") or r.get("stopped_by") or "")[:80]  # sweep.csv's message
                rows.append([lab, r["x"], "", "", ex, "", "", "", "", "failed: " + why, r["dir"]])
        line, = ax.semilogx([p[0] for p in ok], [p[1] for p in ok], marker=markers[i % 10], ls="-",
                            mfc="none", label=lab)
        if bad:
            ax.semilogx(bad, [7500] * len(bad), marker="x", ls="none", color=line.get_color(), ms=9,
                        label=f"{lab}: unstable")
    ax.set_xlabel("1/Dn = 1/Dt (mm/MPa)")
    ax.set_ylabel("bulk modulus K (MPa) from " + ("energy (P-35)" if which == "energy" else "pressure (P-36)"))
    ax.set_title(title, fontsize=10)
    ax.set_ylim(1000, 8000 if which == "energy" else 4000)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7)
    save(fig, os.path.join(outdir, f"{fig_name}.png"))
    write_csv(os.path.join(outdir, f"{fig_name}.csv"),
              ["series", "inv_D_mm_per_MPa", "K_energy_MPa", "K_pressure_MPa", "K_csa_MPa", "error_energy_percent",
               "error_pressure_percent", "interface_share", "force_limited_node_directions", "status", "run"], rows)


def fig12(runner, quick, outdir):
    if quick:
        inv = [1e-9, 1e-7, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2]
        series = cube_series("h100_ppc1", inv, "100 $\\mu$m, 1 ppc", [], h=0.1, ppc=1, end_time=0.012)
        # Without the limit K rises past the perfect interface's CSA and the run goes
        # unstable near the explicit spring's bound (docs/multimaterial.md §8): 1e-7 fails.
        series += cube_series("h100_ppc1_nolimit", [1e-7, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2],
                              "100 $\\mu$m, 1 ppc, no force limit", [], h=0.1, ppc=1, force_limit=False,
                              end_time=0.012)
        series += cube_series("h100_ppc1_exact", [1e-9, 1e-7, 1e-6, 1e-5],
                              "100 $\\mu$m, 1 ppc, exact integration", [], h=0.1, ppc=1,
                              integration="exact", end_time=0.012)
    else:
        inv = [1e-9, 1e-8, 1e-7, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2]
        series = cube_series("h100", inv, "100 $\\mu$m", [], h=0.1)
        series += cube_series("h050", inv, "50 $\\mu$m", [], h=0.05)
        series += cube_series("h100_shortdt", inv, "100 $\\mu$m (shorter $\\Delta$t: cfl 0.125)", [], h=0.1,
                              cfl=0.125)
        series += cube_series("h050_nolimit", inv, "50 $\\mu$m (no force limits)", [], h=0.05, force_limit=False)
        series += cube_series("h100_exact", inv, "100 $\\mu$m, exact integration", [], h=0.1,
                              integration="exact")
        # docs/interface_validation.md, "Extrapolated separation" (2 ppc: 1 ppc is unstable with it)
        series += cube_series("h100_extrapolated", inv, "100 $\\mu$m, extrapolated separation", [], h=0.1,
                              separation="extrapolated")
    plot_cube("fig12", runner, outdir, series, "energy", "Fig. 12: K from energy, r = 700 $\\mu$m, "
              "Vf = 17.96 %, Dn = Dt")


def fig13(runner, quick, outdir):
    if quick:
        inv = [1e-9, 1e-7, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2]
        series = cube_series("h100_ppc1", inv, "micro, 100 $\\mu$m, 1 ppc", [], h=0.1, ppc=1, end_time=0.012)
        ninv = [1e-10, 1e-9, 1e-8, 1e-7, 1e-6, 1e-5]
        series += cube_series("nano_h100_ppc1", ninv, "nano, 100 nm, 1 ppc", [], h=0.1, ppc=1, scale=1e-3,
                              end_time=0.012)
    else:
        inv = [1e-9, 1e-8, 1e-7, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2]
        series = cube_series("h100", inv, "micro, 100 $\\mu$m", [], h=0.1)
        series += cube_series("h050", inv, "micro, 50 $\\mu$m", [], h=0.05)
        ninv = [1e-10, 1e-9, 1e-8, 1e-7, 1e-6, 1e-5]
        series += cube_series("nano_h050", ninv, "nano, 50 nm", [], h=0.05, scale=1e-3)
    plot_cube("fig13", runner, outdir, series, "pressure", "Fig. 13: K from mean pressure, Vf = 17.96 %",
              nano=True)


FIGURES = {"fig5": fig5, "fig7": fig7, "fig8": fig8, "fig9": fig9, "fig10": fig10, "fig11": fig11,
           "fig12": fig12, "fig13": fig13}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    ap.add_argument("figure", choices=sorted(FIGURES) + ["all"])
    ap.add_argument("--quick", action="store_true", help="coarse cells, few values (minutes)")
    ap.add_argument("--jobs", type=int, default=2, help="runs at once (default 2)")
    ap.add_argument("--mmpm", default=os.path.join(ROOT, "build", "mmpm"), help="the mmpm binary")
    ap.add_argument("--out", default=os.path.join(ROOT, "results", "figures"), help="figures folder")
    ap.add_argument("--force", action="store_true", help="re-run sweeps even if results exist")
    a = ap.parse_args(argv)
    mmpm = os.path.abspath(a.mmpm)
    if not os.access(mmpm, os.X_OK):
        raise SystemExit(f"no mmpm binary at {mmpm} (use --mmpm)")
    names = sorted(FIGURES) if a.figure == "all" else [a.figure]
    for name in names:
        outdir = os.path.join(os.path.abspath(a.out), name)
        os.makedirs(outdir, exist_ok=True)
        print(f"{name}{' (quick)' if a.quick else ''}:", flush=True)
        FIGURES[name](Runner(mmpm, a.jobs, os.path.abspath(a.out), a.force), a.quick, outdir)
    return 0


if __name__ == "__main__":
    sys.exit(main())
