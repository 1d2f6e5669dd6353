#!/usr/bin/env bash
# Installs what is missing, builds the s2kf program and runs the main job on the bundled data:
# tracking the synthetic handstand (675 frames, 50 markers, 100 Hz) into results/handstand.*.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
jobs=$(nproc 2>/dev/null || echo 2)
# Ninja and unity batches of 16, as scripts/test.sh builds (they share build/; a build directory
# made earlier keeps its generator).
generator=()
[ -f build/CMakeCache.txt ] || generator=(-G Ninja)
cmake -S . -B build "${generator[@]}" -DCMAKE_BUILD_TYPE=Release -DCMAKE_UNITY_BUILD=ON \
  -DCMAKE_UNITY_BUILD_BATCH_SIZE=16 >/dev/null
cmake --build build -j "$jobs" --target s2kf_cli
mkdir -p results
./build/s2kf track data/handstand.c3d --out results/handstand "$@"
