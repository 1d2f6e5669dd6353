#!/usr/bin/env bash
# Creates or updates the virtual environment of the Python tests (PyPI packages of
# python/requirements-test.txt) and prints its interpreter's path.
set -euo pipefail
cd "$(dirname "$0")/.."
# One environment per user and Python version, shared by every clone and build folder (540 MB,
# 25-38 s of a clean clone's scripts/test.sh to install on a 2-core Zen 3); S2KF_VENV names
# another. Its absolute path lies outside every clone, so the module's build and the pip test's
# wheel name its pybind11 alike and the compiler cache gives the wheel the module's objects
# (scripts/test.sh, CCACHE_BASEDIR).
version=$(/usr/bin/python3 -c 'import sys; print("%d.%d" % sys.version_info[:2])')
venv=${S2KF_VENV:-${XDG_CACHE_HOME:-${HOME:-$PWD}/.cache}/s2kf/venv-python$version}
mkdir -p "$(dirname "$venv")"
# Two clones' test runs at once take turns: pip must not install into one environment twice at once.
exec 9>"$venv.lock"
flock 9
[ -x "$venv/bin/python" ] || /usr/bin/python3 -m venv --system-site-packages "$venv" >&2
"$venv/bin/python" -m pip install -q --disable-pip-version-check -r python/requirements-test.txt >&2
echo "$venv/bin/python"
