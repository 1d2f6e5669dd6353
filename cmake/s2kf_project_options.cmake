# Compiler options of this project's own targets (tests, program, benchmarks, module), never of a
# consumer's: warnings (errors only with S2KF_WERROR, which scripts/test.sh and CI pass),
# sanitizers, and -march=native. Included by the top CMakeLists.txt after it has made the
# interface target s2kf_project_options.
target_compile_options(s2kf_project_options INTERFACE -Wall -Wextra -Wpedantic)
if(S2KF_WERROR)
  target_compile_options(s2kf_project_options INTERFACE -Werror)
endif()
# UBSan without the checks of a memory access (alignment, null, object-size, pointer-overflow): ASan
# reports the invalid access itself, and these checks on every load of Eigen's inlined code are half
# of an instrumented -O1 compile (src/body.cpp with Clang 14: 47 s of CPU with them, 21 s without).
# The parsers of outside bytes (the C3D reader, the QTM protocol) keep every check: their libFuzzer
# targets (tests/fuzz) are built with all of UBSan.
if(S2KF_SANITIZE)
  target_compile_options(s2kf_project_options INTERFACE
    -fsanitize=address,undefined -fno-sanitize=alignment,null,object-size,pointer-overflow
    -fno-sanitize-recover=all -fno-omit-frame-pointer)
  target_link_options(s2kf_project_options INTERFACE -fsanitize=address,undefined)
endif()
# Without -march=native the hot kernels still run with the processor's best instruction set: they
# are compiled for SSE2, AVX2 and AVX-512 and chosen at run time (core/instruction_set.hpp).
if(S2KF_NATIVE)
  target_compile_options(s2kf_project_options INTERFACE -march=native)
endif()
# GCC 12 reports -Wmaybe-uninitialized false positives inside libstdc++ (<regex>, std::function)
# and its own AVX-512 headers when sanitizers or -march=native change inlining (with both, also
# -Wuninitialized: the `__m512d __Y = __Y;` idiom of avx512fintrin.h under Eigen's ptranspose);
# keep them visible as warnings there, but not errors.
if((S2KF_SANITIZE OR S2KF_NATIVE) AND CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
  target_compile_options(s2kf_project_options INTERFACE -Wno-error=maybe-uninitialized
                                                         -Wno-error=uninitialized)
endif()
# With AVX-512, GCC 12 floods every file that uses Eigen with false positives from its own
# intrinsics (-Wmaybe-uninitialized on the `__m512d __Y = __Y;` idiom of avx512fintrin.h, about
# 4000 lines a build; -Wuninitialized on the same idiom in the tests, compiled at -O1: GCC bug
# 105593) and misreads Eigen's 512-bit loads of small fixed-size vectors as out of bounds
# (-Warray-bounds). Native builds leave these out; the sanitizer pass of scripts/test.sh builds
# portably, where they are still checked.
if(S2KF_NATIVE AND CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
  target_compile_options(s2kf_project_options INTERFACE -Wno-maybe-uninitialized -Wno-uninitialized
                                                         -Wno-array-bounds)
endif()

# s2kf_front_end_optimisation(TARGET): TARGET's own code (argument parsing, file formats, reports,
# bindings; the numerics it calls are s2kf_compiled's, at the build type's -O3) at -Og in a release
# build: it runs in no hot loop, and compiles a fifth faster than at -O1 (the program's first batch
# 23.0 -> 18.2 s of CPU), which compiles a fifth faster than -O2; s2kf track's outputs and times
# stay the same. Flags the user set for the
# build type (no -O3 in them) are kept. An executable or module links the libraries' objects before
# its own (s2kf_link_libraries_first), so an inline function both compile (Eigen's kernels) is the
# library's -O3 copy: the program's outputs are the same to the bit.
# Under the sanitizers it is built at -O0, as the tests' own code: the instrumentation compiles in a
# third of the time (the numerics the tests run are the library's, still at -O1).
function(s2kf_front_end_optimisation target)
  if(S2KF_SANITIZE)
    target_compile_options(${target} PRIVATE -O0)
  elseif(CMAKE_BUILD_TYPE STREQUAL "Release" AND CMAKE_CXX_FLAGS_RELEASE MATCHES "-O3")
    target_compile_options(${target} PRIVATE -Og)
  endif()
endfunction()

# s2kf_cold_unit_optimisation(SOURCE...): the compiled library's units no hot loop runs in at -Og
# in a release build, as the front ends' code.
function(s2kf_cold_unit_optimisation)
  if(CMAKE_BUILD_TYPE STREQUAL "Release" AND CMAKE_CXX_FLAGS_RELEASE MATCHES "-O3")
    set_source_files_properties(${ARGN} DIRECTORY ${PROJECT_SOURCE_DIR} PROPERTIES COMPILE_OPTIONS -Og)
  endif()
endfunction()

# s2kf_link_libraries_first(TARGET LIBRARY...): the linker keeps the first copy of an inline function
# it meets, and a target's own objects come before its libraries: the LIBRARY archives are linked
# whole ahead of them instead.
function(s2kf_link_libraries_first target)
  set(archives)
  foreach(library ${ARGN})
    list(APPEND archives "$<TARGET_FILE:${library}>")
  endforeach()
  target_link_options(${target} PRIVATE "LINKER:--whole-archive" ${archives} "LINKER:--no-whole-archive")
endfunction()
