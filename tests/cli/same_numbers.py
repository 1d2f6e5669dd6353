#!/usr/bin/env python3
"""The same command gives the same numbers: `s2kf track` on the bundled recordings against the
motion files of tests/data/golden/<instruction set>/, the set the program was compiled for
(`s2kf --version`, "baseline"). avx512/ was written before the house was reorganised (commit
64422a8; again when the bundle adjustment's relative tolerance became 1e-3, its accuracy
measured); avx2/ by the same code (commit e2f2d3e) on an AVX2 processor (AMD EPYC, Zen 3).
Usage: same_numbers.py S2KF_PROGRAM REPOSITORY SCRATCH_DIR. Exits 1 naming the first difference,
77 (skipped) for a build with no files of its own (a portable build).

Tolerances: 1e-4 rad (0.006 degrees) for angles, modulo a turn, and 0.01 mm for the root position,
far below what any change to the filter, the calibration or the model moves (tenths of a degree),
and above what another inlining or instruction order changes: rounding differences in the last
digits, which the filter carries over hundreds of frames to a few 1e-6 rad. Another instruction
set is another order of every vector sum: over a recording the two sets of files differ by up to
0.14 rad in the split of a bend between the two neck joints (which the head's markers hardly
tell apart) and 0.15 mm in the root's position, hence one set of files per instruction set."""
import csv
import math
import os
import pathlib
import re
import subprocess
import sys

program, repo, scratch = sys.argv[1], pathlib.Path(sys.argv[2]), pathlib.Path(sys.argv[3])
scratch.mkdir(parents=True, exist_ok=True)
# The kernels the program chooses itself: S2KF_SIMD in the caller's environment would choose others.
environment = {k: v for k, v in os.environ.items() if k != "S2KF_SIMD"}
version = subprocess.run([program, "--version"], capture_output=True, text=True, env=environment).stdout
baseline = re.search(r"baseline (\w+)", version)
golden = repo / "tests" / "data" / "golden" / (baseline.group(1) if baseline else "")
if not baseline or not golden.is_dir():
    sets = ", ".join(sorted(p.name for p in golden.parent.iterdir() if p.is_dir()))
    print(f"no motion files for this build ({version.strip()!r}); there are files for {sets}: skipped")
    sys.exit(77)


def rows(path):
    with open(path, newline="") as f:
        table = list(csv.reader(f))
    return table[0], [[float(v) for v in row] for row in table[1:]]


failures = []
for name in ("handstand", "walk", "cartwheel"):
    prefix = scratch / name
    done = subprocess.run([program, "track", str(repo / "data" / f"{name}.c3d"), "--out", str(prefix), "--quiet"],
                          capture_output=True, text=True, env=environment)
    if done.returncode != 0:
        failures.append(f"{name}: s2kf track failed: {done.stderr.strip()}")
        continue
    header, now = rows(f"{prefix}.csv")
    golden_header, before = rows(golden / f"{name}.csv")
    if header != golden_header or len(now) != len(before):
        failures.append(f"{name}: columns or row count differ ({len(now)} rows against {len(before)})")
        continue
    worst = (0.0, "", 0)
    for r, (a, b) in enumerate(zip(now, before)):
        for c, (x, y) in enumerate(zip(a, b)):
            if math.isnan(x) and math.isnan(y):
                continue
            position = header[c] in ("root_x", "root_y", "root_z")
            # An angle of pi and one of -pi are one orientation.
            difference = x - y if position else math.remainder(x - y, 2 * math.pi)
            tolerance = 1e-2 if position else 1e-4
            excess = abs(difference) / tolerance if not (math.isnan(x) or math.isnan(y)) else math.inf
            if excess > worst[0]:
                worst = (excess, header[c], r)
    if worst[0] > 1:
        failures.append(f"{name}: column {worst[1]} differs at row {worst[2]} by {worst[0]:.3g} x its tolerance")
    else:
        print(f"{name}: {len(now)} rows x {len(header)} columns as in {golden.name}/ (worst {worst[0]:.2g} x tolerance)")
for f in failures:
    print(f)
sys.exit(1 if failures else 0)
