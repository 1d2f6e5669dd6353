#!/usr/bin/python3
"""The parts of a tracked recording against its calibration: the worst consecutive 2-s and 5-s
windows of the per-frame mean marker distance, against the distance over the calibration's
stretches. Reads what `s2kf track REC --out PREFIX` writes (PREFIX_markers.csv and PREFIX.json).
    scripts/marker-distance-windows.py PREFIX [PREFIX ...]
The first second (the tracker's convergence) is left out; windows start at whole multiples of
their length after it, and a window needs at least half its frames tracked.
"""
import csv
import json
import math
import sys


def windows(times, distances, start, length):
    """(mean, first second) of each consecutive window of `length` seconds from `start`."""
    result = []
    t = start
    end = times[-1] if times else start
    while t + length <= end + 1e-9:
        values = [d for s, d in zip(times, distances) if t <= s < t + length and not math.isnan(d)]
        expected = sum(1 for s in times if t <= s < t + length)
        if values and 2 * len(values) >= expected:
            result.append((sum(values) / len(values), t))
        t += length
    return result


def load(prefix):
    """(summary, times, distances) of what `s2kf track --out PREFIX` wrote; SystemExit with a
    sentence naming the file when it is missing or not what s2kf writes."""
    try:
        with open(prefix + ".json") as f:
            summary = json.load(f)
        summary["mean_marker_distance_all_frames_mm"]
        times, distances = [], []
        with open(prefix + "_markers.csv") as f:
            for row in csv.DictReader(f):
                times.append(float(row["time"]))
                value = row["mean_marker_distance_mm"]
                distances.append(float(value) if value not in ("", "nan", "NaN") else math.nan)
    except OSError as e:
        sys.exit(f"{e.filename}: cannot be read ({e.strerror}); give the PREFIX of s2kf track --out PREFIX")
    except (ValueError, KeyError, TypeError) as e:
        sys.exit(f"{prefix}: not the summary and _markers.csv that s2kf track writes ({e})")
    return summary, times, distances


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    rows = []
    for prefix in sys.argv[1:]:
        summary, times, distances = load(prefix)
        calibration = summary.get("calibration") or {}
        stretches = calibration.get("mean_marker_distance_after_mm", math.nan)
        cells = [prefix.split("/")[-1], f"{stretches:.1f}" if stretches > 0 else "-",
                 f"{summary['mean_marker_distance_all_frames_mm']:.1f}"]
        for length in (2.0, 5.0):
            found = windows(times, distances, 1.0, length)
            if not found:
                cells += ["-", "-"]
                continue
            worst, at = max(found)
            ratio = f"{worst / stretches:.2f}" if stretches > 0 else "- (not calibrated)"
            cells += [f"{worst:.1f} ({at:g})" if length == 2.0 else f"{worst:.1f}", ratio]
        rows.append("| " + " | ".join(cells) + " |")
    print("| recording | stretches (mm) | whole recording (mm) | worst 2-s window (mm, from s) | ratio | "
          "worst 5-s window (mm) | ratio |")
    print("|---|---|---|---|---|---|---|")
    print("\n".join(rows))


if __name__ == "__main__":
    main()
