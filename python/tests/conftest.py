"""Shared fixtures of the s2kf Python tests: where the data and the command-line program are.

ctest sets PYTHONPATH to the built module and S2KF_CLI, S2KF_DATA_DIR, S2KF_C3D_DATA_DIR to the
program and data of the same build (python/CMakeLists.txt); run by hand, the defaults below assume
the source tree and a build in build/.
"""
import os
import pathlib
import subprocess

import pytest

SOURCE_DIR = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def data_dir():
    return pathlib.Path(os.environ.get("S2KF_DATA_DIR", SOURCE_DIR / "data"))


@pytest.fixture(scope="session")
def c3d_dir():
    return pathlib.Path(os.environ.get("S2KF_C3D_DATA_DIR", SOURCE_DIR / "tests" / "data" / "c3d"))


@pytest.fixture(scope="session")
def cli():
    """Runs the s2kf command-line program; skips the test when it was not built."""
    path = os.environ.get("S2KF_CLI", str(SOURCE_DIR / "build" / "s2kf"))
    if not os.path.exists(path):
        pytest.skip("the s2kf program is not built (S2KF_CLI)")

    def run(*arguments):
        done = subprocess.run([path, *map(str, arguments)], capture_output=True, text=True)
        assert done.returncode == 0, done.stderr
        return done.stdout

    run.path = path  # for tests that read the program's own output (--help)
    return run
