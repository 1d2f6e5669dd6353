"""What the OpenSim tests and scripts/peer-benchmark.py share: running s2kf, reading its OpenSim files
with OpenSim itself (opensim from PyPI), OpenSim's marker positions at the .mot's coordinates, its
Inverse Kinematics tool, and the .bioMod of the same model for biorbd.

Positions are in the lab frame (C3D: x right, y forward, z up) in mm unless a name says otherwise;
OpenSim's ground is Y-up: ground = GROUND_FROM_LAB @ lab (io/opensim_model.hpp).
"""
import math
import os
import pathlib
import platform
import subprocess
import sys
import time
import xml.etree.ElementTree as ET

import numpy as np

SOURCE_DIR = pathlib.Path(__file__).resolve().parents[2]
GROUND_FROM_LAB = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])


def wheel_exists_here(package):
    """Whether PyPI has a wheel of `package` for this machine (checked by hand: opensim 4.6 and biorbd
    1.12 for CPython 3.11 on x86_64 Linux, the Debian 12 machines CI runs on)."""
    return (sys.platform == "linux" and platform.machine() == "x86_64"
            and sys.version_info[:2] == (3, 11))


def import_peer(package):
    """Imports `package`; where PyPI has it for this machine its absence is a failure (the test
    environment, scripts/python-env.sh, installs it), elsewhere the caller skips."""
    try:
        module = __import__(package)
        if package == "opensim":
            module.Logger.setLevelString("error")  # not a line per loaded model and IK frame
            module.Logger.removeFileSink()  # no opensim.log in the working directory
        return module
    except ImportError as error:
        if wheel_exists_here(package):
            raise AssertionError(
                f"{package} is not installed in {sys.executable} ({error}); PyPI has it for this machine: "
                "run scripts/python-env.sh and use the interpreter it prints") from error
        return None


def cli_path():
    return os.environ.get("S2KF_CLI", str(SOURCE_DIR / "build" / "s2kf"))


def run_cli(*arguments):
    done = subprocess.run([cli_path(), *map(str, arguments)], capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"s2kf {' '.join(map(str, arguments))} failed: {done.stderr.strip()}")
    return done.stdout


def read_table(path, delimiter=","):
    """A CSV with a header line: (column names, float array)."""
    with open(path) as f:
        header = f.readline().strip().split(delimiter)
    values = np.genfromtxt(path, delimiter=delimiter, skip_header=1, dtype=float, ndmin=2)
    return header, values


def s2kf_model_markers(subject, pose_csv, row):
    """s2kf's model markers (lab, mm) for data row `row` of a pose CSV, from `s2kf model`."""
    text = run_cli("model", "--subject", subject, "--pose", pose_csv, "--row", row)
    markers = {}
    for line in text.splitlines()[1:]:
        name, x, y, z = line.split(",")
        markers[name] = np.array([float(x), float(y), float(z)])
    return markers


def read_mot(osim, path):
    """The .mot as OpenSim reads it: (column labels, times, values in OpenSim units: m and rad)."""
    table = osim.TimeSeriesTable(str(path))
    labels = list(table.getColumnLabels())
    times = np.array(table.getIndependentColumn())
    values = table.getMatrix().to_numpy()
    if table.getTableMetaDataAsString("inDegrees").strip().lower() == "yes":
        model_free = {"root_x", "root_y", "root_z"}
        for c, label in enumerate(labels):
            if label not in model_free:
                values[:, c] = np.radians(values[:, c])
    return labels, times, values


def set_coordinates(model, state, labels, values):
    """Sets every coordinate named in `labels` (OpenSim units), then realises positions."""
    coordinates = model.getCoordinateSet()
    for label, value in zip(labels, values):
        coordinates.get(label).setValue(state, float(value), False)
    model.realizePosition(state)


def opensim_markers(model, state):
    """OpenSim's marker positions in the current state: name -> lab mm."""
    markers = {}
    marker_set = model.getMarkerSet()
    for m in range(marker_set.getSize()):
        marker = marker_set.get(m)
        ground = marker.getLocationInGround(state).to_numpy()
        markers[marker.getName()] = 1000.0 * GROUND_FROM_LAB.T @ ground
    return markers


def read_trc(path):
    """A .trc as written by s2kf: (marker names, times, positions (frames, markers, 3) lab mm, NaN
    where missing)."""
    with open(path) as f:
        lines = f.read().split("\n")
    names = [n for n in lines[3].split("\t")[2:] if n]
    rows = [line.split("\t") for line in lines[6:] if line.strip()]
    times = np.array([float(r[1]) for r in rows])
    ground = np.full((len(rows), len(names), 3), np.nan)
    for f, r in enumerate(rows):
        cells = (r + [""] * (2 + 3 * len(names)))[2:2 + 3 * len(names)]
        ground[f] = np.array([float(c) if c.strip() else np.nan for c in cells]).reshape(len(names), 3)
    return names, times, ground @ GROUND_FROM_LAB  # row vectors: lab = ground @ G (G^T g)


def marker_rms_mm(model, state, labels, values, names, recorded):
    """Per frame: the RMS distance (mm) of the model's markers at `values` from the `recorded` ones
    (frames, markers, 3), over the markers seen in that frame (OpenSim IK's marker_error_RMS)."""
    rms = np.full(len(values), np.nan)
    for f, row in enumerate(values):
        set_coordinates(model, state, labels, row)
        at = opensim_markers(model, state)
        d2 = [np.sum((at[n] - recorded[f, k]) ** 2) for k, n in enumerate(names)
              if np.all(np.isfinite(recorded[f, k]))]
        if d2:
            rms[f] = math.sqrt(np.mean(d2))
    return rms


def run_inverse_kinematics(osim, model_path, trc_path, out_dir, start_time, end_time):
    """OpenSim's InverseKinematicsTool on the .trc with the .osim (every marker weight 1, accuracy
    1e-5): (coordinate labels, times, values in m and rad, seconds of tool.run())."""
    out_dir = pathlib.Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    model = osim.Model(str(model_path))
    tool = osim.InverseKinematicsTool()
    tool.setModel(model)
    tool.setName(pathlib.Path(model_path).stem)
    tool.setMarkerDataFileName(str(trc_path))
    tool.setStartTime(start_time)
    tool.setEndTime(end_time)
    tool.set_accuracy(1e-5)
    tool.set_report_errors(True)
    tool.setResultsDir(str(out_dir))
    motion = out_dir / (pathlib.Path(model_path).stem + "_ik.mot")
    tool.setOutputMotionFileName(str(motion))
    start = time.perf_counter()
    if not tool.run():
        raise RuntimeError("OpenSim's InverseKinematicsTool failed on " + str(trc_path))
    seconds = time.perf_counter() - start
    labels, times, values = read_mot(osim, motion)
    return labels, times, values, seconds


# --- biorbd: the same model as a .bioMod -------------------------------------------------------------

def _vector(text):
    return [float(v) for v in text.split()]


def osim_to_biomod(osim_path, biomod_path):
    """Writes the .osim's kinematic tree as a .bioMod in the lab frame (z up, mm -> m): one segment per
    OpenSim body, its translation from the parent, its coordinates as rotations in the .osim's order
    (body-fixed, as OpenSim's CustomJoint composes them) with their ranges, the segment masses and
    inertias, and the markers. The root is `translations xyz`, `rotations zyx` (yaw, pitch, roll).
    Returns the generalised coordinates' names in biorbd's order."""
    model = ET.parse(osim_path).getroot().find("Model")
    names = []
    out = ["version 4", "", "gravity 0 0 -9.80665", ""]
    bodies = {b.get("name"): b for b in model.find("BodySet").find("objects")}
    for joint in model.find("JointSet").find("objects"):
        frames = {f.get("name"): f for f in joint.find("frames")}
        parent_frame = frames[joint.find("socket_parent_frame").text]
        child_frame = frames[joint.find("socket_child_frame").text]
        child = child_frame.find("socket_parent").text.split("/")[-1]
        parent = parent_frame.find("socket_parent").text.split("/")[-1]
        ranges = {c.get("name"): _vector(c.find("range").text)
                  for c in joint.find("coordinates")}
        axes = []
        translations = []
        for axis in joint.find("SpatialTransform"):
            coordinate = (axis.find("coordinates").text or "").strip()
            if not coordinate:
                continue
            letter = "xyz"[int(np.argmax(np.abs(_vector(axis.find("axis").text))))]
            (translations if axis.get("name").startswith("translation") else axes).append((letter, coordinate))
        body = bodies[child]
        segment = [f"segment {child}"]
        if parent != "ground":
            segment.append(f"\tparent {parent}")
            t = _vector(parent_frame.find("translation").text)
            segment.append(f"\tRT 0 0 0 xyz {t[0]:.12g} {t[1]:.12g} {t[2]:.12g}")
        dofs = []
        if translations:
            segment.append("\ttranslations " + "".join(letter for letter, _ in translations))
            dofs += [c for _, c in translations]
        if axes:
            segment.append("\trotations " + "".join(letter for letter, _ in axes))
            dofs += [c for _, c in axes]
        if dofs:
            segment.append("\trangesQ")
            segment += [f"\t\t{ranges[c][0]:.12g} {ranges[c][1]:.12g}" for c in dofs]
        names += dofs
        mass = float(body.find("mass").text)
        segment.append(f"\tmass {max(mass, 1e-6):.12g}")
        segment.append("\tcom " + " ".join(f"{v:.12g}" for v in _vector(body.find("mass_center").text)))
        inertia = _vector(body.find("inertia").text)
        i = [max(v, 1e-9) for v in inertia[:3]]
        segment.append(f"\tinertia {i[0]:.12g} 0 0 0 {i[1]:.12g} 0 0 0 {i[2]:.12g}")
        segment.append("endsegment")
        out += segment + [""]
    # Markers segment by segment, the root's first: biorbd's Kalman filter starts on the first ones.
    segments = [line.split()[1] for line in out if line.startswith("segment ")]
    markers = sorted(model.find("MarkerSet").find("objects"),
                     key=lambda m: segments.index(m.find("socket_parent_frame").text.split("/")[-1]))
    for marker in markers:
        body = marker.find("socket_parent_frame").text.split("/")[-1]
        p = _vector(marker.find("location").text)
        out += [f"marker {marker.get('name')}", f"\tparent {body}",
                f"\tposition {p[0]:.12g} {p[1]:.12g} {p[2]:.12g}", "endmarker", ""]
    # The root rotates yaw, pitch, roll (Rz Ry Rx) after translating along the lab axes, as in the .osim;
    # the .osim's ground offset (lab -> OpenSim's Y-up ground) is left out: biorbd's world is the lab.
    text = "\n".join(out)
    root_rotations = [n for n in names if n in ("root_yaw", "root_pitch", "root_roll")]
    if root_rotations != ["root_yaw", "root_pitch", "root_roll"]:
        raise ValueError("the .osim's root joint is not yaw, pitch, roll")
    pathlib.Path(biomod_path).write_text(text)
    return names
