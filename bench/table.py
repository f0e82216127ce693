#!/usr/bin/python3
"""Turns mmpm_bench's JSON (Google Benchmark 1.7.1) into Markdown tables.

    bench/table.py [bench/results.json] [-o bench/RESULTS.md]
    bench/table.py --merge OUT.json PASS1.json [PASS2.json ...] [--loads FILE]

Benchmark names are "family/key:value/..." (see bench/bench_common.hpp).
bench/run runs the binary once per pass and merges the passes (--merge);
every benchmark then has one sample per pass: headline times are the minimum
over the samples, breakdown counters the median. Standard library only.
"""

import argparse
import datetime
import json
import os
import re
import subprocess
import sys

STAGES = ["sort", "p2g", "mm", "grid", "g2p", "constitutive"]
SHAPES = ["linear", "gimp", "bspline2", "bspline3"]
LAWS = ["stick", "frictionless", "friction", "interface"]
NORMALS = ["mvg", "avg", "specified", "radial"]
NOTES_MARKER = "<!-- notes: everything below this line is kept when table.py rewrites the file -->"


def parse_name(name):
    parts = name.split("/")
    info = {"family": parts[0]}
    for p in parts[1:]:
        if ":" in p:
            k, v = p.split(":", 1)
            if k not in ("min_time", "repeats"):
                info[k] = v
    return info


# Headline times: the minimum over the samples (passes; the least disturbed run
# on a shared machine). Every other counter (stage breakdowns, node counts): the median.
PRIMARY = {"ns_per_particle", "ns_per_mm_node", "ns_per_node"}


def merge(out_path, pass_paths, loads_path=None):
    """One JSON from several passes: every benchmark entry kept, tagged with its pass."""
    merged = {"context": None, "benchmarks": []}
    for k, path in enumerate(pass_paths, 1):
        with open(path) as f:
            data = json.load(f)
        if merged["context"] is None:
            merged["context"] = data.get("context", {})
        for b in data.get("benchmarks", []):
            b["pass"] = k
            merged["benchmarks"].append(b)
    ctx = merged["context"] or {}
    ctx["passes"] = len(pass_paths)
    if loads_path:
        with open(loads_path) as f:
            ctx["pass_load_averages"] = [line.strip() for line in f if line.strip()]
    merged["context"] = ctx
    with open(out_path, "w") as f:
        json.dump(merged, f, indent=1)


def load(path):
    """Samples per benchmark: every non-aggregate entry (one per pass or repetition)."""
    with open(path) as f:
        data = json.load(f)
    runs = {}  # key (sorted name items) -> {"info", "samples": [entries]}
    errors = []
    for b in data.get("benchmarks", []):
        name = b.get("run_name", b["name"])
        if b.get("error_occurred"):
            errors.append((name, b.get("error_message", "")))
            continue
        if b.get("run_type") == "aggregate":
            continue
        info = parse_name(name)
        key = tuple(sorted(info.items()))
        runs.setdefault(key, {"info": info, "samples": []})["samples"].append(b)
    return data.get("context", {}), runs, errors


class Results:
    def __init__(self, runs, context=None):
        self.runs = runs
        self.context = context or {}

    def caches(self):
        """'48 KiB L1d and 2 MiB L2 per core, 480 MiB L3 shared', from the
        caches Google Benchmark read off this machine (the text named one
        host's caches until 2026-12-01, wrong on the others)."""
        def size(b):
            return f"{b // 1048576} MiB" if b >= 1048576 else f"{b // 1024} KiB"
        found = {}
        for c in self.context.get("caches", []):
            if c.get("type") in ("Data", "Unified"):
                found[c["level"]] = (c["size"], c.get("num_sharing", 1))
        if 1 not in found or 2 not in found:
            return "caches not recorded"
        text = f"{size(found[1][0])} L1d and {size(found[2][0])} L2 per core"
        if 3 in found:
            text += f", {size(found[3][0])} L3" + (" shared" if found[3][1] > 1 else " per core")
        return text

    def find(self, family, **want):
        """The run of `family` whose name has exactly these key:value items."""
        want = {k: str(v) for k, v in want.items()}
        want["family"] = family
        for rec in self.runs.values():
            if rec["info"] == want and rec["samples"]:
                return rec
        return None

    def samples(self, family, counter, **want):
        rec = self.find(family, **want)
        if rec is None:
            return []
        return sorted(b[counter] for b in rec["samples"] if counter in b)

    def value(self, family, counter, stat=None, **want):
        v = self.samples(family, counter, **want)
        if not v:
            return None
        if stat is None:
            stat = "min" if counter in PRIMARY else "median"
        if stat == "min":
            return v[0]
        if stat == "max":
            return v[-1]
        mid = len(v) // 2
        return v[mid] if len(v) % 2 else 0.5 * (v[mid - 1] + v[mid])

    def spread(self, family, counter, **want):
        """(max - min) / min over the samples, or None for a single sample."""
        v = self.samples(family, counter, **want)
        if len(v) < 2 or v[0] == 0:
            return None
        return (v[-1] - v[0]) / v[0]

    def repetitions(self):
        return max((len(rec["samples"]) for rec in self.runs.values()), default=0)


def core_share(runs):
    """Median cpu_time / real_time of the 1-thread, real-time benchmarks: the
    share of a core they got (1.0 on an idle machine)."""
    shares = []
    for rec in runs.values():
        if rec["info"].get("threads") != "1":
            continue
        for b in rec["samples"]:
            if "manual_time" not in b.get("name", "") and b.get("real_time", 0) > 0:
                shares.append(b["cpu_time"] / b["real_time"])
    if not shares:
        return None, 0
    shares.sort()
    return shares[len(shares) // 2], len(shares)


def fmt(x, digits=1):
    if x is None:
        return "–"
    if abs(x) >= 1000:
        return f"{x:,.0f}"
    if abs(x) >= 100:
        return f"{x:.0f}"
    return f"{x:.{digits}f}"


def ratio(a, b, digits=2):
    if a is None or b is None or b == 0:
        return "–"
    return f"{a / b:.{digits}f}×"


def pct(x):
    return "–" if x is None else f"{100 * x:.1f} %"


def table(header, rows):
    out = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    for r in rows:
        out.append("| " + " | ".join(r) + " |")
    return "\n".join(out)


def lscpu_model():
    try:
        text = subprocess.run(["lscpu"], capture_output=True, text=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        return "unknown", "?"
    model, cpus = "unknown", "?"
    for line in text.splitlines():
        k, _, v = line.partition(":")
        if k.strip() == "Model name":
            model = v.strip()
        elif k.strip() == "CPU(s)":
            cpus = v.strip()
    return model, cpus


def git_commit(root):
    try:
        rev = subprocess.run(["git", "-C", root, "rev-parse", "--short", "HEAD"],
                             capture_output=True, text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", root, "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, check=True).stdout.strip()
        return rev + ("+dirty" if dirty else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def p2g_section(R):
    ns = "ns_per_particle"
    out = ["## 1. P2G: windowed vs pointwise, colored vs serial vs atomic scatter (ns/particle)", "",
           "Mass, momentum and internal force of one material (the solver's USL transfer). "
           "2D: 250 000 particles in a 254² grid; 3D: 262 144 particles in a 36³ grid; "
           "2 particles per cell and direction, sorted by tile. Colored = tiles color by color "
           "(tile 16 in 2D, 8 in 3D, the solver defaults). Windowed = the solver's kernel "
           "(kernels/window.hpp: a cell's particles add into a register block written once per "
           "cell, rows of the window as vectors); pointwise = the reference kernel that adds every "
           "particle into its stencil node by node (the kernel before the window). Atomic uses "
           "the pointwise loop with atomic adds (`std::atomic_ref` compare-and-swap, as `omp atomic` compiles them; before 2026-11-30 `omp atomic` itself). Ratios > 1 mean the first named is slower. "
           "GFLOP/s and GB/s (colored windowed, 1 thread): flops of the pointwise sums "
           "(kP2GFlopsPerNode per stencil node) and the particle bytes streamed, per second.", ""]
    header = ["dim", "shape", "real", "windowed serial 1t", "windowed colored 1t", "windowed colored 2t",
              "2t/1t speed-up", "pointwise serial 1t", "pointwise colored 1t", "pointwise colored 2t",
              "pointwise / windowed (colored 1t)", "atomic 2t", "atomic 2t / windowed 2t",
              "GFLOP/s (1t)", "GB/s (1t)"]
    rows = []
    for dim in ("2", "3"):
        tile = "16" if dim == "2" else "8"
        for real in ("double", "float"):
            for shape in SHAPES:
                base = dict(dim=dim, shape=shape, real=real)
                get = lambda strat, th, counter=ns, **kw: R.value("p2g", counter, **base, strategy=strat,
                                                                  threads=th, **kw)
                s1, c1, c2 = get("serial", 1), get("colored", 1, tile=tile), get("colored", 2, tile=tile)
                ps1 = get("serial_pointwise", 1)
                pc1, pc2 = get("colored_pointwise", 1, tile=tile), get("colored_pointwise", 2, tile=tile)
                a2 = get("atomic", 2)
                gf = get("colored", 1, counter="Gflops", tile=tile)
                gb = get("colored", 1, counter="particle_GBps", tile=tile)
                if all(v is None for v in (s1, c1, c2, ps1, pc1, pc2, a2)):
                    continue
                rows.append([dim + "D", shape, real, fmt(s1), fmt(c1), fmt(c2), ratio(c1, c2), fmt(ps1),
                             fmt(pc1), fmt(pc2), ratio(pc1, c1), fmt(a2), ratio(a2, c2), fmt(gf), fmt(gb)])
    out.append(table(header, rows))
    # Where the solver's block units take two window rows (uGIMP and
    # quadratic B-splines in double, 2D and 3D): the one-row units, this run.
    rows = []
    for dim in ("2", "3"):
        tile = "16" if dim == "2" else "8"
        for real in ("double", "float"):
            for shape in SHAPES:
                get = lambda strat, th: R.value("p2g", ns, dim=dim, shape=shape, real=real,
                                                strategy=strat, threads=th, tile=tile)
                r1, r2 = get("colored_row_units", 1), get("colored_row_units", 2)
                if r1 is None and r2 is None:
                    continue
                c1, c2 = get("colored", 1), get("colored", 2)
                rows.append([dim + "D", shape, real, fmt(c1), fmt(r1), ratio(r1, c1), fmt(c2), fmt(r2),
                             ratio(r2, c2)])
    if rows:
        out += ["", "### Two window rows per vector unit vs one (colored windowed, ns/particle)", "",
                "Windows binned by the nearest node have 9 rows of 4 nodes in 3D, 3 in 2D; the "
                "solver's scatter blocks take 2 rows per AVX-512 vector (3D: 5 units, 2D: 2, the "
                "last padded), the baseline one row (9 or 3 half-register units). Bitwise the same "
                "grid (tests/test_p2g.cpp).", ""]
        out.append(table(["dim", "shape", "real", "2 rows 1t", "1 row 1t", "1 row / 2 rows (1t)",
                          "2 rows 2t", "1 row 2t", "1 row / 2 rows (2t)"], rows))
    out += ["", "### Tile edge of the colored scatter (ns/particle; best per row in bold)", "",
            "TileLayout rounds the tile edge up to a power of two of at least 4, so an edge of 3 "
            "is not available; 32 is measured instead. In 3D the 36³ grid has only 2 tiles of 32 "
            "per direction (one tile per color: no parallelism).", ""]
    header = ["dim", "shape", "threads", "T=4", "T=8", "T=16", "T=32"]
    rows = []
    for dim in ("2", "3"):
        for shape in SHAPES:
            for th in ("1", "2"):
                vals = [R.value("p2g_tile", ns, dim=dim, shape=shape, real="double", strategy="colored",
                                tile=t, threads=th) for t in ("4", "8", "16", "32")]
                if all(v is None for v in vals):
                    continue
                best = min((v for v in vals if v is not None), default=None)
                cells = [("**" + fmt(v) + "**") if v is not None and v == best else fmt(v) for v in vals]
                rows.append([dim + "D", shape, th] + cells)
    if rows:
        out.append(table(header, rows))
    else:
        out.append("(no tile sweep in this run)")
    out += p2g_size_table(R)
    return out


# p2g_size: (dim, shape, real, block edges in cells, smallest to largest)
P2G_SIZES = [("2", "linear", "double", ("24", "48", "96", "250")),
             ("2", "gimp", "double", ("24", "48", "96", "250")),
             ("2", "gimp", "float", ("24", "48", "96", "250")),
             ("3", "gimp", "double", ("8", "12", "20", "32"))]


def p2g_size_table(R):
    """The colored scatter on one thread from an L2-resident block to the p2g/ block."""
    out = ["", "### P2G against the block's size (colored windowed, 1 thread, ns/particle)", "",
           "`p2g_size/`: the same kernel and particle layout as above on blocks of 2 × 2 (2D) or "
           "2 × 2 × 2 (3D) particles per cell, from a few thousand particles, whose columns and grid "
           "fit in one core's 1 MiB L2, to the blocks above (L3). block 1 / block 4: the share "
           "of the large block's time that remains when nothing comes from beyond L2 — the "
           "kernel's own instructions (docs/performance.md \"P2G's time without memory\").", ""]
    rows = []
    for dim, shape, real, edges in P2G_SIZES:
        vals = []
        for e in edges:
            v = R.value("p2g_size", "ns_per_particle", dim=dim, shape=shape, real=real, cells=e,
                        threads="1")
            n = R.value("p2g_size", "particles", dim=dim, shape=shape, real=real, cells=e,
                        threads="1")
            vals.append((e, n, v))
        if all(v is None for _, _, v in vals):
            continue
        cells = [f"{fmt(v, 2)} ({int(n):,} p)" if v is not None and n else fmt(v, 2)
                 for _, n, v in vals]
        share = pct(vals[0][2] / vals[-1][2]) if vals[0][2] and vals[-1][2] else "–"
        rows.append([dim + "D", shape, real] + cells + [share])
    if rows:
        out.append(table(["dim", "shape", "real", "block 1 (L2)", "block 2", "block 3",
                          "block 4 (as above)", "block 1 / block 4"], rows))
    else:
        out.append("(no size sweep in this run)")
    return out


def kernel_section(R):
    ns = "ns_per_particle"
    out = ["## 2. G2P and constitutive update (ns/particle)", "",
           "G2P: FLIP/PIC velocity, position, velocity gradient and the tile-change test, "
           "as the Stepper runs it (packed for 2D linear, windowed for the other shapes); "
           "pointwise = the node-by-node reference gather. MUSL fused G2P+P2G: MUSL's first "
           "particle pass (G2P of the new velocity, then P2G of m v with the same window), colored "
           "as in the step; its reference column is the one-particle windowed kernel; in 3D "
           "also with the momenta scattered after each batch of 32 (GroupedScatter) instead of "
           "in the block beside the gathers (the solver's choice where both fit the registers). "
              "G2P one particle per vector: the double windowed gather of the shapes binned by "
              "the nearest node (uGIMP, quadratic B-spline; 2D and 3D) without pairs of "
              "particles per 512-bit vector, the solver's baseline in the same run. "
           "MUSL gradient pass + separation shift: the step's last G2P (velocity gradient, "
           "position commit) advancing an interface scene's separation shift in the same pass "
           "(kernels/separation_shift.hpp), against the gradient pass followed by the shift's "
           "own pass (the reference column) and the gradient pass alone (no shift); two fields "
           "split at mid-block. "
           "Constitutive: isotropic small-strain "
           "update (plane strain in 2D). Same particle blocks as P2G.", ""]
    header = ["kernel", "dim", "shape", "real", "1 thread", "2 threads", "speed-up",
              "GB/s (2t)", "pointwise 1t", "pointwise / solver (1t)"]
    rows = []
    for dim in ("2", "3"):
        for real in ("double", "float"):
            for shape in SHAPES:
                v1 = R.value("g2p", ns, dim=dim, shape=shape, real=real, threads=1)
                v2 = R.value("g2p", ns, dim=dim, shape=shape, real=real, threads=2)
                gb = R.value("g2p", "particle_GBps", dim=dim, shape=shape, real=real, threads=2)
                p1 = R.value("g2p_pointwise", ns, dim=dim, shape=shape, real=real, threads=1)
                if v1 is None and v2 is None:
                    continue
                rows.append(["G2P", dim + "D", shape, real, fmt(v1), fmt(v2), ratio(v1, v2), fmt(gb),
                             fmt(p1), ratio(p1, v1)])
                # Where the solver gathers two particles per vector (3D
                # double): the windowed gather one particle at a time, this run.
                u1 = R.value("g2p_one_per_vector", ns, dim=dim, shape=shape, real=real, threads=1)
                u2 = R.value("g2p_one_per_vector", ns, dim=dim, shape=shape, real=real, threads=2)
                if u1 is not None or u2 is not None:
                    rows.append(["G2P one particle per vector", dim + "D", shape, real, fmt(u1), fmt(u2),
                                 ratio(u1, u2), "–", "–", ratio(u1, v1) + " (vs pairs)"])
            # MUSL's fused pass (G2P + P2G of m v): the solver's kernel vs the
            # one-particle windowed kernel, both in this run.
            for shape in SHAPES:
                want = dict(dim=dim, shape=shape, real=real)
                v1 = R.value("g2p_fused", ns, kernel="solver", threads=1, **want)
                v2 = R.value("g2p_fused", ns, kernel="solver", threads=2, **want)
                o1 = R.value("g2p_fused", ns, kernel="one_particle", threads=1, **want)
                if v1 is None and v2 is None:
                    continue
                rows.append(["MUSL fused G2P+P2G", dim + "D", shape, real, fmt(v1), fmt(v2),
                             ratio(v1, v2), "–", fmt(o1) + " (one particle)", ratio(o1, v1)])
                # 3D: the momenta scattered after each batch instead of in
                # the block beside the gathers (the solver's choice there).
                a1 = R.value("g2p_fused", ns, kernel="after_batch", threads=1, **want)
                a2 = R.value("g2p_fused", ns, kernel="after_batch", threads=2, **want)
                if a1 is not None or a2 is not None:
                    rows.append(["MUSL fused, momenta after each batch", dim + "D", shape, real, fmt(a1),
                                 fmt(a2), ratio(a1, a2), "–", "–", ratio(a1, v1) + " (vs solver)"])
            # MUSL's gradient pass with the separation shift inside it (the
            # solver's), against the pass followed by the shift's own pass,
            # and against the gradient pass alone (no interface spring).
            for shape in SHAPES:
                want = dict(dim=dim, shape=shape, real=real)
                f1, f2, s1, n1, n2 = (
                    R.value("g2p_gradient_shift", ns, kernel=k, threads=t, **want)
                    for k, t in (("fused", 1), ("fused", 2), ("separate", 1), ("none", 1),
                                 ("none", 2)))
                if f1 is None and f2 is None:
                    continue
                rows.append(["MUSL gradient pass + separation shift", dim + "D", shape, real,
                             fmt(f1), fmt(f2), ratio(f1, f2), "–", fmt(s1) + " (own pass)",
                             ratio(s1, f1)])
                rows.append(["MUSL gradient pass, no shift", dim + "D", shape, real, fmt(n1),
                             fmt(n2), ratio(n1, n2), "–", "–", ratio(f1, n1) + " (with shift)"])
            v1 = R.value("constitutive", ns, dim=dim, law="isotropic", real=real, threads=1)
            v2 = R.value("constitutive", ns, dim=dim, law="isotropic", real=real, threads=2)
            gb = R.value("constitutive", "particle_GBps", dim=dim, law="isotropic", real=real, threads=2)
            if v1 is not None or v2 is not None:
                rows.append(["constitutive", dim + "D", "–", real, fmt(v1), fmt(v2), ratio(v1, v2), fmt(gb),
                             "–", "–"])
    out.append(table(header, rows))
    return out


def grid_section(R):
    ns = "ns_per_node"
    out = ["## 8. Grid node loops alone (ns/node)", "",
           "bench_grid.cpp: the single-material MUSL step's node loops (kernels/grid_update.hpp) on "
           "one field, 2D 255² and 3D 41³ nodes, each thread on an even share it touched first. "
           "update = grid_update with the velocities (reads m, p, f; writes p, vel, dvel), "
           "velocities = grid_momentum_velocities (reads m, p; writes vel), triad = a = b + s c over "
           "three node arrays: the machine's own 2-thread gain for a loop of this length, in the "
           "same run. warm = the loop repeated (each thread's nodes in its caches); evicted = every "
           "thread reads 64 MiB before each call (the grid comes from memory). GB/s count each "
           "write twice, as the triad does. The in-step grid stage (§3 stage columns) sits between "
           "the two states.", ""]
    header = ["dim", "real", "kernel", "warm 1t", "warm 2t", "speed-up", "GB/s (warm 1t)",
              "evicted 1t", "evicted 2t", "speed-up", "GB/s (evicted 1t)"]
    rows = []
    for dim in ("2", "3"):
        for real in ("double", "float"):
            for kernel in ("update", "velocities", "triad"):
                v = {}
                for cache in ("warm", "evicted"):
                    for t in (1, 2):
                        v[cache, t] = R.value("grid", ns, dim=dim, real=real, kernel=kernel,
                                              cache=cache, threads=t)
                if all(x is None for x in v.values()):
                    continue
                gw = R.value("grid", "GBps", dim=dim, real=real, kernel=kernel, cache="warm", threads=1)
                ge = R.value("grid", "GBps", dim=dim, real=real, kernel=kernel, cache="evicted",
                             threads=1)
                rows.append([dim + "D", real, kernel, fmt(v["warm", 1], 2), fmt(v["warm", 2], 2),
                             ratio(v["warm", 1], v["warm", 2]), fmt(gw),
                             fmt(v["evicted", 1], 2), fmt(v["evicted", 2], 2),
                             ratio(v["evicted", 1], v["evicted", 2]), fmt(ge)])
    out.append(table(header, rows))
    return out


STEP_SCENES = [
    ("2d_linear_1mat", "2D linear, 1 elastic material"),
    (("2d_linear_1mat", {"scheme": "USL"}), "the same with scheme = USL (one transfer)"),
    (("2d_linear_1mat", {"fuse_step_tail": "false"}),
     "the same with the step's tail unfused (fuse_step_tail = false)"),
    (("2d_linear_1mat", {"fuse_constitutive": "true"}),
     "the same with the constitutive update fused into G2P"),
    ("2d_gimp_interface", "2D gimp two-layer, imperfect interface (Dn perfect, Dt 5, SN)"),
    (("2d_gimp_interface", {"fuse_step_tail": "false"}),
     "the same with the step's tail unfused (fuse_step_tail = false)"),
    (("2d_gimp_interface", {"fuse_constitutive": "true"}),
     "the same with the constitutive update fused into G2P"),
    (("2d_gimp_interface", {"mm_fields_share": "0.0"}),
     "the same with mx, Ω scattered with the first P2G (mm_fields_share = 0)"),
    ("2d_gimp_inclusions", "2D gimp, 625 glass disks in a polymer block, interface (mvg normal)"),
    (("2d_gimp_inclusions", {"mm_fields_share": "1.0"}),
     "the same with mx, Ω, g always scattered apart (mm_fields_share = 1)"),
    ("3d_gimp_1mat", "3D gimp, 1 elastic material"),
    ("2d_gimp_1mat", "2D gimp, same geometry, 1 material (baseline)"),
    ("2d_gimp_2mat_shared", "2D gimp, 2 materials sharing one field"),
    ("2d_linear_room", "2D linear block in a 504 × 504 grid, 3/4 of the nodes empty (step_ab only)"),
    ("2d_linear_1e6", "2D linear block of 10^6 particles, 504 × 504 grid (step_ab only)"),
]


def step_scenes():
    """(scene name, label, benchmark-name filter) for each STEP_SCENES row."""
    for scene, label in STEP_SCENES:
        if isinstance(scene, tuple):
            yield scene[0], label, {"scene": scene[0], **scene[1]}
        else:
            yield scene, label, {"scene": scene}


def step_section(R):
    ns = "ns_per_particle"
    out = ["## 3. Whole step through the Simulation interface (ns/particle/step)", "",
           "make_simulation(parse_scene_text(...)), step() in the loop, the solver's default scheme "
           "(MUSL) unless noted. MUSL runs P2G, then one fused pass (G2P of the updated velocity + "
           "P2G of the new momenta, timed as g2p) and a G2P of the velocity gradient; by default "
           "(fuse_step_tail) that last G2P, the constitutive update and the next step's P2G run "
           "tile by tile in one pass, whose time the Stepper shares among the g2p, constitutive "
           "and p2g columns in the proportions thread 0 measured. Stage columns are the Stepper's "
           "own timers (1 thread), ns/particle/step.", ""]
    header = ["scene", "particles", "fields", "1 thread", "spread", "2 threads", "spread",
              "speed-up"] + [s + " (1t)" for s in STAGES]
    rows = []
    for scene, label, kw in step_scenes():
        v1 = R.value("step", ns, threads=1, **kw)
        v2 = R.value("step", ns, threads=2, **kw)
        if v1 is None and v2 is None:
            continue
        n = R.value("step", "particles", threads=1, **kw) or R.value("step", "particles", threads=2, **kw)
        fields = R.value("step", "fields", threads=1, **kw)
        stages = [fmt(R.value("step", f"stage_{s}_ns_per_particle", threads=1, **kw)) for s in STAGES]
        rows.append([f"`{scene}`: {label}", fmt(n, 0), fmt(fields, 0), fmt(v1),
                     pct(R.spread("step", ns, threads=1, **kw)), fmt(v2),
                     pct(R.spread("step", ns, threads=2, **kw)), ratio(v1, v2)] + stages)
    out.append(table(header, rows))
    for kw, what in (({}, "default scheme"), ({"scheme": "USL"}, "USL")):
        lin = R.value("step", ns, scene="2d_linear_1mat", threads=1, **kw)
        if lin is not None:
            verdict = "meets" if lin <= 40 else "misses"
            out += ["", f"Target for 2D linear, one material, one core: ≤ 40 ns/particle/step — "
                        f"{what}: measured {fmt(lin)}, {verdict} the target."]
    gi = R.value("step", ns, scene="2d_gimp_interface", threads=1)
    if gi is not None:
        verdict = "meets" if gi <= 80 else "misses"
        out += ["", f"Target for the 2D uGIMP two-layer scene with an interface, one core: ≤ 80 "
                    f"ns/particle/step — measured {fmt(gi)}, {verdict} the target."]
    out += stage_speedup_table(R)
    out += paired_speedup_table(R)
    out += paired_setting_table(R)
    return out


# The settings step_ab compares with the defaults (bench/bench_step_ab.cpp):
# label, heading, what A and B run, what a ratio > 1 means, the stage column.
PAIRED_SETTINGS = [
    ("fuse_step_tail_false", "The fused step tail, paired blocks (B: fuse_step_tail = false)",
     "A with the defaults (MUSL's gradient G2P, constitutive update and next P2G fused tile by "
     "tile) and B with the three passes apart", "the fused tail is faster", "p2g"),
    ("particle_order_tile", "Particles stored color by color, paired blocks "
     "(B: particle_order = \"tile\")",
     "A with the defaults (particles stored color by color, so each colored pass reads them "
     "front to back) and B stored in plain tile order", "color order is faster", "g2p"),
    ("skip_empty_nodes_false", "Node passes over the reachable nodes, paired blocks "
     "(B: skip_empty_nodes = false)",
     "A with the defaults (zeroing, momentum update, velocities over the nodes each field's "
     "particles can reach) and B over every node of every field", "skipping is faster", "grid"),
    ("tile_32", "Tile edge 32 on the 254² grids, paired blocks (B: grid.tile = 32)",
     "A with the defaults (tile edge 16 on these grids: 32 would leave 16 tiles per color) and "
     "B with 32", "the default 16 is faster", "p2g"),
    ("tile_16", "Tile edge 16 on the 504² grid, paired blocks (B: grid.tile = 16)",
     "A with the defaults (tile edge 32 on this grid, 64 tiles per color) and B with 16 (the "
     "edge of every 2D grid before 2026-11-26)", "the default 32 is faster", "p2g"),
    ("prefetch_grid_false", "Grid lines requested a line ahead, paired blocks "
     "(B: prefetch_grid = false)",
     "A with the defaults (the 2D transfers request the grid lines their windows reach next, on "
     "grids of 1 MiB and more) and B without the requests", "the requests are faster", "g2p"),
    ("prefetch_particles_false", "Particle columns requested ahead, paired blocks "
     "(B: prefetch_particles = false)",
     "A with the defaults (the transfers request the particle columns they stream a batch "
     "ahead, when those columns take 4 MiB and more) and B without the requests",
     "the requests are faster", "g2p"),
    ("xpic_2", "XPIC(2) particle velocities, paired blocks (B: xpic_order = 2)",
     "A with the defaults (pure FLIP) and B with one term of the XPIC series (an interpolation "
     "to the particles and a colored scatter of momenta per step, kernels/xpic.hpp)",
     "XPIC(2) costs more", "g2p"),
    ("force_limit_false", "MUSL's separation shift, paired blocks "
     "(B: interaction[0].force_limit = false)",
     "A with the defaults (the interface spring Dt = 5 under the force limit, so MUSL's "
     "gradient pass also advances the separation shift, kernels/separation_shift.hpp) and B "
     "without the limit (which never fires at Dt = 5) and so without the shift",
     "A, with the shift, is faster", "g2p"),
    ("same_settings", "Control: two Simulations with the same settings, paired blocks",
     "A and B both with the defaults (B made after A): what the harness itself puts between two "
     "equal runs, the scale against which the rows above are read", "A is slower", "g2p"),
]


def paired_setting_table(R):
    """step_ab/... (bench/bench_step_ab.cpp): two Simulations of a scene, A
    with the defaults and B with one setting changed, alternate blocks of
    steps on the same threads. Per setting and thread count: the median over
    the passes of the median paired ratio t(B) / t(A), [the ratio of the
    minima], (A → B ns/particle/step, minima), and one stage likewise."""
    scenes = [(scene, label) for scene, label, kw in step_scenes() if len(kw) == 1]
    out = []
    for b_label, heading, what, faster, stage in PAIRED_SETTINGS:
        rows = []
        for scene, label in scenes:
            for t in (1, 2):
                kw = dict(scene=scene, b=b_label, threads=t)
                r = R.value("step_ab", "b_over_a_step", stat="median", **kw)
                if r is None:
                    continue
                rm = R.value("step_ab", "b_over_a_step_min", stat="median", **kw)
                a, b = (R.value("step_ab", f"ns{x}_step", stat="min", **kw) for x in "AB")
                pa, pb = (R.value("step_ab", f"ns{x}_{stage}", stat="min", **kw) for x in "AB")
                rows.append([f"`{scene}`: {label}", str(t), f"{r:.3f} [{rm:.3f}]",
                             f"{fmt(a)} → {fmt(b)}", f"{fmt(pa, 2)} → {fmt(pb, 2)}"])
        if not rows:
            continue
        out += ["", f"### {heading}", "",
                f"`step_ab/scene:.../b:{b_label}`: two simulations of the scene, {what}, "
                "alternate blocks of 4 steps (A,B / B,A / ...; one untimed step opens each "
                f"block). Ratio: median over the pairs of t(B) / t(A) (> 1: {faster}), [ratio "
                f"of the minima]; ns/particle/step, minima, A → B; the {stage} column is the "
                "stage (with the fused tail, its measured share of the fused pass).", "",
                table(["scene", "threads", "B / A", "step A → B", f"{stage} A → B"], rows)]
    return out


def paired_speedup_table(R):
    """step_pair/... (bench/bench_step_pair.cpp): one benchmark per scene
    alternates blocks of steps on 1 and 2 threads, so each ratio compares
    two blocks taken seconds apart instead of two benchmarks taken minutes
    apart. Per stage: the median over the passes of the median paired ratio,
    and [the ratio of the per-thread-count minima]."""
    scenes = [(scene, label) for scene, label, kw in step_scenes() if len(kw) == 1
              and R.find("step_pair", scene=scene) is not None]
    if not scenes:
        return []
    out = ["", "### 2-thread speed-up per stage, paired blocks (target ≥ 1.8×)", "",
           "`step_pair/scene:...`: one benchmark per scene alternates blocks of 4 steps on 1 and "
           "on 2 threads of the same simulation (order 1,2 / 2,1 / ...; one untimed step after "
           "each switch), so both sides of a ratio see the same minutes of the shared host. "
           "Cell: median over the pairs of the paired ratio (median over the passes), "
           "[min over the 1-thread blocks / min over the 2-thread blocks], "
           "(1-thread → 2-thread ns/particle/step, minima). Marked * below 1.8×. "
           "Stages under 0.05 ns/particle are left out.", ""]
    parts = ["step"] + STAGES
    rows = []
    for scene, label in scenes:
        cells = []
        for s in parts:
            sp = R.value("step_pair", f"speedup_{s}", stat="median", scene=scene)
            sm = R.value("step_pair", f"speedup_{s}_min", stat="median", scene=scene)
            n1 = R.value("step_pair", f"ns1_{s}", stat="min", scene=scene)
            n2 = R.value("step_pair", f"ns2_{s}", stat="min", scene=scene)
            if sp is None or n1 is None or n1 < 0.05 or not sp:
                cells.append("–")
                continue
            mark = "" if sp >= 1.8 else " *"
            d = 2 if n1 < 10 else 1
            cells.append(f"{sp:.2f}×{mark} [{sm:.2f}×] ({fmt(n1, d)} → {fmt(n2, d)})")
        pairs = R.value("step_pair", "pairs", stat="median", scene=scene)
        rows.append([f"`{scene}`: {label}", fmt(pairs, 0)] + cells)
    out.append(table(["scene", "pairs"] + parts, rows))
    return out


def stage_speedup_table(R):
    """Per stage: 1-thread / 2-thread time of the Stepper's own stage timers,
    against the issue's >= 1.8x target, from the least disturbed samples (the
    minimum over the passes, as the headline times) and, in brackets, from
    the medians. Both are shown because a stage of a few percent of the step
    is timed over a short interval, so one burst of load on the shared
    machine moves its median. The mark follows the minimum. Stages under
    0.05 ns/particle (sort without re-binning, mm in one-field scenes) are
    left out."""
    out = ["", "### 2-thread speed-up per stage (target ≥ 1.8×)", "",
           "1-thread / 2-thread stage time of the Stepper's timers: from the minimum over the "
           "passes, [from the medians]; in parentheses the stage's share of the 1-thread step. "
           "Marked * when the minimum-based ratio is below 1.8×.", ""]
    rows = []
    for scene, label, kw in step_scenes():
        total = sum(R.value("step", f"stage_{s}_ns_per_particle", threads=1, **kw) or 0
                    for s in STAGES)
        if total <= 0:
            continue
        cells = []
        for s in STAGES:
            c = f"stage_{s}_ns_per_particle"
            t1 = R.value("step", c, threads=1, **kw)
            t2 = R.value("step", c, threads=2, **kw)
            b1 = R.value("step", c, stat="min", threads=1, **kw)
            b2 = R.value("step", c, stat="min", threads=2, **kw)
            if t1 is None or t2 is None or t1 < 0.05 or t2 <= 0 or not b2:
                cells.append("–")
                continue
            mark = "" if b1 / b2 >= 1.8 else " *"
            cells.append(f"{b1 / b2:.2f}×{mark} [{t1 / t2:.2f}×] ({100 * t1 / total:.0f} %)")
        rows.append([f"`{scene}`: {label}"] + cells)
    out.append(table(["scene"] + STAGES, rows))
    return out


def scaling_section(R):
    ns = "ns_per_particle"
    out = ["## 7. Problem size: 10^4 to 10^7 particles (2D linear, whole step, ns/particle/step)", "",
           "The `2d_linear_1mat` scene (MUSL) with a square block of N particles (2 × 2 per cell). "
           "grid MiB = nodes × 9 arrays × 8 bytes, particle MiB = N × 16 arrays × 8 bytes "
           "(what the step touches; 20 before L left the particle arrays on 2026-11-26). "
           f"This machine: {R.caches()} (as Google Benchmark read them).", ""]
    header = ["particles", "grid MiB", "particle MiB", "1 thread", "2 threads", "speed-up",
              "p2g (1t)", "g2p (1t)", "grid (1t)", "constitutive (1t)"]
    rows = []
    for n in ("1e+04", "3e+04", "1e+05", "3e+05", "1e+06", "3e+06", "1e+07"):
        v1 = R.value("scaling", ns, particles=n, threads=1)
        v2 = R.value("scaling", ns, particles=n, threads=2)
        if v1 is None and v2 is None:
            continue
        g = lambda c: R.value("scaling", c, particles=n, threads=1) or R.value("scaling", c, particles=n, threads=2)
        st = [fmt(R.value("scaling", f"stage_{x}_ns_per_particle", particles=n, threads=1))
              for x in ("p2g", "g2p", "grid", "constitutive")]
        rows.append([fmt(g("particles"), 0), fmt(g("grid_MiB"), 2), fmt(g("particle_MiB"), 1), fmt(v1), fmt(v2),
                     ratio(v1, v2)] + st)
    if rows:
        out.append(table(header, rows))
    else:
        out.append("(no scaling run in this set)")
    return out


def mm_section(R):
    out = ["## 4. Multimaterial pass (ns per multimaterial node)", "",
           "find + pass A + pass B, as the solver's multimaterial stage runs them, on a grid "
           "with one straight interface on a cell midplane (2D: 16×2050 cells, ~4 100 "
           "multimaterial nodes; 3D: 12×64×64 cells, ~7 900 nodes); gimp P2G of two blocks "
           "moving into each other and sliding. Interface: Dn perfect, Dt 5, force limit on. "
           "Manual timer: the momentum restore between iterations is not timed.", ""]
    header = ["law", "normal", "2D 1t", "2D 2t", "3D 1t", "3D 2t",
              "2D 1t: find / A / B"]
    rows = []
    for law in LAWS:
        for normal in NORMALS:
            g = lambda dim, th: R.value("mm", "ns_per_mm_node", dim=dim, law=law, normal=normal,
                                        real="double", threads=th)
            vals = [g("2", 1), g("2", 2), g("3", 1), g("3", 2)]
            if all(v is None for v in vals):
                continue
            parts = [R.value("mm", c, dim="2", law=law, normal=normal, real="double", threads=1)
                     for c in ("find_ns_per_mm_node", "passA_ns_per_mm_node", "passB_ns_per_mm_node")]
            rows.append([law, normal] + [fmt(v) for v in vals] +
                        [" / ".join(fmt(p) for p in parts)])
    out.append(table(header, rows))
    out += ["", "### Share of a whole step (two-layer and 625-disk scenes)", "",
            "Two measurements: the Stepper's own timer of its multimaterial stage during the whole-step "
            "benchmark, and the stage's work alone (`mm_scene`: the solver's own stage, find + pass A + "
            "pass B per transfer) on the scene's grid after three real steps, restored between "
            "iterations. Target: ≤ 10 % of the step.", ""]
    header = ["scene", "threads", "step ns/particle", "mm stage timer ns/particle", "share (timer)",
              "mm alone ns/particle", "share (alone / step)", "mm nodes", "alone ns per mm node",
              "alone: find / A / B µs per step"]
    rows = []
    for scene in ("2d_gimp_interface", "2d_gimp_inclusions"):
        for th in (1, 2):
            step = R.value("step", "ns_per_particle", scene=scene, threads=th)
            alone = R.value("mm_scene", "ns_per_particle", scene=scene, threads=th)
            if step is None and alone is None:
                continue
            parts = [R.value("mm_scene", c, scene=scene, threads=th)
                     for c in ("find_us", "passA_us", "passB_us")]
            rows.append([f"`{scene}`", str(th), fmt(step),
                         fmt(R.value("step", "stage_mm_ns_per_particle", scene=scene, threads=th), 2),
                         pct(R.value("step", "mm_share", scene=scene, threads=th)),
                         fmt(alone, 2),
                         pct(alone / step if alone is not None and step else None),
                         fmt(R.value("mm_scene", "mm_nodes", scene=scene, threads=th), 0),
                         fmt(R.value("mm_scene", "ns_per_mm_node", scene=scene, threads=th)),
                         " / ".join(fmt(p) for p in parts)])
    out.append(table(header, rows) if rows else "(not in this run)")
    return out


def unused_section(R):
    ns = "ns_per_particle"
    out = ["## 5. Unused features cost nothing", "",
           "Same two-box geometry, supports and traction as the two-layer scene, interleaved "
           "(minimum over the passes shown); spread = (max − min)/min over the passes, i.e. the "
           "noise a difference has to beat.", ""]
    header = ["threads", "1 material (baseline)", "spread", "2 materials, shared field", "spread",
              "difference", "with the interface (2 fields + mm pass)"]
    rows = []
    for th in (1, 2):
        a = R.value("step", ns, scene="2d_gimp_1mat", threads=th)
        b = R.value("step", ns, scene="2d_gimp_2mat_shared", threads=th)
        if a is None and b is None:
            continue
        ca = R.spread("step", ns, scene="2d_gimp_1mat", threads=th)
        cb = R.spread("step", ns, scene="2d_gimp_2mat_shared", threads=th)
        diff = "–" if a is None or b is None else f"{100 * (b - a) / a:+.1f} %"
        c = R.value("step", ns, scene="2d_gimp_interface", threads=th)
        rows.append([str(th), fmt(a), pct(ca), fmt(b), pct(cb), diff,
                     fmt(c) + (f" ({ratio(c, a)})" if c is not None and a else "")])
    out.append(table(header, rows) if rows else "(not in this run)")
    # Stage breakdown of the pair, 1 thread.
    rows = []
    for scene in ("2d_gimp_1mat", "2d_gimp_2mat_shared"):
        vals = [R.value("step", f"stage_{s}_ns_per_particle", scene=scene, threads=1) for s in STAGES]
        if all(v is None for v in vals):
            continue
        rows.append([f"`{scene}`"] + [fmt(v, 2) for v in vals])
    if rows:
        out += ["", "Stage breakdown, 1 thread (ns/particle/step):", "",
                table(["scene"] + STAGES, rows)]
    return out


def sort_section(R):
    out = ["## 6. Sort / binning", "",
           "Stepper::sort_particles for the gimp column set (tile keys, stable counting sort, "
           "every column permuted through a scratch array, tile ranges). `sorted`: particles "
           "already in tile order (a re-sort when nothing moved); `random`: a shuffled order.", ""]
    header = ["dim", "order", "threads", "total ns/particle", "keys", "counting sort", "permute",
              "ranges", "columns"]
    rows = []
    for dim in ("2", "3"):
        for order in ("sorted", "random"):
            for th in (1, 2):
                base = dict(dim=dim, shape="gimp", real="double", order=order, threads=th)
                tot = R.value("sort", "ns_per_particle", **base)
                if tot is None:
                    continue
                rows.append([dim + "D", order, str(th), fmt(tot)] +
                            [fmt(R.value("sort", c + "_ns_per_particle", **base), 2)
                             for c in ("keys", "counting_sort", "permute", "ranges")] +
                            [fmt(R.value("sort", "columns", **base), 0)])
    out.append(table(header, rows) if rows else "(not in this run)")
    out += ["", "### Re-sorting every k steps (2D linear scene, whole step, ns/particle/step)", "",
            "`sort_every = 0` (the default) re-bins only when a particle changes tile; in this "
            "scene (small vibrations) that never happens after the first step.", ""]
    header = ["sort_every", "1 thread", "sort stage (1t)", "2 threads", "sort stage (2t)"]
    rows = []
    for every in (None, "1", "10", "100"):
        kw = {} if every is None else {"sort_every": every}
        v1 = R.value("step", "ns_per_particle", scene="2d_linear_1mat", threads=1, **kw)
        v2 = R.value("step", "ns_per_particle", scene="2d_linear_1mat", threads=2, **kw)
        if v1 is None and v2 is None:
            continue
        s1 = R.value("step", "stage_sort_ns_per_particle", scene="2d_linear_1mat", threads=1, **kw)
        s2 = R.value("step", "stage_sort_ns_per_particle", scene="2d_linear_1mat", threads=2, **kw)
        rows.append([every or "0 (default)", fmt(v1), fmt(s1, 2), fmt(v2), fmt(s2, 2)])
    out.append(table(header, rows) if rows else "(not in this run)")
    return out


def seed_section(R):
    out = ["## 9. Seeding a particle-filled block (make_particles, ns/particle)", "",
           "bench_seed.cpp: a 250 × 250 mm block of 250 000 particles (254² grid of 1 mm cells, "
           "2 × 2 per cell) holding n × n disks that replace its particles inside them; the "
           "scene is parsed outside the timer. Ratio: against the block alone. Seeding tests "
           "only the particles in a later body's bounding-box cells, so the cost does not grow "
           "with the number of bodies (before 2026-11-26 every later body tested every "
           "particle).", ""]
    header = ["disks", "bodies", "particles", "ns/particle", "ratio to the block alone"]
    rows = []
    base = R.value("seed", "ns_per_particle", disks=0, threads=1)
    for n in (0, 625, 2500, 10000):
        v = R.value("seed", "ns_per_particle", disks=n, threads=1)
        if v is None:
            continue
        rows.append([str(n), fmt(R.value("seed", "bodies", disks=n, threads=1), 0),
                     fmt(R.value("seed", "particles", disks=n, threads=1), 0), fmt(v),
                     ratio(v, base)])
    out.append(table(header, rows) if rows else "(no seed run in this set)")
    out += ["", "Parsing the same scenes (`parse/disks:N`, parse_scene_text, µs per body): flat "
            "in the number of bodies since 2026-11-26 (it was O(bodies²): toml11 counted the "
            "lines from the file's start for each body's location).", ""]
    rows = []
    for n in (625, 10000, 40000):
        v = R.value("parse", "us_per_body", disks=n, threads=1, stat="min")
        if v is not None:
            rows.append([str(n), fmt(R.value("parse", "bodies", disks=n, threads=1), 0), fmt(v, 2)])
    out.append(table(["disks", "bodies", "µs per body"], rows) if rows else "(no parse run in this set)")
    return out


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("json", nargs="?", default=os.path.join(here, "results.json"))
    ap.add_argument("-o", "--output", default=None, help="Markdown file (default: stdout)")
    ap.add_argument("--note", default=None, help="a line added under the header")
    ap.add_argument("--merge", metavar="OUT", default=None,
                    help="merge the pass files given as arguments into OUT and stop")
    ap.add_argument("passes", nargs="*", help=argparse.SUPPRESS)
    ap.add_argument("--loads", default=None, help="(with --merge) load averages per pass")
    args = ap.parse_args()
    if args.merge:
        merge(args.merge, [args.json] + args.passes, args.loads)
        return

    context, runs, errors = load(args.json)
    R = Results(runs, context)
    model, cpus = lscpu_model()
    commit = context.get("git_commit") or git_commit(os.path.dirname(here))
    date = context.get("date") or datetime.datetime.now().isoformat(timespec="seconds")
    load_avg = context.get("load_avg")
    # results-TAG.json: a host's own full run (bench/run --tag TAG).
    tagged = re.fullmatch(r"results-(.+)\.json", os.path.basename(args.json))
    full_run = f"bench/run --tag {tagged.group(1)}" if tagged else "bench/run"
    lines = ["# mmpm benchmark results", "",
             f"Tables written by `bench/table.py` from `bench/{os.path.basename(args.json)}`; reproduce with "
             f"`{full_run}` (full, 26–37 min on the 2096 MHz host, ~36 on the 2596 MHz one) or "
             "`bench/run --quick` (subset, results on stdout). "
             "Only the notes at the end are hand-written.", "",
             f"- Date: {date}",
             f"- Machine: {model}, {cpus} CPU(s) (`lscpu`), {context.get('num_cpus', '?')} seen by "
             f"the benchmark at {context.get('mhz_per_cpu', '?')} MHz",
             f"- Git commit: {commit}",
             f"- Build: Release, -O3 -march=native, MMPM_FAST_DEV={context.get('mmpm_fast_dev', '?')}; "
             f"Google Benchmark {context.get('library_version', '1.7.1')} "
             f"(Debian package, itself built as {context.get('library_build_type', '?')})",
             f"- Load average (1/5/15 min) at the start of the first pass: "
             f"{' / '.join(f'{x:.2f}' for x in load_avg) if load_avg else '?'}"
             + ("; per pass (before -> after): " + "; ".join(context["pass_load_averages"])
                if context.get("pass_load_averages") else ""),
             "- Times are wall-clock (UseRealTime, or a manual timer where state is restored "
             "between iterations). The machine has 2 cores: 2-thread numbers are only meaningful "
             "when nothing else runs (see the load average).",
             f"- Each benchmark ran {R.repetitions()} time(s), once per pass of the whole set: "
             "headline times (ns/particle, ns/node) are the minimum over the passes, the least "
             "disturbed run on a shared machine; breakdown counters (stages, find/A/B) are "
             "medians, so they need not add up exactly to the headline. `spread` = "
             "(max − min)/min over the passes."]
    share, count = core_share(runs)
    if share is not None:
        lines.append(f"- CPU share: the {count} single-thread wall-clock benchmarks got a median "
                     f"{100 * share:.0f} % of a core (cpu_time / real_time; ~100 % on an idle machine)")
    if args.note:
        lines += [f"- Note: {args.note}"]
    lines.append("")
    for section in (p2g_section, kernel_section, step_section, mm_section, unused_section,
                    sort_section, scaling_section, grid_section, seed_section):
        lines += section(R)
        lines.append("")
    if errors:
        lines += ["## Benchmarks that reported an error", ""]
        lines += [f"- `{n}`: {m}" for n, m in errors]
        lines.append("")
    text = "\n".join(lines)
    if args.output:
        # Hand-written notes after the marker survive a regeneration.
        if os.path.exists(args.output):
            with open(args.output) as f:
                old = f.read()
            at = old.find(NOTES_MARKER)
            if at >= 0:
                text = text.rstrip("\n") + "\n\n" + old[at:]
        with open(args.output, "w") as f:
            f.write(text)
    else:
        sys.stdout.write(text)


if __name__ == "__main__":
    main()
