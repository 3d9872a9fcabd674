# The consumer test (ctest `consumer`, label consumer): installs the build tree BUILD_DIR into a
# fresh prefix under WORK_DIR, configures and builds this folder's project against it with the
# same generator and compiler (GENERATOR, CXX_COMPILER, LAUNCHER: ccache or empty), and runs it. Fails at the first step
# that fails, with that step's output.
#   cmake -DBUILD_DIR=... -DWORK_DIR=... -DGENERATOR=Ninja -DCXX_COMPILER=... [-DLAUNCHER=...]
#         -P run_consumer_test.cmake
foreach(var BUILD_DIR WORK_DIR GENERATOR CXX_COMPILER)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "run_consumer_test.cmake: -D${var}=... is required")
  endif()
endforeach()

function(step what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(NOT code EQUAL 0)
    message(FATAL_ERROR "consumer test: ${what} failed (${code}):\n${out}")
  endif()
  message(STATUS "consumer test: ${what}: done")
  set(step_output "${out}" PARENT_SCOPE)
endfunction()

file(REMOVE_RECURSE ${WORK_DIR})
set(prefix ${WORK_DIR}/prefix)
step("install into ${prefix}" ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix})
set(launcher)
if(LAUNCHER)
  set(launcher -DCMAKE_CXX_COMPILER_LAUNCHER=${LAUNCHER})
endif()
step("configure against it" ${CMAKE_COMMAND} -S ${CMAKE_CURRENT_LIST_DIR} -B ${WORK_DIR}/build
     -G ${GENERATOR} -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=${prefix}
     -DCMAKE_CXX_COMPILER=${CXX_COMPILER} ${launcher})
step("build" ${CMAKE_COMMAND} --build ${WORK_DIR}/build)
step("run" ${WORK_DIR}/build/impactdic_consumer)
message(STATUS "${step_output}")
