#!/usr/bin/env bash
# Creates or updates the virtual environment of the Python tests (PyPI packages of
# python/requirements-test.txt) and prints its interpreter's path.
set -euo pipefail
cd "$(dirname "$0")/.."
venv=${S2KF_VENV:-build/venv}
[ -x "$venv/bin/python" ] || /usr/bin/python3 -m venv --system-site-packages "$venv" >&2
"$venv/bin/python" -m pip install -q --disable-pip-version-check -r python/requirements-test.txt >&2
echo "$venv/bin/python"
