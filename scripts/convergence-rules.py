#!/usr/bin/env python3
"""The convergence frame of `s2kf track` results under the earlier and the current rule, from
their per-frame marker distances (PREFIX_markers.csv) and rates (PREFIX.json), computed here
independently of the program (docs/notes/2026-11-23-first-accuracy-tables.md).

    scripts/convergence-rules.py PREFIX [PREFIX ...]

Earlier rule: the first frame after which the distance stays within 1.5 times its final level (the
median over the second half); any late fast phase restarts it. Current rule: the first measured
frame from which the median over the next second falls below 1.5 times the median over the whole
recording. Prints, per result, both frames, the mean distance from each (the level after
convergence), the program's own converged_frame, and the frame count.
"""
import csv
import json
import math
import statistics
import sys


def distances(prefix):
    with open(prefix + "_markers.csv") as f:
        return [float(row["mean_marker_distance_mm"]) for row in csv.DictReader(f)]


def finite(values):
    return [v for v in values if math.isfinite(v)]


def earlier_rule(d, factor=1.5):
    level = statistics.median(finite(d[len(d) // 2:]))
    first = 0
    for f, v in enumerate(d):
        if not math.isfinite(v):
            if f == first:
                first += 1
            continue
        if v > factor * level:
            first = f + 1
    return first


def current_rule(d, window, factor=1.5):
    threshold = factor * statistics.median(finite(d))
    for f, v in enumerate(d):
        if math.isfinite(v):
            ahead = finite(d[f:f + window])
            if statistics.median(ahead) < threshold:
                return f
    return -1


def mean_from(d, f):
    values = finite(d[f:]) if f >= 0 else []
    return sum(values) / len(values) if values else float("nan")


print("result,frames,earlier_rule_frame,earlier_level_mm,current_rule_frame,current_level_mm,"
      "program_converged_frame,program_level_mm")
for prefix in sys.argv[1:]:
    d = distances(prefix)
    with open(prefix + ".json") as f:
        summary = json.load(f)
    window = max(1, round(summary["rate"])) if summary["rate"] >= 1 else 1
    old, new = earlier_rule(d), current_rule(d, window)
    level = summary["mean_marker_distance_mm"]
    print(f"{prefix},{len(d)},{old},{mean_from(d, old):.1f},{new},{mean_from(d, new):.1f},"
          f"{summary['converged_frame']},{level if level is None else round(level, 1)}")
