#!/usr/bin/env bash
# Regenerates the bundled synthetic recordings in data/ (C3D + _truth.csv + _clean.csv), bit for bit.
#   scripts/make-data.sh            build s2kf in build/ if needed, then rewrite the files in data/
#   scripts/make-data.sh --check    write them to a scratch directory and compare with data/ (cmp)
#   S2KF=/path/to/s2kf scripts/make-data.sh   use that program instead of building one
set -euo pipefail
cd "$(dirname "$0")/.."
s2kf=${S2KF:-}
if [ -z "$s2kf" ]; then
  cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
  cmake --build build -j "$(nproc 2>/dev/null || echo 2)" --target s2kf_cli >/dev/null
  s2kf=build/s2kf
fi
out=data
if [ "${1:-}" = "--check" ]; then
  out=$(mktemp -d)
  trap 'rm -rf "$out"' EXIT
fi

# The paper's recording: a handstand, 675 frames at 100 Hz, a 1.75 m subject with the default
# (careful Vicon session) placement, soft-tissue and noise; then the same take with the paper's
# occlusion (0.5 % per frame, Poisson(100) frames). Same seed: same subject, same noise.
"$s2kf" simulate --motion handstand --seed 1 --height 1750 --out "$out/handstand.c3d"
"$s2kf" simulate --motion handstand --seed 1 --height 1750 --occlusion 0.005,100 --out "$out/handstand_occluded.c3d"
# Two more: walking, and a cartwheel (root pitch through 360 deg) by a shorter subject.
"$s2kf" simulate --motion walk --seed 2 --height 1800 --out "$out/walk.c3d"
"$s2kf" simulate --motion cartwheel --seed 3 --height 1650 --out "$out/cartwheel.c3d"

if [ "$out" != data ]; then
  for file in handstand handstand_occluded walk cartwheel; do
    for suffix in .c3d _truth.csv _clean.csv; do
      cmp "$out/$file$suffix" "data/$file$suffix"
    done
  done
  echo "data/ is reproduced bit for bit"
fi
