#!/usr/bin/python3
"""Per joint: the static stance, the static trial's posture error and the moving trials' bias, against the truth.

Reads the folder that `scripts/static-trial-table.py --configs static --stance-sd DEG --out DIR` wrote
(each seed's static trial, its subject and stance, and each motion tracked with that subject), tracks
each static trial with its own subject, and prints per joint and seed (degrees):

  stance   the angle held in the static trial (its offset from the reference pose)
  static   the static trial tracked with the subject calibrated on it, mean (estimate - truth): the
           posture the calibration settled on, off the one held
  motion   the moving trials tracked with that subject, mean (estimate - truth) over frames and
           motions, +- the mean SD over frames: a constant error the calibration left, and how much
           the error varies with the motion

    scripts/static-trial-bias.py --out DIR [--s2kf build/s2kf] [--seeds 1,2,3] [--joints RWx,RWy,...]
"""
import argparse
import csv
import json
import math
import os
import subprocess

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--s2kf", default="build/s2kf")
parser.add_argument("--out", required=True, help="the --out folder of static-trial-table.py (--configs static)")
parser.add_argument("--seeds", default="1,2,3")
parser.add_argument("--motions", default="walk,jumping_jacks,forward_roll,cartwheel")
parser.add_argument("--occlusion", default="none")
parser.add_argument("--joints", default="RWx,RWy,LWx,LWy,REz,LEz,RSz,LSz,LHz,RHz")
parser.add_argument("--skip", type=int, default=20, help="frames left out at the start (convergence)")
args = parser.parse_args()


def load(path):
    with open(path) as f:
        rows = list(csv.reader(f))
    return rows[0], [[float(x) for x in row] for row in rows[1:]]


def bias(estimate_path, truth_path, joint):
    """Mean and SD (deg) of estimate - truth of one joint over the frames after --skip."""
    header, estimate = load(estimate_path)
    _, truth = load(truth_path)
    column = header.index(joint)
    frames = min(len(estimate), len(truth))
    d = [math.degrees(estimate[k][column] - truth[k][column]) for k in range(args.skip, frames)]
    mean = sum(d) / len(d)
    return mean, math.sqrt(sum((x - mean) ** 2 for x in d) / len(d))


seeds = args.seeds.split(",")
for seed in seeds:
    base = os.path.join(args.out, f"static_{seed}")
    subprocess.run([args.s2kf, "track", base + ".c3d", "--subject", os.path.join(args.out, f"subject_{seed}.json"),
                    "--truth", base + "_truth.csv", "--formats", "csv", "--quiet", "--out", base + "_tracked"],
                   check=True, capture_output=True)
print("| joint | " + " | ".join(f"seed {s}: stance, static, motion" for s in seeds) + " |")
print("|---|" + "---|" * len(seeds))
for joint in args.joints.split(","):
    cells = []
    for seed in seeds:
        with open(os.path.join(args.out, f"static_motion_{seed}.json")) as f:
            stance = json.load(f)["keyframes"][0]["joints"][joint]
        base = os.path.join(args.out, f"static_{seed}")
        static, _ = bias(base + "_tracked.csv", base + "_truth.csv", joint)
        moving = [bias(os.path.join(args.out, f"{m}_{seed}_{args.occlusion}_static.csv"),
                       os.path.join(args.out, f"{m}_{seed}_{args.occlusion}_truth.csv"), joint)
                  for m in args.motions.split(",")]
        mean = sum(b[0] for b in moving) / len(moving)
        spread = sum(b[1] for b in moving) / len(moving)
        cells.append(f"{stance:+.1f}, {static:+.1f}, {mean:+.1f} +- {spread:.1f}")
    print(f"| {joint} | " + " | ".join(cells) + " |")
