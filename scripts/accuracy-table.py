#!/usr/bin/python3
"""The accuracy table of docs/accuracy.md: `s2kf evaluate --motion` on simulated realistic subjects
(several motions and subject seeds, with and without the paper's occlusion), the S2KF's default
beside the true-subject reference. Prints a Markdown table and the means over the runs.

    scripts/accuracy-table.py [--s2kf build/s2kf] [--motions walk,...] [--seeds 1,2,3] [--out DIR]
                              [--occlusion none,paper] [--extra=--no-calibrate] [--raw FILE] [--reuse]

--raw writes every case's accuracy figures (filter, smoothed, reference, latency, marker distance,
per segment) to one JSON file; --reuse reads a case's summary.json from --out when it is there
instead of running it again.
"""
import argparse
import json
import os
import subprocess
import sys

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--s2kf", default="build/s2kf")
parser.add_argument("--motions", default="walk,jumping_jacks,forward_roll,cartwheel")
parser.add_argument("--seeds", default="1,2,3")
parser.add_argument("--out", default="results/accuracy")
parser.add_argument("--occlusion", default="none,paper", help="none, paper or both (none,paper)")
parser.add_argument("--extra", default="", help="more options for s2kf evaluate, space-separated")
parser.add_argument("--raw", default="", help="write every case's figures to this JSON file")
parser.add_argument("--reuse", action="store_true", help="read existing summaries instead of running")
args = parser.parse_args()

PAPER_OCCLUSION = "0.005,100"
rows = []
raw = []
modes = [mode == "paper" for mode in args.occlusion.split(",")]
for occluded in modes:
    for motion in args.motions.split(","):
        for seed in args.seeds.split(","):
            out = os.path.join(args.out, f"{motion}_{seed}" + ("_occluded" if occluded else ""))
            command = [args.s2kf, "evaluate", "--motion", motion, "--subject-seed", seed, "--runs", "1",
                       "--samples", "301", "--smooth", "--quiet", "--out", out] + args.extra.split()
            if occluded:
                command += ["--occlusion", PAPER_OCCLUSION]
            if not (args.reuse and os.path.exists(os.path.join(out, "summary.json"))):
                result = subprocess.run(command, capture_output=True, text=True)
                if result.returncode != 0:
                    sys.exit(" ".join(command) + " failed: " + result.stderr.strip())
            with open(os.path.join(out, "summary.json")) as f:
                summary = json.load(f)
            raw.append({"motion": motion, "seed": int(seed), "occlusion": PAPER_OCCLUSION if occluded else None,
                        "command": " ".join(command), "machine": summary["machine"],
                        "calibrated": summary["calibrated"],
                        "s2kf": {k: summary["s2kf"][k] for k in ("truth", "latency_ms", "mean_marker_distance_mm")},
                        "s2kf_smoothed": summary["s2kf_smoothed"],
                        "true_subject_reference": summary["true_subject_reference"],
                        "identifiable_subject_reference": summary.get("identifiable_subject_reference"),
                        "tracker_model_reference": summary.get("tracker_model_reference"),
                        "true_subject_tracking_reference": summary.get("true_subject_tracking_reference"),
                        "constant_placement_reference": summary.get("constant_placement_reference"),
                        "calibration_at_true_poses_reference": summary.get("calibration_at_true_poses_reference")})
            if "error_by_time_hidden" in summary:
                raw[-1]["error_by_time_hidden"] = summary["error_by_time_hidden"]
            rows.append((occluded, motion, seed, summary["s2kf"]["truth"], summary["s2kf_smoothed"],
                         summary["true_subject_reference"]))

keys = ["segment_orientation_rms_deg", "limb_flexion_rms_deg", "root_orientation_rms_deg"]
print("| occlusion | motion | seed | segment RMS (deg): filter / smoothed / reference | "
      "flexion RMS (deg) | root orientation (deg) | limit violations |")
print("|---|---|---|---|---|---|---|")
for occluded, motion, seed, filtered, smoothed, reference in rows:
    cells = [" / ".join(f"{t[k]:.2f}" for t in (filtered, smoothed, reference)) for k in keys]
    print(f"| {'paper' if occluded else 'none'} | {motion} | {seed} | " + " | ".join(cells) +
          f" | {filtered['joint_limit_violations']} / {smoothed['joint_limit_violations']} |")
for occluded in modes:
    chosen = [r for r in rows if r[0] == occluded]
    means = [" / ".join(f"{sum(r[i][k] for r in chosen) / len(chosen):.2f}" for i in (3, 4, 5)) for k in keys]
    print(f"| {'paper' if occluded else 'none'} | **mean** | | " + " | ".join(means) + " | |")
if args.raw:
    with open(args.raw, "w") as f:
        json.dump(raw, f, indent=1)
        f.write("\n")
