#!/usr/bin/env bash
# Installs what is missing, builds s2kf and runs the whole test suite.
#   scripts/test.sh              release build in build/
#   scripts/test.sh --sanitize   AddressSanitizer + UndefinedBehaviorSanitizer build with Clang in build-sanitize/
set -euo pipefail
cd "$(dirname "$0")/.."
build=build
# A clean build: every test program, the program and the Python module compile their files in
# unity batches of 16, which share the parsing of Eigen, GoogleTest and the library's headers and
# the template instantiations those headers bring (docs/architecture.md, "Compile time"). A build
# for editing one file at a time is quicker without: configure it yourself, as in the README.
unity=(-DCMAKE_UNITY_BUILD=ON -DCMAKE_UNITY_BUILD_BATCH_SIZE=16)
flags=(-DCMAKE_BUILD_TYPE=Release -DS2KF_WERROR=ON "${unity[@]}")
# A compiler cache: a second run after an edit recompiles only what changed, and the pip wheel test
# (tests/tools/pip_install.sh, built with this build's compiler and flags) finds every object
# compiled already instead of compiling them again (4 minutes of CPU).
launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
# Paths below the source folder enter the cache's keys relative to the compiling folder: the wheel,
# built in a folder beside build/, then finds the module's and the application layer's unity
# batches too (their files are the build folder's own, so their absolute paths differ).
export CCACHE_BASEDIR=${CCACHE_BASEDIR:-$PWD}
# Depend mode: on a miss ccache hashes the compiler's own dependency file (-MD) instead of running
# the preprocessor once more (0.6 s of a 7-s test batch; a fresh clone's build 25 s of CPU); a
# hit is found the same way (direct mode), the wheel's objects too.
export CCACHE_DEPEND=${CCACHE_DEPEND:-1}
skip=()
# The C3D mutation test (C3dFuzz) runs for a bounded time: 5 s here, 10 s under the sanitizers,
# where a mutation that reads out of bounds is caught (CI then runs libFuzzer on the reader for
# longer); S2KF_FUZZ_SECONDS sets both.
fuzz_seconds=${S2KF_FUZZ_SECONDS:-5}
if [ "${1:-}" = "--sanitize" ]; then
  fuzz_seconds=${S2KF_FUZZ_SECONDS:-10}
  # The consumer test builds an outside project against the installed package: nothing in it
  # runs under the sanitizers, and the release pass has already run it. The Slurm job array
  # (tests/tools) tests the batch recipe, which the release pass has run. cli_same_numbers and the
  # example track_c3d track whole recordings for their numbers (a minute under the sanitizers),
  # which the release pass checks; the shorter tests run the same code here.
  skip=(-E 'consumer_find_package|slurm_job_array|cli_same_numbers|example_track_c3d')
  build=build-sanitize
  # Clang (Debian's clang 14 and its sanitizer runtime), while the release pass uses GCC: CI builds
  # with both compilers, and Clang compiles the instrumented code faster and in less memory
  # (src/core_filter.cpp at -O1 with both sanitizers: 56 s of CPU and 1.0 GB, GCC 79 s and 2.1 GB).
  scripts/install-deps.sh clang libclang-rt-14-dev
  # A build folder configured for another compiler is made anew.
  if [ -f "$build/CMakeCache.txt" ] && ! grep -q '^CMAKE_CXX_COMPILER:[A-Z]*=.*clang++' "$build/CMakeCache.txt"; then
    rm -rf "$build"
  fi
  # -O1 for the library, whose code the suite runs for minutes; the tests', the program's and the
  # application layer's own code at -O0 (cmake/s2kf_project_options.cmake), where the instrumentation
  # is cheap to compile (this pass: 966 -> 386 s on 2 cores of an AMD EPYC Zen 3, with UBSan's
  # memory-access checks left to ASan).
  # Portable (no -march=native): the memory checks concern this code, not the instruction set (the
  # run-time dispatch still runs the AVX2 or AVX-512 kernels the processor has).
  flags=(-DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_FLAGS_RELEASE=-O1 -DS2KF_SANITIZE=ON -DS2KF_NATIVE=OFF -DS2KF_WERROR=ON
         -DS2KF_BUILD_BENCHMARKS=OFF "${unity[@]}")
fi
# Beyond the build packages, the tests use: pybind11 and numpy/pytest (the Python module), xmllint
# (the OpenSim model's well-formedness), blender (the BVH import test), chromium (the viewer tests),
# liblo-tools (oscdump, the OSC receiver of the s2kf live test),
# python3-venv for the test environment of PyPI packages (OpenSim, biorbd, ezc3d: tests/tools,
# python/tests), and slurm-wlm and munge (the Slurm job array of docs/batch.md, on a one-node cluster
# the test starts).
scripts/install-deps.sh ccache pybind11-dev python3-dev python3-numpy python3-pytest libxml2-utils blender chromium \
  liblo-tools python3-venv slurm-wlm munge
# Absolute but not resolved: the venv's python is a symlink to the system's, and only the venv's
# own path makes Python use the venv's packages.
test_python=$(scripts/python-env.sh)
case $test_python in /*) ;; *) test_python=$PWD/$test_python ;; esac
# The module is built with the environment's pybind11 (PyPI, 2.12 or newer): its tests run with the
# environment's NumPy 2 (which the PyPI peers bring), which Debian's pybind11 2.10 misreads.
flags+=("-Dpybind11_DIR=$("$test_python" -m pybind11 --cmakedir)")
jobs=$(nproc 2>/dev/null || echo 2)
# Ninja lets every target's files compile while the libraries they link are still being built
# (Make waits for them, and one core idles during the compiled library's two minutes). A build
# directory made earlier keeps the generator it was made with.
generator=()
[ -f "$build/CMakeCache.txt" ] || generator=(-G Ninja)
cmake -S . -B "$build" "${generator[@]}" "${flags[@]}" "${launcher[@]}" -DS2KF_TEST_PYTHON="$test_python" >/dev/null
cmake --build "$build" -j "$jobs"
cd "$build"
# Two tests per core: a fifth of the suite's time is tests waiting on the clock, not computing (the
# live tests stream at the recording's rate, the viewer's wait on a browser, the Slurm test on its
# daemons), and others compute meanwhile (the suite 132 -> 109 s on 2 cores).
S2KF_FUZZ_SECONDS=$fuzz_seconds ctest --output-on-failure -j "$((jobs * 2))" "${skip[@]}"
