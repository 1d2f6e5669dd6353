# Installs s2kf into a scratch prefix, then configures, builds and runs two outside projects:
# one with find_package(s2kf), one with add_subdirectory(s2kf). Any failing step fails the test.
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})

function(run_step)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "step failed (${rc}): ${ARGN}\n${out}\n${err}")
  endif()
endfunction()

set(prefix ${WORK_DIR}/prefix)
run_step(${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${WORK_DIR}/s2kf-build -G ${CMAKE_GENERATOR}
         -DS2KF_BUILD_TESTS=OFF -DS2KF_BUILD_BENCHMARKS=OFF -DS2KF_BUILD_EXAMPLES=OFF -DS2KF_BUILD_PROGRAM=OFF
         -DS2KF_BUILD_PYTHON=OFF -DS2KF_INSTALL=ON -DCMAKE_INSTALL_PREFIX=${prefix})
run_step(${CMAKE_COMMAND} --build ${WORK_DIR}/s2kf-build --target install)

run_step(${CMAKE_COMMAND} -S ${SOURCE_DIR}/tests/consumer/find_package_project -B ${WORK_DIR}/fp-build
         -G ${CMAKE_GENERATOR} -DCMAKE_PREFIX_PATH=${prefix})
run_step(${CMAKE_COMMAND} --build ${WORK_DIR}/fp-build)
run_step(${WORK_DIR}/fp-build/consumer)

run_step(${CMAKE_COMMAND} -S ${SOURCE_DIR}/tests/consumer/subdirectory_project -B ${WORK_DIR}/sd-build
         -G ${CMAKE_GENERATOR} -DS2KF_SOURCE_DIR=${SOURCE_DIR})
run_step(${CMAKE_COMMAND} --build ${WORK_DIR}/sd-build)
run_step(${WORK_DIR}/sd-build/consumer)
# A consumer must not get s2kf's tests or programs.
if(EXISTS ${WORK_DIR}/sd-build/s2kf/tests OR EXISTS ${WORK_DIR}/sd-build/s2kf/examples)
  message(FATAL_ERROR "add_subdirectory(s2kf) built the project's own tests or examples")
endif()
