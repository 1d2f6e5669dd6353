#!/usr/bin/env bash
# Creates or updates the virtual environment of the Python tests (PyPI packages of
# python/requirements-test.txt) and prints its interpreter's path.
set -euo pipefail
cd "$(dirname "$0")/.."
# Beside the build folders, not in one: the release and the sanitizer builds share it, and its
# pybind11 then has the same path relative to build/ as to the pip test's wheel folder, so the
# compiler cache gives the wheel the module's unity batch (scripts/test.sh, CCACHE_BASEDIR).
venv=${S2KF_VENV:-build-venv}
[ -x "$venv/bin/python" ] || /usr/bin/python3 -m venv --system-site-packages "$venv" >&2
"$venv/bin/python" -m pip install -q --disable-pip-version-check -r python/requirements-test.txt >&2
echo "$venv/bin/python"
