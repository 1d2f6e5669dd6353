#!/usr/bin/env python3
"""The same command gives the same numbers: `s2kf track` on the bundled recordings against the
motion files of tests/data/golden/ (written before the house was reorganised, commit 64422a8;
again when the bundle adjustment's relative tolerance became 1e-3, its accuracy measured).
Usage: same_numbers.py S2KF_PROGRAM REPOSITORY SCRATCH_DIR. Exits 1 naming the first difference.

Tolerances: 1e-4 rad (0.006 degrees) for angles and 0.01 mm for the root position, far below what
any change to the filter, the calibration or the model moves (tenths of a degree), and above what
another inlining or instruction order changes: rounding differences in the last digits, which the
filter carries over hundreds of frames to a few 1e-6 rad."""
import csv
import math
import pathlib
import subprocess
import sys

program, repo, scratch = sys.argv[1], pathlib.Path(sys.argv[2]), pathlib.Path(sys.argv[3])
scratch.mkdir(parents=True, exist_ok=True)


def rows(path):
    with open(path, newline="") as f:
        table = list(csv.reader(f))
    return table[0], [[float(v) for v in row] for row in table[1:]]


failures = []
for name in ("handstand", "walk", "cartwheel"):
    prefix = scratch / name
    done = subprocess.run([program, "track", str(repo / "data" / f"{name}.c3d"), "--out", str(prefix), "--quiet"],
                          capture_output=True, text=True)
    if done.returncode != 0:
        failures.append(f"{name}: s2kf track failed: {done.stderr.strip()}")
        continue
    header, now = rows(f"{prefix}.csv")
    golden_header, before = rows(repo / "tests" / "data" / "golden" / f"{name}.csv")
    if header != golden_header or len(now) != len(before):
        failures.append(f"{name}: columns or row count differ ({len(now)} rows against {len(before)})")
        continue
    worst = (0.0, "", 0)
    for r, (a, b) in enumerate(zip(now, before)):
        for c, (x, y) in enumerate(zip(a, b)):
            if math.isnan(x) and math.isnan(y):
                continue
            scale = 1e-2 if header[c] in ("root_x", "root_y", "root_z") else 1e-4
            excess = abs(x - y) / scale if not (math.isnan(x) or math.isnan(y)) else math.inf
            if excess > worst[0]:
                worst = (excess, header[c], r)
    if worst[0] > 1:
        failures.append(f"{name}: column {worst[1]} differs at row {worst[2]} by {worst[0]:.3g} x its tolerance")
    else:
        print(f"{name}: {len(now)} rows x {len(header)} columns as before (worst {worst[0]:.2g} x tolerance)")
for f in failures:
    print(f)
sys.exit(1 if failures else 0)
