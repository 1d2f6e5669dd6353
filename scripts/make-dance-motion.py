#!/usr/bin/python3
"""Writes data/motions/dance.json: a dance-like motion whose twists move.

The other bundled motions move flexion and ab/adduction only; their axial rotations (the trunk's
and neck's z, the humerus's LSz/RSz, the forearm's pronation LEz/REz, the hip's LHz/RHz) stay
at 0, so they cannot tell how well a tracker follows those. Here every one of them moves at a
dancer's pace: the pelvis turns +-20 deg at 0.5 Hz while the hips turn back so the feet keep
pointing forward, the thorax counter-rotates, the humeri rotate +-35 deg at 0.75 Hz, the forearms
pronate and supinate +-60 deg at 0.5 Hz (about 190 deg/s at the peak), the knees bounce at 1 Hz
with the ankles keeping the feet flat, the elbows flex 30-110 deg at 1 Hz. An envelope brings the
pose from and back to the zero pose over the first and last second, and the first and last two
keyframes are equal, so the motion starts and ends at rest.

    scripts/make-dance-motion.py [--out data/motions/dance.json]
"""
import argparse
import json
import math

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--out", default="data/motions/dance.json")
args = parser.parse_args()

DURATION = 8.0  # s, the moving part
STEP = 0.1  # s between keyframes: the cubic interpolation follows these sines closely
THIGH, SHANK = 245.0, 246.0  # mm for a 1000 mm subject (the model's 428.75 and 430.5 at 1750)


def envelope(t):
    """0 -> 1 over the first second, 1 -> 0 over the last, smoothly."""
    ramp = min(t, DURATION - t, 1.0)
    return 0.5 - 0.5 * math.cos(math.pi * max(ramp, 0.0))


def wave(frequency, t, phase=0.0):
    return math.sin(2 * math.pi * frequency * t + phase)


def pose(t):
    e = envelope(t)
    yaw = 20 * e * wave(0.5, t)
    bounce = e * (0.5 + 0.5 * wave(1.0, t, -math.pi / 2))  # 0 .. 1, at the bottom every second
    hip, knee = 18 * bounce, -36 * bounce  # deg
    ankle = -(hip + knee)  # the shank leans forward, the foot stays flat
    drop = THIGH * (1 - math.cos(math.radians(hip))) + SHANK * (1 - math.cos(math.radians(hip + knee)))
    joints = {
        # trunk and head: the thorax counter-rotates against the pelvis, the head keeps looking ahead
        "BPx": -4 * bounce, "BTz": -0.6 * yaw, "BLNz": -0.2 * yaw, "BUNz": -0.2 * yaw,
        # legs: the hips turn back against the pelvis, so the feet keep pointing forward
        "LHx": hip, "RHx": hip, "LKx": knee, "RKx": knee, "LAx": ankle, "RAx": ankle,
        "LHz": -yaw, "RHz": -yaw, "LHy": 4 * e, "RHy": -4 * e,
        # arms
        "LSx": e * (50 + 35 * wave(0.5, t)), "RSx": e * (50 + 35 * wave(0.5, t, math.pi)),
        "LSy": e * (35 + 20 * wave(0.5, t, 1.5)), "RSy": -e * (35 + 20 * wave(0.5, t, 1.5 + math.pi)),
        "LSz": 35 * e * wave(0.75, t), "RSz": -35 * e * wave(0.75, t, 0.5),
        "LEx": e * (70 + 40 * wave(1.0, t)), "REx": e * (70 + 40 * wave(1.0, t, math.pi)),
        "LEz": 60 * e * wave(0.5, t, 0.7), "REz": 60 * e * wave(0.5, t, 2.0),
        "LWx": e * (5 + 10 * wave(1.0, t, 0.3)), "RWx": e * (5 + 10 * wave(1.0, t, 1.3)),
        "LWy": 25 * e * wave(0.5, t), "RWy": -25 * e * wave(0.5, t, 1.0),
    }
    return {"root_position": [round(60 * e * wave(0.5, t), 2) + 0.0, 0.0, round(530 - drop, 2)],
            "root_rpy": [0.0, round(3 * e * wave(0.5, t), 3) + 0.0, round(yaw, 3) + 0.0],
            "joints": {name: round(value, 3) + 0.0 for name, value in joints.items()}}


keyframes = []
count = int(round(DURATION / STEP))
for k in range(count + 1):
    t = k * STEP
    keyframes.append({"time": round(t + 0.2, 3), **pose(t)})
rest_start = {"time": 0.0, **pose(0.0)}
rest_end = {"time": round(DURATION + 0.4, 3), **pose(DURATION)}
motion = {
    "name": "dance",
    "description": "8 s of a dance-like groove whose twists move: the pelvis turns +-20 deg with the hips "
                   "turning back, the thorax counter-rotates, the humeri rotate +-35 deg, the forearms "
                   "pronate and supinate +-60 deg, the knees bounce at 1 Hz, the arms swing and bend.",
    "units": "deg",
    "keyframes": [rest_start] + keyframes + [rest_end],
}
with open(args.out, "w") as f:
    f.write("{\n")
    f.write(f'  "name": {json.dumps(motion["name"])},\n')
    f.write(f'  "description": {json.dumps(motion["description"])},\n')
    f.write('  "units": "deg",\n  "keyframes": [\n')
    f.write(",\n".join("    " + json.dumps(k) for k in motion["keyframes"]))
    f.write("\n  ]\n}\n")
