#!/usr/bin/env bash
# `pip install .` as a Python user runs it: a fresh virtual environment, the repository given to pip
# (scikit-build-core builds the wheel, pyproject.toml), then, from another folder and without
# S2KF_DATA_DIR, the module imports from the venv, lists and simulates a bundled motion and tracks
# the recording with a bundled marker set. The installed files (the wheel's RECORD) must hold the
# module and every bundled marker set and motion.
#   tests/tools/pip_install.sh SOURCE_DIR WORK_DIR [NAME=VALUE...]
# Each NAME=VALUE is a CMake setting of the wheel's build (ctest passes its own build's compiler,
# launcher and flags); without any, the wheel is built exactly as a user's `pip install .` builds it.
# S2KF_WHEEL_BUILD_DIR, if set, is the folder the wheel is built in (else a temporary one).
set -euo pipefail
source_dir=$(cd "$1" && pwd)
work=$2
shift 2
rm -rf "$work"
mkdir -p "$work/elsewhere"
work=$(cd "$work" && pwd)

# python/pyproject.toml (for `pip install ./python`) must say what the repository's says.
/usr/bin/python3 - "$source_dir" <<'PY'
import sys, tomllib
root = tomllib.load(open(f"{sys.argv[1]}/pyproject.toml", "rb"))
sub = tomllib.load(open(f"{sys.argv[1]}/python/pyproject.toml", "rb"))
assert sub["tool"]["scikit-build"]["cmake"].pop("source-dir") == "..", "python/pyproject.toml: cmake.source-dir must be .."
if root != sub:
    sys.exit("pyproject.toml and python/pyproject.toml differ (beyond cmake.source-dir)")
PY

/usr/bin/python3 -m venv "$work/venv"
# All cores for the wheel's build.
export CMAKE_BUILD_PARALLEL_LEVEL=${CMAKE_BUILD_PARALLEL_LEVEL:-$(nproc 2>/dev/null || echo 2)}
unset S2KF_DATA_DIR PYTHONPATH
config=()
# A build folder given (S2KF_WHEEL_BUILD_DIR) is made anew, so the wheel is always built whole.
if [ -n "${S2KF_WHEEL_BUILD_DIR:-}" ]; then
  rm -rf "$S2KF_WHEEL_BUILD_DIR"
  config+=("--config-settings=build-dir=$S2KF_WHEEL_BUILD_DIR")
fi
for setting in "$@"; do
  # An empty value (no launcher, no extra flags) leaves the project's default.
  [ -n "${setting#*=}" ] && config+=("--config-settings=cmake.define.$setting")
done
# The compiler cache's hits show which objects were the build's own.
stats() {
  command -v ccache >/dev/null &&
    ccache --print-stats 2>/dev/null | awk '$1 ~ /^(direct_cache_hit|preprocessed_cache_hit|cache_miss)$/ { printf "%s %s ", $1, $2 }'
}
before=$(stats || true)
start=$(date +%s)
(cd "$work/elsewhere" && "$work/venv/bin/python" -m pip install --disable-pip-version-check -q "${config[@]}" "$source_dir")
echo "pip install: $(($(date +%s) - start)) s; compiler cache before: ${before:-none}; after: $(stats || true)"

cd "$work/elsewhere"
"$work/venv/bin/python" - "$source_dir" "$work" <<'PY'
import importlib.metadata, pathlib, sys
source, work = (pathlib.Path(p) for p in sys.argv[1:])
import s2kf

where = pathlib.Path(s2kf.__file__).resolve()
assert where.is_relative_to(work / "venv"), f"s2kf imported from {where}, not from the venv"
installed = {str(f) for f in importlib.metadata.files("s2kf")}
assert any(f.startswith("s2kf.") and f.endswith(".so") for f in installed), sorted(installed)
for folder in ("markersets", "motions"):
    for bundled in sorted((source / "data" / folder).glob("*.json")):
        assert f"s2kf_data/{folder}/{bundled.name}" in installed, f"the wheel lacks {folder}/{bundled.name}"
motions = s2kf.motions()
assert "walk" in motions, motions
labels, rate, points = s2kf.simulate("walk", frames=40, seed=3)
# A marker set read from the wheel's s2kf_data/markersets.
result = s2kf.track(points, labels, rate, markerset="plugin_gait", calibrate=False, samples=101)
assert result.summary["marker_set"] == "plugin_gait", result.summary["marker_set"]
assert result.joints.shape == (40, 40)
import numpy
print(f"s2kf {s2kf.__version__} from {where.parent} (numpy {numpy.__version__}): {len(installed)} files "
      f"installed, {len(motions)} motions; tracked 40 frames with plugin_gait")
PY
