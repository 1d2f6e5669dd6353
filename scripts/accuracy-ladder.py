#!/usr/bin/python3
"""The ladder of references behind the tracker's accuracy, from an accuracy-table.py --raw file:
for each occlusion mode the means over its cases of segment-orientation, limb-flexion and
root-orientation RMS (deg) for the tracker and each per-frame fit started at the true pose, from
the best constant subject with every pose known down to the marker set as it is; then the same per
segment. Prints Markdown.

    scripts/accuracy-ladder.py RAW.json
"""
import json
import sys

if len(sys.argv) != 2:
    sys.exit(__doc__)
with open(sys.argv[1]) as f:
    cases = json.load(f)


def identifiable(case, fraction):
    for r in case.get("identifiable_subject_reference") or []:
        if r["prior_only_fraction"] == fraction:
            return r["truth"]
    return None


def nested(*keys):
    def get(case):
        value = case
        for key in keys:
            value = value.get(key) if isinstance(value, dict) else None
        return value
    return get


RUNGS = [
    ("tracker (S2KF, default options)", nested("s2kf", "truth")),
    ("tracker with the true subject", nested("true_subject_tracking_reference", "s2kf")),
    ("tracker with the true subject, smoothed", nested("true_subject_tracking_reference", "s2kf_smoothed")),
    ("fit with the tracker's calibrated model", nested("tracker_model_reference")),
    ("fit with the calibration's bundle adjustment started at the true poses",
     nested("calibration_at_true_poses_reference", "truth")),
    ("fit with the marker set as it is (nominal)", lambda c: identifiable(c, "nominal")),
    ("fit with the true subject, exact gauges reset (identifiable, 1e-5)", lambda c: identifiable(c, 1e-5)),
    ("fit with the best constant placement, exact gauges reset",
     nested("constant_placement_reference", "identifiable", "truth")),
    ("fit with the true subject", nested("true_subject_reference")),
    ("fit with the best constant placement (every pose known)", nested("constant_placement_reference", "truth")),
]
METRICS = ["segment_orientation_rms_deg", "limb_flexion_rms_deg", "root_orientation_rms_deg"]


def mean(values):
    values = [v for v in values if v is not None]
    return sum(values) / len(values) if values else float("nan")


for occlusion in sorted({c["occlusion"] or "" for c in cases}):
    group = [c for c in cases if (c["occlusion"] or "") == occlusion]
    title = "the paper's occlusion (" + occlusion + ")" if occlusion else "no occlusion"
    print(f"\n{title}, {len(group)} cases; means of the per-case RMS (deg)\n")
    print("| | segments | limb flexion | root orientation |")
    print("|---|---|---|---|")
    for name, get in RUNGS:
        row = [mean([(get(c) or {}).get(m) for c in group]) for m in METRICS]
        print(f"| {name} | " + " | ".join(f"{v:.2f}" for v in row) + " |")
    segments = list(group[0]["s2kf"]["truth"]["segment_rms_deg"])
    print(f"\nPer segment, {title} (columns in the order of the rows above)\n")
    print("| segment | " + " | ".join(str(k + 1) for k in range(len(RUNGS))) + " |")
    print("|---|" + "---|" * len(RUNGS))
    for segment in segments:
        row = [mean([((get(c) or {}).get("segment_rms_deg") or {}).get(segment) for c in group])
               for _, get in RUNGS]
        print(f"| {segment} | " + " | ".join(f"{v:.1f}" for v in row) + " |")
