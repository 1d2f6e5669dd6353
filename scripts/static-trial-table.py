#!/usr/bin/python3
"""Tracking accuracy with a static-trial calibration against the default, on simulated subjects.

For each seed it simulates a static trial (the bundled `static` motion, or --static-motion) and each
motion on the same subject (`s2kf simulate --seed S` draws the subject from the seed), then tracks
the motion three ways against its truth:

  default  s2kf track REC --truth TRUTH                    (calibrates on the recording itself)
  static   s2kf calibrate STATIC --static; s2kf track REC --subject SUBJECT
  both     the same subject as --markerset: calibrated again on the recording, starting from it

and prints Markdown tables of the means (segment orientation, limb flexion, root orientation RMS
in degrees, root position RMS and mean marker distance in mm), one per occlusion mode and seed set.

    scripts/static-trial-table.py [--s2kf build/s2kf] [--seeds 1,2,3] [--out DIR] [--raw FILE.json]
                                  [--occlusion none,paper] [--extra="--smooth"]
"""
import argparse
import json
import os
import subprocess
import sys

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--s2kf", default="build/s2kf")
parser.add_argument("--motions", default="walk,jumping_jacks,forward_roll,cartwheel")
parser.add_argument("--seeds", default="1,2,3,4,5,6")
parser.add_argument("--occlusion", default="none,paper", help="none, paper or both (none,paper)")
parser.add_argument("--static-motion", default="static", help="the static trial's motion (name or .json)")
parser.add_argument("--out", default="results/static-trial")
parser.add_argument("--raw", default="", help="write every run's figures to this JSON file")
parser.add_argument("--extra", default="", help="more options for every s2kf track, space-separated (--smooth)")
args = parser.parse_args()
PAPER_OCCLUSION = "0.005,100"
CONFIGS = ("default", "static", "both")
KEYS = ("segment_orientation_rms_deg", "limb_flexion_rms_deg", "root_orientation_rms_deg", "root_position_rms_mm")


def run(*command):
    result = subprocess.run([args.s2kf, *command], capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit(" ".join([args.s2kf, *command]) + " failed: " + (result.stderr or result.stdout).strip())


os.makedirs(args.out, exist_ok=True)
rows = []
for seed in args.seeds.split(","):
    static = os.path.join(args.out, f"static_{seed}.c3d")
    subject = os.path.join(args.out, f"subject_{seed}.json")
    run("simulate", "--motion", args.static_motion, "--seed", seed, "--out", static)
    run("calibrate", static, "--static", "--quiet", "--out", subject)
    for occlusion in args.occlusion.split(","):
        for motion in args.motions.split(","):
            base = os.path.join(args.out, f"{motion}_{seed}_{occlusion}")
            extra = ["--occlusion", PAPER_OCCLUSION] if occlusion == "paper" else []
            run("simulate", "--motion", motion, "--seed", seed, *extra, "--out", base + ".c3d")
            for config in CONFIGS:
                option = {"default": [], "static": ["--subject", subject], "both": ["--markerset", subject]}[config]
                prefix = f"{base}_{config}"
                run("track", base + ".c3d", "--truth", base + "_truth.csv", *option, *args.extra.split(),
                    "--formats", "csv", "--quiet", "--out", prefix)
                with open(prefix + ".json") as f:
                    summary = json.load(f)
                row = {"motion": motion, "seed": int(seed), "occlusion": occlusion, "config": config,
                       "mean_marker_distance_mm": summary["mean_marker_distance_all_frames_mm"]}
                row.update({k: summary["truth"][k] for k in KEYS})
                rows.append(row)

if args.raw:
    with open(args.raw, "w") as f:
        json.dump(rows, f, indent=1)
seeds = args.seeds
print(f"Means over {len(args.motions.split(','))} motions, seeds {seeds}; after 20 frames.\n")
print("| occlusion | calibration | segments (deg) | limb flexion (deg) | root orientation (deg) "
      "| root position (mm) | marker distance (mm) |")
print("|---|---|---|---|---|---|---|")
for occlusion in args.occlusion.split(","):
    for config in CONFIGS:
        group = [r for r in rows if r["occlusion"] == occlusion and r["config"] == config]
        means = [sum(r[k] for r in group) / len(group) for k in (*KEYS, "mean_marker_distance_mm")]
        print(f"| {occlusion} | {config} | " + " | ".join(f"{m:.2f}" for m in means) + " |")
