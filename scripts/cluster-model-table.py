#!/usr/bin/python3
"""The cluster model against anatomical markers on simulated subjects, truth known.

For each motion and seed it simulates the subject wearing the cluster model
(data/simulation/plugin_gait_upper_clusters.json) and the full Plug-in Gait set, each with a static
trial of the same subject, and tracks them (101 samples, calibrated, --truth):

  clusters           s2kf track REC
  clusters_static    s2kf track REC --static STATIC --static-alone [--static-options]  (the subject
                     calibrated on the static trial alone)
  clusters_joint     s2kf track REC --static STATIC [--static-options]  (the static trial and the
                     recording calibrated together, what --static does)
  anatomical         the same for the Plug-in Gait recording
  anatomical_static
  anatomical_joint

It prints a Markdown table: joint-angle RMS (deg, frames 20 on, offsets included) of the hips,
knees and ankles from the written CSV against _truth.csv, the pelvis orientation RMS and the mean
marker distance from the summary, the cluster markers placed on their true segment, and the
segments not observed.

    scripts/cluster-model-table.py [--s2kf build/s2kf] [--motions walk,jumping_jacks,squats]
                                   [--seeds 1,2,3] [--frames 400] [--out DIR] [--raw FILE.json]
                                   [--configs clusters,clusters_static,anatomical,anatomical_static]
                                   (or _joint for the static trial calibrated with the recording)
                                   [--static-options="--static-posture near"]
                                   [--simulate-options="--soft-tissue 0"] [--reuse]
"""
import argparse
import csv
import json
import math
import os
import subprocess
import sys

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--s2kf", default="build/s2kf")
parser.add_argument("--motions", default="walk,jumping_jacks,squats")
parser.add_argument("--seeds", default="1,2,3")
parser.add_argument("--frames", default="400")
parser.add_argument("--out", default="results/cluster-model")
parser.add_argument("--raw", default="", help="write every run's figures to this JSON file")
parser.add_argument("--configs", default="clusters,clusters_static,anatomical,anatomical_static")
parser.add_argument("--static-options", default="", help="more options for --static, space-separated")
parser.add_argument("--simulate-options", default="", help="more options for s2kf simulate (--soft-tissue 0)")
parser.add_argument("--reuse", action="store_true", help="keep summaries already in --out")
args = parser.parse_args()

CLUSTER_SET = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data", "simulation",
                           "plugin_gait_upper_clusters.json")
# The segment each cluster of the simulated set rides on (label without its last letter).
TRUE_SEGMENT = {"PEL": "root", "LFM": "LH", "RFM": "RH", "LTB": "LK", "RTB": "RK", "LFT": "LA", "RFT": "RA",
                "LG": "LH", "RG": "RH"}
GROUPS = {"hips": ("LH", "RH"), "knees": ("LK", "RK"), "ankles": ("LA", "RA")}


def run(*command):
    result = subprocess.run([args.s2kf, *command], capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit(" ".join([args.s2kf, *command]) + " failed: " + (result.stderr or result.stdout).strip())


def read_csv(path):
    with open(path) as f:
        rows = list(csv.reader(f))
    return rows[0], [[float(v) if v not in ("", "nan", "NaN") else math.nan for v in row] for row in rows[1:]]


def joint_rms(motion_csv, truth_csv, groups):
    """RMS (deg) over frames 20 on of the joints whose name without its axis is in `groups`."""
    names, motion = read_csv(motion_csv)
    truth_names, truth = read_csv(truth_csv)
    total, count, missing = 0.0, 0, False
    for column, name in enumerate(truth_names):
        if name[:-1] not in groups:
            continue
        at = names.index(name)
        for f in range(20, len(truth)):
            e = math.remainder(motion[f][at] - truth[f][column], 2 * math.pi)
            if math.isfinite(e):
                total, count = total + e * e, count + 1
            else:
                missing = True
    return (math.degrees(math.sqrt(total / count)) if count else math.nan), missing


def placement(summary):
    placed = summary.get("markers_inferred") or []
    right = sum(1 for m in placed if TRUE_SEGMENT.get(m["label"][:-1]) == m["segment"])
    wrong = [m["label"] + " " + m["segment"] for m in placed if TRUE_SEGMENT.get(m["label"][:-1]) != m["segment"]]
    return len(placed), right, wrong, len(summary.get("labels_left_out") or [])


def main():
    os.makedirs(args.out, exist_ok=True)
    configs = args.configs.split(",")
    raw = {}
    for motion in args.motions.split(","):
        for seed in args.seeds.split(","):
            key = motion + " " + seed
            raw[key] = {}
            for kind, markerset in (("clusters", CLUSTER_SET), ("anatomical", "plugin_gait")):
                if not any(c.startswith(kind) for c in configs):
                    continue
                base = os.path.join(args.out, f"{kind}_{motion}_{seed}")
                still = os.path.join(args.out, f"{kind}_static_{seed}")
                if not (args.reuse and os.path.exists(base + ".c3d")):
                    run("simulate", "--motion", motion, "--frames", args.frames, "--seed", seed, "--markerset",
                        markerset, "--out", base + ".c3d", *args.simulate_options.split())
                if not (args.reuse and os.path.exists(still + ".c3d")):
                    run("simulate", "--motion", "static", "--seed", seed, "--markerset", markerset, "--out",
                        still + ".c3d", *args.simulate_options.split())
                for config in (kind, kind + "_static", kind + "_joint"):
                    if config not in configs:
                        continue
                    suffix = config[len(kind):]  # "", "_static" or "_joint"
                    prefix = base + "_tracked" + suffix
                    if not (args.reuse and os.path.exists(prefix + ".json")):
                        alone = ["--static-alone"] if suffix == "_static" else []
                        extra = ["--static", still + ".c3d", *alone, *args.static_options.split()] if suffix else []
                        run("track", base + ".c3d", "--out", prefix, "--samples", "101", "--formats", "csv",
                            "--truth", base + "_truth.csv", *extra)
                    with open(prefix + ".json") as f:
                        summary = json.load(f)
                    figures = {name: joint_rms(prefix + ".csv", base + "_truth.csv", groups)[0]
                               for name, groups in GROUPS.items()}
                    figures["pelvis"] = summary["truth"]["root_orientation_rms_deg"]
                    figures["distance"] = summary["mean_marker_distance_all_frames_mm"]
                    figures["unobserved"] = (summary.get("unobserved") or {}).get("segments", [])
                    figures["placed"], figures["right"], figures["wrong"], figures["left_out"] = placement(summary)
                    figures["source"] = summary.get("marker_set_source", "")
                    raw[key][config] = figures
    if args.raw:
        with open(args.raw, "w") as f:
            json.dump(raw, f, indent=1)
    print("| motion, seed | hips | knees | ankles | pelvis orientation | marker distance (mm) | placed, on their "
          "true segment, left out | not observed |")
    print("|---|---|---|---|---|---|---|---|")
    for key, runs in raw.items():
        cells = []
        for name in ("hips", "knees", "ankles", "pelvis", "distance"):
            cells.append(" / ".join(f"{runs[c][name]:.2f}" if c in runs else "-" for c in configs))
        c = next((c for c in ("clusters_static", "clusters_joint") if c in runs), "clusters")
        p = runs.get(c, {})
        placed = f"{p.get('placed')}, {p.get('right')}, {p.get('left_out')} ({', '.join(p.get('wrong', []))})" if p else "-"
        unobserved = " / ".join(",".join(runs[c]["unobserved"]) or "-" for c in configs if c in runs)
        print(f"| {key} | " + " | ".join(cells) + f" | {placed} | {unobserved} |")


main()
