# Precompiled headers for builds without unity batches (the editing build): each file of the
# program, the tests and the Python module otherwise parses Eigen, the standard library and its
# framework (GoogleTest, CLI11, nlohmann JSON, pybind11) again, which is about half of its compile
# time. A unity build parses them once per batch already, where a precompiled header would only add
# its own compile, so it is used only without CMAKE_UNITY_BUILD. Only headers that never change with
# this project's code go in: an edit of a library header recompiles no precompiled header.
option(S2KF_PRECOMPILE_HEADERS "Precompile Eigen, the standard library and the test/CLI frameworks (builds without unity batches)" ON)

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
# compile options: the test programs).
function(s2kf_reuse_precompiled_headers target from)
  if(S2KF_PRECOMPILE_HEADERS AND NOT CMAKE_UNITY_BUILD)
    target_precompile_headers(${target} REUSE_FROM ${from})
  endif()
endfunction()
