# Precompiled headers for builds without unity batches (the editing build): each file of the
# program and of the Python module otherwise parses Eigen, the standard library, CLI11, nlohmann
# JSON or pybind11 again (a file of the program: 11.1-11.5 s of CPU with them, 13.0 s without, at
# -O3; a test file at -O1 with GoogleTest 2.4 s instead of 3.8, 5.1 instead of 7.2). A unity
# build parses them once per batch already, where a precompiled header would only add its own
# compile, so it is used only without CMAKE_UNITY_BUILD. Only headers that never change with this
# project's code go in: an edit of a library header recompiles no precompiled header.
option(S2KF_PRECOMPILE_HEADERS "Precompile Eigen, the standard library, CLI11, JSON and pybind11 for the program, the module and the tests (builds without unity batches)" ON)

set(s2kf_common_pch_headers <Eigen/Core> <Eigen/Dense> <algorithm> <cmath> <cstdint> <functional> <map> <memory>
                            <optional> <sstream> <string> <vector>)

# s2kf_precompile_headers(TARGET HEADER...): TARGET's own precompiled header of the common headers
# and the ones given.
function(s2kf_precompile_headers target)
  if(S2KF_PRECOMPILE_HEADERS AND NOT CMAKE_UNITY_BUILD)
    target_precompile_headers(${target} PRIVATE ${s2kf_common_pch_headers} ${ARGN})
  endif()
endfunction()

# s2kf_reuse_precompiled_headers(TARGET FROM): TARGET uses FROM's precompiled header (the same
# definitions and options, or GCC refuses it: -Winvalid-pch, an error with S2KF_WERROR).
function(s2kf_reuse_precompiled_headers target from)
  if(S2KF_PRECOMPILE_HEADERS AND NOT CMAKE_UNITY_BUILD)
    target_precompile_headers(${target} REUSE_FROM ${from})
  endif()
endfunction()
