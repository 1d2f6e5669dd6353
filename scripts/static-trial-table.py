#!/usr/bin/python3
"""Tracking accuracy with a static-trial calibration against the default, on simulated subjects.

For each seed it simulates a static trial (the bundled `static` motion, or --static-motion) and each
motion on the same subject (`s2kf simulate --seed S` draws the subject from the seed), then tracks
the motion three ways against its truth:

  default  s2kf track REC --truth TRUTH                    (calibrates on the recording itself)
  no-stretch  the same with --no-static-stretch
  static   s2kf calibrate STATIC --static; s2kf track REC --subject SUBJECT
  both     the same subject as --markerset: calibrated again on the recording, starting from it
  track    s2kf track REC --static STATIC [--static-options]  (what a user runs: the static trial
           and the recording calibrated together)
  alone    s2kf track REC --static STATIC --static-alone [--static-options]  (calibrated on the
           static trial alone)

--lead-in starts every motion with the seed's static trial (its stance, 3 s) and a 1 s step from it
into the motion: a static trial inside the recording, which `s2kf track` finds by itself (config
`default`; `no-stretch` is the same with --no-static-stretch).

--stance-sd DEG holds each seed's static trial in a posture of its own: every joint angle off the
reference pose (--stance) by a draw of SD DEG (seeded by the seed, kept inside the joint's limits),
as people stand; 0 keeps the bundled static motion's posture.

and prints Markdown tables of the means (segment orientation, limb flexion, root orientation RMS
in degrees, root position RMS and mean marker distance in mm), one per occlusion mode and seed set.

    scripts/static-trial-table.py [--s2kf build/s2kf] [--seeds 1,2,3] [--out DIR] [--raw FILE.json]
                                  [--occlusion none,paper] [--extra="--smooth"] [--configs default,track]
                                  [--stance zero|t-pose|a-pose] [--stance-sd DEG] [--static-options="..."]
                                  [--lead-in] [--known-stance [--unknown-joints REz,LEz,...]]

--known-stance gives track and alone the stance held (the static trial's true first frame) as
--static-pose; with --unknown-joints those joints are given at the reference pose instead: what a
calibration that knows the rest of the stance exactly, and nothing of these joints, reaches.
"""
import argparse
import json
import math
import os
import random
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
parser.add_argument("--configs", default="default,static,both", help="of default, no-stretch, static, both, track, alone")
parser.add_argument("--stance", default="zero", help="the static trial's reference pose: zero, t-pose, a-pose")
parser.add_argument("--stance-sd", type=float, default=0.0, help="SD (deg) of each joint's offset from it")
parser.add_argument("--markerset", default="", help="the markers the simulated subject wears (plugin_gait, cmu)")
parser.add_argument("--lead-in", action="store_true", help="every motion starts with the static trial")
parser.add_argument("--static-options", default="", help="more options for --static (track, alone), space-separated")
parser.add_argument("--known-stance", action="store_true",
                    help="give track and alone the stance held as the reference pose (--static-pose with the "
                         "static trial's _truth.csv): what a stance known exactly would give")
parser.add_argument("--unknown-joints", default="",
                    help="with --known-stance: joints given at the reference pose, not as held (REz,LEz)")
args = parser.parse_args()
CONFIGS = tuple(args.configs.split(","))
PAPER_OCCLUSION = "0.005,100"
KEYS = ("segment_orientation_rms_deg", "limb_flexion_rms_deg", "root_orientation_rms_deg", "root_position_rms_mm")


def run(*command):
    result = subprocess.run([args.s2kf, *command], capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit(" ".join([args.s2kf, *command]) + " failed: " + (result.stderr or result.stdout).strip())


def reference_angle_deg(name):
    """The reference pose's (--stance) angle of joint `name` in degrees: the upper arms' LSy, RSy."""
    reference = {"t-pose": 90, "a-pose": 45}.get(args.stance, 0)
    return float({"LSy": reference, "RSy": -reference}.get(name, 0))


def write_stance(seed, path):
    """The bundled static motion with every joint held off the reference pose by its own draw."""
    table = subprocess.run([args.s2kf, "model", "--joints"], capture_output=True, text=True, check=True).stdout
    limits = {}
    for line in table.splitlines()[1:]:
        name, _parent, _axis, lower, upper = line.split(",")[:5]
        limits[name] = (math.degrees(float(lower)), math.degrees(float(upper)))
    base = {name: reference_angle_deg(name) for name in limits}
    draw = random.Random(1000 + seed)
    held = {}
    for name, (lower, upper) in limits.items():
        value = base[name] + draw.gauss(0, args.stance_sd)
        held[name] = min(max(value, lower + 0.5), upper - 0.5)
    with open(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data", "motions", "static.json")) as f:
        motion = json.load(f)
    motion["name"] = f"static_{args.stance}_{seed}"
    motion["description"] = f"A static trial near the {args.stance} pose, every joint off it by SD {args.stance_sd} deg"
    for key in motion["keyframes"]:
        joints = dict(held)
        for name, sway in key["joints"].items():
            joints[name] = held[name] + sway
        key["joints"] = joints
    with open(path, "w") as f:
        json.dump(motion, f, indent=1)


def write_lead_in(static_motion, motion, path):
    """The static trial's keyframes, then `motion`'s 1 s after its last (a step into the motion)."""
    def load(name):
        bundled = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data", "motions", name + ".json")
        with open(name if name.endswith(".json") else bundled) as f:
            return json.load(f)
    still, moving = load(static_motion), load(motion)
    start = still["keyframes"][-1]["time"] + 1.0 - moving["keyframes"][0]["time"]
    for key in moving["keyframes"]:
        key["time"] += start
    still["name"] = moving["name"] + "_after_static"
    still["description"] = "A static trial, then " + moving["name"]
    still["keyframes"] += moving["keyframes"]
    with open(path, "w") as f:
        json.dump(still, f, indent=1)


def known_stance(seed):
    """The static trial's true posture as a pose CSV, --unknown-joints put back at the reference pose."""
    truth = os.path.join(args.out, f"static_{seed}_truth.csv")
    unknown = [name for name in args.unknown_joints.split(",") if name]
    if not unknown:
        return truth
    with open(truth) as f:
        lines = f.read().splitlines()
    header = lines[0].split(",")
    for name in unknown:
        if name not in header:
            sys.exit(f"--unknown-joints: {name} is not a joint of the model")
    rows = [lines[0]]
    for line in lines[1:]:
        cells = line.split(",")
        for name in unknown:
            cells[header.index(name)] = repr(math.radians(reference_angle_deg(name)))
        rows.append(",".join(cells))
    path = os.path.join(args.out, f"static_{seed}_known.csv")
    with open(path, "w") as f:
        f.write("\n".join(rows) + "\n")
    return path


os.makedirs(args.out, exist_ok=True)
rows = []
for seed in args.seeds.split(","):
    static = os.path.join(args.out, f"static_{seed}.c3d")
    subject = os.path.join(args.out, f"subject_{seed}.json")
    static_motion = args.static_motion
    if args.stance_sd > 0 or args.stance != "zero":
        static_motion = os.path.join(args.out, f"static_motion_{seed}.json")
        write_stance(int(seed), static_motion)
    worn = ["--markerset", args.markerset] if args.markerset else []
    run("simulate", "--motion", static_motion, "--seed", seed, *worn, "--out", static)
    if "static" in CONFIGS or "both" in CONFIGS:
        run("calibrate", static, "--static", "--quiet", "--out", subject, *args.static_options.split())
    for occlusion in args.occlusion.split(","):
        for motion in args.motions.split(","):
            base = os.path.join(args.out, f"{motion}_{seed}_{occlusion}")
            extra = ["--occlusion", PAPER_OCCLUSION] if occlusion == "paper" else []
            simulated = motion
            if args.lead_in:
                simulated = base + "_motion.json"
                write_lead_in(static_motion, motion, simulated)
            run("simulate", "--motion", simulated, "--seed", seed, *extra, *worn, "--out", base + ".c3d")
            static_options = args.static_options.split()
            if args.known_stance:
                static_options += ["--static-pose", known_stance(seed)]
            for config in CONFIGS:
                option = {"default": [], "no-stretch": ["--no-static-stretch"], "static": ["--subject", subject], "both": ["--markerset", subject],
                          "track": ["--static", static, *static_options],
                          "alone": ["--static", static, "--static-alone", *static_options]}[config]
                prefix = f"{base}_{config}"
                run("track", base + ".c3d", "--truth", base + "_truth.csv", *option, *args.extra.split(),
                    "--formats", "csv", "--quiet", "--out", prefix)
                with open(prefix + ".json") as f:
                    summary = json.load(f)
                row = {"motion": motion, "seed": int(seed), "occlusion": occlusion, "config": config,
                       "mean_marker_distance_mm": summary["mean_marker_distance_all_frames_mm"],
                       "most_rejected_share": max([(r["innovation"] + r["frozen"]) / summary["frames"]
                                                   for r in summary["rejected_markers"]] or [0])}
                row.update({k: summary["truth"][k] for k in KEYS})
                row["segment_rms_deg"] = summary["truth"]["segment_rms_deg"]
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
