#!/usr/bin/env python3
"""Check that the loops written to vectorise did vectorise, in a built binary.

Why: twice a loop that the code and docs/performance.md called vectorised
ran as scalar code in the solver's own build, and nothing noticed
(PositionTile::any_moved, now moved_tiles: a member read through `this` inside an `omp simd`
loop; 3D pass A of the multimaterial batch: h_perp left out of line in the
solver's translation units). The compiler's -fopt-info on a small test file
said "vectorized" for both, so the check has to read the binary that runs.

For each rule: every out-of-line function whose demangled name matches must
hold at least `least` packed floating-point instructions (add, sub, mul,
div, fma, sqrt, min, max, round, convert on *pd / *ps; a scalar 3D pass A
has 7-9 of them, a vectorised one 200-500; the thresholds sit between),
and at least one such function must
exist (a rule that matches nothing means inlining changed: update the rule).

Usage: check_vectorised.py BINARY      (exit 0: all rules hold; 1: not)
"""
import re
import subprocess
import sys

# (name pattern, least packed FP instructions, exempt pattern or None, why)
RULES = [
    # any_moved picks the loop of the layout's tile order (moved_tiles<true>:
    # color-major slots, <false>: tile indices); both must be vector loops.
    (r"^bool mmpm::PositionTile<\d, (float|double)>::moved_tiles<(true|false)>\(", 2, None,
     "G2P's tile-change test (kernels/binning.hpp)"),
    (r"^void mmpm::mm_detail::pass_a_lanes<", 30,
     # Coulomb friction in 3D: GCC 12 rejects its masked loads
     # (docs/multimaterial.md "Pass A in SIMD lanes").
     r"\(mmpm::Law\)2, false, false, 3,",
     "multimaterial pass A lanes (kernels/mm_pair_batch.hpp)"),
    (r"^void mmpm::mm_detail::pass_b_lanes<", 16, None,
     "multimaterial pass B lanes (kernels/mm_pair_batch.hpp)"),
    (r"^void mmpm::detail::update_deformable<", 16, None,
     "grid momentum update (kernels/grid_update.hpp)"),
    # A short loop: vel = m > thr ? p/m : 0 (and dvel) is 2-6 packed
    # divides and fmas; as scalar code it has none. Out of line since
    # 2026-12-06: inlined, it moved between the team's region body and
    # for_own_field_nodes' copy as the loop's body changed.
    (r"^void mmpm::detail::velocity_range<", 2, None,
     "grid velocities (kernels/grid_update.hpp)"),
    # The per-material loops of one range: the constitutive pass's threads
    # and the fused step tail's tiles call it (solver/stepper_impl.hpp).
    (r"^mmpm::Stepper<\d, mmpm::\w+, (float|double)>::constitutive_range\(unsigned long, unsigned long, mmpm::ParticleView<\d, (float|double)> const&\)$", 30,
     None, "constitutive update loops (kernels/constitutive.hpp)"),
]

PACKED = re.compile(
    r"^v?(add|sub|mul|div|sqrt|min|max|fn?madd\d*|fn?msub\d*|rndscale|round|cvt\w*)p[sd]$")
HEADER = re.compile(r"^[0-9a-f]+ <(.*)>:$")


def packed_counts(binary):
    dump = subprocess.run(["objdump", "-d", "--no-show-raw-insn", "-C", binary],
                          capture_output=True, text=True, check=True).stdout
    counts, name = {}, None
    for line in dump.splitlines():
        m = HEADER.match(line)
        if m:
            name = m.group(1)
            counts.setdefault(name, 0)
            continue
        if name is None or "\t" not in line:
            continue
        fields = line.split("\t")[-1].split()
        if fields and PACKED.match(fields[0]):
            counts[name] += 1
    return counts


def main():
    if len(sys.argv) != 2:
        print(__doc__)
        return 2
    counts = packed_counts(sys.argv[1])
    failed = False
    for pattern, least, exempt, what in RULES:
        found = [(n, c) for n, c in counts.items()
                 if re.search(pattern, n) and not (exempt and re.search(exempt, n))]
        if not found:
            print(f"FAIL {what}: no function matches {pattern!r} (inlined? update the rule)")
            failed = True
            continue
        scalar = [(n, c) for n, c in found if c < least]
        for n, c in scalar:
            print(f"FAIL {what}: {n[:160]} has {c} packed FP instructions (< {least}): scalar")
        if scalar:
            failed = True
            continue
        low, high = min(c for _, c in found), max(c for _, c in found)
        print(f"ok   {what}: {len(found)} functions, {low}..{high} packed FP instructions "
              f"(need >= {least})")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
