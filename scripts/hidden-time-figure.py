#!/usr/bin/python3
"""Error against the time a segment has been hidden, over the occluded cases of an accuracy table:
reads the JSON that `scripts/accuracy-table.py --raw FILE` writes (each case's
`error_by_time_hidden` from `s2kf evaluate`'s summary.json), pools the bins of all cases (frames
weighted), and writes a data file for docs/figures/tracking_hidden_time.gp plus a Markdown table.

    scripts/hidden-time-figure.py RAW.json DATA.dat
"""
import json
import math
import sys

if len(sys.argv) != 3:
    sys.exit(__doc__)
with open(sys.argv[1]) as f:
    cases = [c for c in json.load(f) if c.get("occlusion") and c.get("error_by_time_hidden")]
if not cases:
    sys.exit(sys.argv[1] + " holds no occluded case with error_by_time_hidden")

# Segment groups drawn beside all segments: the frames' names as s2kf evaluate gives them.
GROUPS = {"forearms": ("LEz", "REz"), "hands": ("LWy", "RWy"), "feet": ("LAy", "RAy"),
          "shanks": ("LKx", "RKx"), "thighs": ("LHy", "RHy"), "trunk and pelvis": ("root", "BTy")}


def pool(series):
    """series: list of bin lists (same edges); returns [(from, to, frames, rms)]."""
    out = []
    for b in range(len(series[0])):
        frames = sum(s[b]["frames"] for s in series)
        sq = sum(s[b]["frames"] * s[b]["rms_deg"] ** 2 for s in series if s[b]["frames"])
        out.append((series[0][b]["hidden_from_s"], series[0][b]["hidden_to_s"], frames,
                    math.sqrt(sq / frames) if frames else float("nan")))
    return out


columns = {}
for method in ("s2kf", "s2kf_smoothed"):
    columns[method + " all"] = pool([c["error_by_time_hidden"][method]["all_segments"] for c in cases])
    for group, names in GROUPS.items():
        series = [c["error_by_time_hidden"][method]["segments"][n]["bins"] for c in cases for n in names
                  if n in c["error_by_time_hidden"][method]["segments"]]
        columns[method + " " + group] = pool(series)

names = list(columns)
first = columns[names[0]]
with open(sys.argv[2], "w") as f:
    f.write("# bin from_s to_s " + " ".join(n.replace(" ", "_") for n in names) + " (RMS deg; frames in the table)\n")
    for b, (lo, hi, _, _) in enumerate(first):
        f.write(f"{b} {lo} {hi if hi is not None else 'inf'} " +
                " ".join(f"{columns[n][b][3]:.3f}" for n in names) + "\n")

label = lambda lo, hi: "visible" if hi == 0 else (f"{lo:g}-{hi:g} s" if hi is not None else f"> {lo:g} s")
print("| hidden for | " + " | ".join(names) + " |")
print("|---|" + "---|" * len(names))
for b, (lo, hi, _, _) in enumerate(first):
    print(f"| {label(lo, hi)} | " + " | ".join(f"{columns[n][b][3]:.1f} ({columns[n][b][2]})" for n in names) + " |")
print(f"\n{len(cases)} occluded cases")
