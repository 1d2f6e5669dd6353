#!/usr/bin/env python3
"""Joint flexion of `s2kf track` CSV files against the Plug-in Gait angles Nexus stored in the C3D.

Vicon Nexus writes its model's joint angles as points (LHipAngles, LKneeAngles, LAnkleAngles, ...:
x flexion, y ab/adduction, z rotation, degrees). For the hips' flexion and ab/adduction and the
knees' and ankles' flexion it prints, per CSV, the Pearson r of s2kf's angle against Nexus's and
the RMS difference (deg) with each one's mean removed and s2kf's sign turned to r's (the two
models' zeros and directions differ), then the range of each (deg). Needs ezc3d (the venv of
scripts/python-env.sh).

    $(scripts/python-env.sh) scripts/nexus-angles.py REC.c3d RUN.csv [RUN2.csv ...]
"""
import csv
import sys

import ezc3d
import numpy as np

# s2kf's column, Nexus's point, its axis
PAIRS = [("LHx", "LHipAngles", 0), ("RHx", "RHipAngles", 0), ("LHy", "LHipAngles", 1),
         ("RHy", "RHipAngles", 1), ("LKx", "LKneeAngles", 0), ("RKx", "RKneeAngles", 0),
         ("LAx", "LAnkleAngles", 0), ("RAx", "RAnkleAngles", 0)]


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    c3d = ezc3d.c3d(sys.argv[1])
    labels = c3d["parameters"]["POINT"]["LABELS"]["value"]
    points = c3d["data"]["points"]
    missing = [name for _, name, _ in PAIRS if name not in labels]
    if missing:
        sys.exit(f"{sys.argv[1]} holds no Nexus angles {', '.join(sorted(set(missing)))}")
    print("%-28s %s   (r / RMS deg; s2kf range / Nexus range, deg)" %
          ("run", " ".join("%16s" % column for column, _, _ in PAIRS)))
    for run in sys.argv[2:]:
        rows = list(csv.DictReader(open(run)))
        frames = np.array([int(row["frame"]) for row in rows])
        cells = []
        for column, name, axis in PAIRS:
            ours = np.degrees(np.array([float(row[column]) for row in rows]))
            theirs = points[axis, labels.index(name), frames]
            seen = np.isfinite(ours) & np.isfinite(theirs)
            a, b = ours[seen], theirs[seen]
            r = np.corrcoef(a, b)[0, 1]
            sign = -1.0 if r < 0 else 1.0
            rms = np.sqrt(np.mean((sign * (a - a.mean()) - (b - b.mean())) ** 2))
            cells.append("%5.2f/%4.1f %3.0f/%3.0f" % (r, rms, np.ptp(a), np.ptp(b)))
        print("%-28s %s" % (run.split("/")[-1], " ".join("%16s" % cell for cell in cells)))


if __name__ == "__main__":
    main()
