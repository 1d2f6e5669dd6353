"""Fixtures of the tests against the real tools (OpenSim, biorbd from PyPI): the recordings, calibrated
and tracked once by the s2kf program, whose OpenSim files the tests open.

ctest runs these with the test environment's interpreter (scripts/python-env.sh, S2KF_TEST_PYTHON)
and sets S2KF_CLI, S2KF_DATA_DIR and S2KF_TEST_TMP_DIR (tests/tools/CMakeLists.txt).
"""
import os
import pathlib
import sys

import pytest

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import opensim_peer  # noqa: E402

# The bundled recordings (a subject's first 300 frames suffice for the calibration and keep this
# quick) and one simulated here; with --mass for one, the default mass for the others.
RECORDINGS = {"handstand": [], "walk": ["--mass", "68.5"], "cartwheel": [], "simulated_squats": []}


@pytest.fixture(scope="session")
def scratch():
    root = pathlib.Path(os.environ.get("S2KF_TEST_TMP_DIR", opensim_peer.SOURCE_DIR / "build" / "tmp_tools"))
    folder = root / "opensim"
    folder.mkdir(parents=True, exist_ok=True)
    return folder


@pytest.fixture(scope="session")
def tracked(scratch):
    """name -> dict(prefix, subject, mass_args): each recording calibrated (`s2kf calibrate`, whose
    SUBJECT.osim is written too) and tracked with that subject (`s2kf track --subject`), so that
    `s2kf model --subject` gives the tracked model's markers."""
    if not os.path.exists(opensim_peer.cli_path()):
        pytest.fail("the s2kf program is not built (S2KF_CLI=" + opensim_peer.cli_path() + ")")
    data = pathlib.Path(os.environ.get("S2KF_DATA_DIR", opensim_peer.SOURCE_DIR / "data"))
    results = {}
    for name, mass_args in RECORDINGS.items():
        if name.startswith("simulated_"):
            recording = scratch / (name + ".c3d")
            opensim_peer.run_cli("simulate", "--motion", name[len("simulated_"):], "--seed", 3,
                                 "--frames", 200, "--out", recording)
        else:
            recording = data / (name + ".c3d")
        subject = scratch / (name + "_subject.json")
        prefix = scratch / name
        opensim_peer.run_cli("calibrate", recording, "--out", subject, "--frames", 300, "--quiet", *mass_args)
        opensim_peer.run_cli("track", recording, "--subject", subject, "--out", prefix, "--quiet",
                             "--formats", "csv,mot,osim,trc", *mass_args)
        results[name] = {"prefix": prefix, "subject": subject, "recording": recording,
                         "mass_kg": float(mass_args[1]) if mass_args else None}
    return results
