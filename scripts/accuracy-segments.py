#!/usr/bin/python3
"""Per-segment orientation RMS (deg), mean over the cases of accuracy-table.py --raw files: the
tracker (one or more raw files, e.g. default and --no-calibrate) beside the identifiable-subject
references (at each ratio threshold) and the true-subject reference of the first file. Prints one
Markdown table per occlusion mode; the gap columns are tracker minus the reachable reference.

    scripts/accuracy-segments.py NAME=RAW.json [NAME=RAW.json ...]
"""
import json
import sys

if len(sys.argv) < 2:
    sys.exit(__doc__)
runs = []
for argument in sys.argv[1:]:
    name, _, path = argument.partition("=")
    with open(path) as f:
        runs.append((name, json.load(f)))


def mean(values):
    values = [v for v in values if v is not None]
    return sum(values) / len(values) if values else float("nan")


first = runs[0][1]
thresholds = []
for case in first:
    for r in case.get("identifiable_subject_reference") or []:
        if r["prior_only_fraction"] not in thresholds:
            thresholds.append(r["prior_only_fraction"])
for occlusion in (None, "0.005,100"):
    cases = {(c["motion"], c["seed"]): c for c in first if c["occlusion"] == occlusion}
    if not cases:
        continue
    columns = []  # (name, {case: truth})
    for name, data in runs:
        columns.append((name, {(c["motion"], c["seed"]): c["s2kf"]["truth"] for c in data
                               if c["occlusion"] == occlusion}))
    for name, data in runs:  # the same per-frame fit with each run's own (calibrated) model
        fits = {(c["motion"], c["seed"]): c.get("tracker_model_reference") for c in data
                if c["occlusion"] == occlusion}
        if all(fits.values()):
            columns.append((f"{name} model fit", fits))
    for t in thresholds:
        columns.append((f"identifiable ({t if isinstance(t, str) else format(t, 'g')})", {
            k: next(r["truth"] for r in c["identifiable_subject_reference"] if r["prior_only_fraction"] == t)
            for k, c in cases.items()}))
    columns.append(("true subject", {k: c["true_subject_reference"] for k, c in cases.items()}))
    keys = sorted(cases)
    segments = sorted(next(iter(cases.values()))["true_subject_reference"]["segment_rms_deg"])
    reachable = next((t for n, t in columns if n.startswith("identifiable")), columns[-1][1])
    print(f"\nOcclusion: {occlusion or 'none'} ({len(keys)} cases); per-segment RMS (deg), mean over cases")
    header = [n for n, _ in columns] + [f"{n} - reachable" for n, _ in columns[:len(runs)]]
    print("| segment | " + " | ".join(header) + " |")
    print("|---|" + "---|" * len(header))
    for segment in segments + ["**all**"]:
        def value(table, key):
            t = table[key]
            return t["segment_orientation_rms_deg"] if segment == "**all**" else t["segment_rms_deg"].get(segment)
        cells = [mean([value(table, k) for k in keys]) for _, table in columns]
        gaps = [mean([value(table, k) - value(reachable, k) for k in keys]) for _, table in columns[:len(runs)]]
        print(f"| {segment} | " + " | ".join(f"{v:.2f}" for v in cells + gaps) + " |")
    # Per case: the segment RMS of each column.
    print("\n| motion | seed | " + " | ".join(n for n, _ in columns) + " |")
    print("|---|---|" + "---|" * len(columns))
    for k in keys:
        print(f"| {k[0]} | {k[1]} | " + " | ".join(f"{table[k]['segment_orientation_rms_deg']:.2f}"
                                                  for _, table in columns) + " |")
