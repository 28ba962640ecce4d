# SPDX-License-Identifier: BSD-3-Clause
# cmake -DBUILD_DIR=... -DCONSUMER_SOURCE=... -DWORK_DIR=... -P run_consumer_test.cmake
# Installs the build into WORK_DIR/prefix, checks the layout, then configures, builds and runs
# the consumer project against it, and runs the installed `lidarcal` on the installed example.
foreach(var BUILD_DIR CONSUMER_SOURCE WORK_DIR)
  if(NOT ${var})
    message(FATAL_ERROR "${var} not set")
  endif()
endforeach()
file(REMOVE_RECURSE "${WORK_DIR}")
set(prefix "${WORK_DIR}/prefix")

function(run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${what} failed (${rc}):\n${out}\n${err}")
  endif()
  message(STATUS "${what}: ok")
  set(last_output "${out}" PARENT_SCOPE)
endfunction()

run("install" "${CMAKE_COMMAND}" --install "${BUILD_DIR}" --prefix "${prefix}")
foreach(f bin/lidarcal include/lidarcal/io/sequence.hpp include/lidarcal/common/pose2.hpp
          share/lidarcal/example/scans/sequence.json share/lidarcal/scenes/paper_field.json
          lib/cmake/lidarcal/lidarcalConfig.cmake lib/cmake/lidarcal/lidarcalConfigVersion.cmake
          lib/cmake/lidarcal/lidarcalTargets.cmake)
  if(NOT EXISTS "${prefix}/${f}")
    message(FATAL_ERROR "not installed: ${f}")
  endif()
endforeach()
file(GLOB libs "${prefix}/lib/liblidarcal_*.a" "${prefix}/lib/*/liblidarcal_*.a")
list(LENGTH libs nlibs)
if(nlibs LESS 5)
  message(FATAL_ERROR "expected at least 5 installed libraries, found: ${libs}")
endif()

run("configure consumer" "${CMAKE_COMMAND}" -S "${CONSUMER_SOURCE}" -B "${WORK_DIR}/build"
    "-DCMAKE_PREFIX_PATH=${prefix}" -DCMAKE_BUILD_TYPE=Release)
run("build consumer" "${CMAKE_COMMAND}" --build "${WORK_DIR}/build" -j2)
run("run consumer" "${WORK_DIR}/build/consumer" "${WORK_DIR}")
message(STATUS "${last_output}")
run("installed lidarcal info" "${CMAKE_COMMAND}" -E env "LIDARCAL_DATA_DIR=${prefix}/share/lidarcal"
    "${prefix}/bin/lidarcal" info "${prefix}/share/lidarcal/example/scans")
file(REMOVE_RECURSE "${WORK_DIR}")
