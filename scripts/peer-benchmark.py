#!/usr/bin/env python3
"""s2kf beside its peers on the same recordings, in one run: OpenSim's Inverse Kinematics tool
(frame-by-frame least squares on the markers) and biorbd's extended Kalman filter on markers
(KalmanReconsMarkers), both with the model s2kf calibrated and wrote (.osim; the .bioMod is written
from it), on the .trc s2kf wrote. Per recording and method: time per frame, marker RMS (mm, over the
markers seen each frame, averaged over frames) and, on simulated recordings, the joint-angle RMS (deg)
against the truth over the 40 joints.

  $(scripts/python-env.sh) scripts/peer-benchmark.py [--out DIR] [--frames N] [--repeat R] [REC.c3d ...]
      [--simulate MOTION:SEED ...]
  (scripts/python-env.sh prints the test environment's python, which has opensim and biorbd)

Without recordings: data/handstand.c3d, data/walk.c3d, tests/data/c3d/85_02.c3d (CMU),
tests/data/c3d/PiG_Motion-FlatFoot-One.c3d (Plug-in Gait), and squats and jumping_jacks simulated
(seed 1). Times: s2kf's `tracking` stage of PREFIX.json (the filter, one thread), OpenSim's
InverseKinematicsTool.run(), biorbd's reconstructFrame loop; each divided by the frames, the median of
R runs (default 3).
Prints a Markdown table (docs/benchmarks.md).
"""
import argparse
import json
import math
import os
import pathlib
import sys
import time

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "tests" / "tools"))
import opensim_peer  # noqa: E402

DEFAULT_RECORDINGS = ["data/handstand.c3d", "data/walk.c3d", "tests/data/c3d/85_02.c3d",
                      "tests/data/c3d/PiG_Motion-FlatFoot-One.c3d"]
DEFAULT_SIMULATED = ["squats:1", "jumping_jacks:1"]


def joint_rms_deg(labels, times, values, truth_header, truth):
    """RMS over frames (deg) of `values` (rad) against the truth CSV at the same times, each difference
    wrapped to (-180, 180] degrees: (over the 40 joints, over the 28 of arms and legs). The spine's and
    neck's 12 are apart because markers ride on the pelvis, thorax and head only: how the bend is shared
    between the two joints of each is the motion model's (s2kf) or the solver's choice."""
    joints = [c for c in truth_header if c not in ("frame", "time") and not c.startswith("root_")]
    rows = [int(np.argmin(np.abs(truth[:, truth_header.index("time")] - t))) for t in times]
    errors = []
    for label in joints:
        ours = values[:, labels.index(label)]
        true = truth[rows, truth_header.index(label)]
        errors.append(np.angle(np.exp(1j * (ours - true))))  # wrapped to (-pi, pi]
    e = np.degrees(np.array(errors))
    limbs = [k for k, label in enumerate(joints) if label[1] in "SEWHKA"]
    return float(np.sqrt(np.nanmean(e ** 2))), float(np.sqrt(np.nanmean(e[limbs] ** 2)))


def biorbd_kalman(biorbd, biomod, dofs, names, recorded, rate):
    """biorbd's KalmanReconsMarkers on every frame: (values (frames, dofs) rad/m, marker RMS per frame
    mm, seconds)."""
    model = biorbd.Model(str(biomod))
    order = [n.to_string() for n in model.markerNames()]
    columns = [names.index(n) for n in order]
    kalman = biorbd.KalmanReconsMarkers(model, biorbd.KalmanParam(int(round(rate))))
    q = biorbd.GeneralizedCoordinates(model)
    qdot = biorbd.GeneralizedVelocity(model)
    qddot = biorbd.GeneralizedAcceleration(model)
    frames = recorded.shape[0]
    targets = [[biorbd.NodeSegment(*(recorded[f, c] / 1000.0)) for c in columns] for f in range(frames)]
    values = np.zeros((frames, model.nbQ()))
    start = time.perf_counter()
    for f in range(frames):
        kalman.reconstructFrame(model, targets[f], q, qdot, qddot)
        values[f] = q.to_array()
    seconds = time.perf_counter() - start
    rms = np.full(frames, np.nan)
    for f in range(frames):
        at = np.array([m.to_array() for m in model.markers(values[f])]) * 1000.0
        seen = np.all(np.isfinite(recorded[f, columns]), axis=1)
        if seen.any():
            rms[f] = math.sqrt(np.mean(np.sum((at[seen] - recorded[f, columns][seen]) ** 2, axis=1)))
    return values, rms, seconds


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("recordings", nargs="*")
    parser.add_argument("--simulate", action="append", default=None, metavar="MOTION:SEED")
    parser.add_argument("--out", default="build/peer-benchmark")
    parser.add_argument("--frames", type=int, default=0, help="frames per recording at most (0: all)")
    parser.add_argument("--repeat", type=int, default=3, help="runs of each method; times are their median")
    args = parser.parse_args()
    os.chdir(opensim_peer.SOURCE_DIR)
    osim = opensim_peer.import_peer("opensim")
    biorbd = opensim_peer.import_peer("biorbd")
    if osim is None:
        sys.exit("opensim does not exist on PyPI for this machine; nothing to compare with")
    osim.Logger.setLevelString("error")
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    recordings = [(pathlib.Path(r), None) for r in (args.recordings or DEFAULT_RECORDINGS)]
    for item in (args.simulate if args.simulate is not None else ([] if args.recordings else DEFAULT_SIMULATED)):
        motion, seed = item.split(":")
        path = out / f"simulated_{motion}_{seed}.c3d"
        opensim_peer.run_cli("simulate", "--motion", motion, "--seed", seed, "--out", path)
        recordings.append((path, path.with_name(path.stem + "_truth.csv")))

    rows = []
    for recording, truth_path in recordings:
        name = recording.stem
        prefix = out / name
        s2kf_times = []
        for _ in range(args.repeat):
            opensim_peer.run_cli("track", recording, "--out", prefix, "--quiet", "--formats", "csv,mot,osim,trc")
            summary = json.loads(pathlib.Path(str(prefix) + ".json").read_text())
            s2kf_times.append(summary["seconds_per_stage"]["tracking"] / summary["frames"])
        names, trc_times, recorded = opensim_peer.read_trc(str(prefix) + ".trc")
        labels, mot_times, mot_values = opensim_peer.read_mot(osim, str(prefix) + ".mot")
        frames = len(mot_times) if args.frames <= 0 else min(args.frames, len(mot_times))
        mot_times, mot_values = mot_times[:frames], mot_values[:frames]
        trc_rows = [int(np.argmin(np.abs(trc_times - t))) for t in mot_times]
        model = osim.Model(str(prefix) + ".osim")
        state = model.initSystem()
        truth = opensim_peer.read_table(truth_path) if truth_path else None

        s2kf_seconds = float(np.median(s2kf_times))
        s2kf_rms = opensim_peer.marker_rms_mm(model, state, labels, mot_values, names, recorded[trc_rows])
        result = {"recording": name, "frames": frames, "markers": len(names),
                  "s2kf": (s2kf_seconds, np.nanmean(s2kf_rms),
                           joint_rms_deg(labels, mot_times, mot_values, *truth) if truth else None)}

        ik_runs = [opensim_peer.run_inverse_kinematics(osim, str(prefix) + ".osim", str(prefix) + ".trc",
                                                       out / (name + "_ik"), mot_times[0], mot_times[-1])
                   for _ in range(args.repeat)]
        ik_labels, ik_times, ik_values, _ = ik_runs[-1]
        ik_seconds = float(np.median([run[3] for run in ik_runs]))
        ik_values = ik_values[:, [ik_labels.index(label) for label in labels]]  # the .mot's order
        ik_labels = labels
        ik_rows = [int(np.argmin(np.abs(trc_times - t))) for t in ik_times]
        ik_rms = opensim_peer.marker_rms_mm(model, state, ik_labels, ik_values, names, recorded[ik_rows])
        result["opensim_ik"] = (ik_seconds / len(ik_times), np.nanmean(ik_rms),
                                joint_rms_deg(ik_labels, ik_times, ik_values, *truth) if truth else None)
        coordinate_rms = np.sqrt(np.mean((ik_values - mot_values[: len(ik_times)]) ** 2, axis=0))
        result["ik_vs_s2kf_deg"] = float(np.degrees(np.median(coordinate_rms[6:])))

        if biorbd is not None:
            dofs = opensim_peer.osim_to_biomod(str(prefix) + ".osim", out / (name + ".bioMod"))
            first = trc_rows[0]
            kf_runs = [biorbd_kalman(biorbd, out / (name + ".bioMod"), dofs, names,
                                     recorded[first:first + frames], summary["rate"]) for _ in range(args.repeat)]
            values, kf_rms, _ = kf_runs[-1]
            kf_seconds = float(np.median([run[2] for run in kf_runs]))
            kf_values = np.array([[row[dofs.index(label)] for label in labels] for row in values])
            result["biorbd_kalman"] = (kf_seconds / frames, np.nanmean(kf_rms),
                                       joint_rms_deg(labels, trc_times[first:first + frames], kf_values, *truth)
                                       if truth else None)
        rows.append(result)
        print(json.dumps(result), flush=True)

    print("\n| recording | frames | markers | method | ms per frame | marker RMS (mm) | joint RMS vs truth, "
          "40 joints (deg) | arms and legs (deg) |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        for method in ("s2kf", "opensim_ik", "biorbd_kalman"):
            if method not in r:
                continue
            seconds, marker_rms, joint_rms = r[method]
            joint = " | " if joint_rms is None else f"{joint_rms[0]:.2f} | {joint_rms[1]:.2f}"
            print(f"| {r['recording']} | {r['frames']} | {r['markers']} | {method} | {1000 * seconds:.2f} | "
                  f"{marker_rms:.2f} | {joint} |")
    print("\nMedian over the 40 joints of the RMS difference OpenSim IK - s2kf (deg): " +
          ", ".join(f"{r['recording']} {r['ik_vs_s2kf_deg']:.2f}" for r in rows))


if __name__ == "__main__":
    main()
