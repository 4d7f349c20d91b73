# SPDX-License-Identifier: AGPL-3.0-or-later
# test_stream_levels_example (cmake -P): examples/stream_levels on a 4-level
# torus made with `hmc gen` + `hmc enc`, throttled to about half a second.
# Variables: HMC_PROGRAM, HMC_EXAMPLE, HMC_WORK_DIR.
cmake_minimum_required(VERSION 3.18)
file(REMOVE_RECURSE ${HMC_WORK_DIR})
file(MAKE_DIRECTORY ${HMC_WORK_DIR})
function(hmc_run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    string(REPLACE ";" " " cmd "${ARGN}")
    message(FATAL_ERROR "${what} failed (${rc}):\n  ${cmd}\n${out}\n${err}")
  endif()
  set(HMC_OUT "${out}" PARENT_SCOPE)
endfunction()
hmc_run("hmc gen" ${HMC_PROGRAM} gen torus --vertices 4000 -o ${HMC_WORK_DIR}/torus.ply)
hmc_run("hmc enc" ${HMC_PROGRAM} enc ${HMC_WORK_DIR}/torus.ply -o ${HMC_WORK_DIR}/torus.hmc --levels 4)
file(SIZE ${HMC_WORK_DIR}/torus.hmc size)
math(EXPR rate "${size} * 2")  # about half a second
execute_process(COMMAND ${HMC_EXAMPLE} --rate ${rate} INPUT_FILE ${HMC_WORK_DIR}/torus.hmc
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message(STATUS "${out}${err}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "stream_levels failed (${rc})")
endif()
foreach(lod 3 2 1 0)
  if(NOT out MATCHES "level ${lod} complete after [0-9]+ bytes: [0-9]+ vertices, [1-9][0-9]* triangles")
    message(FATAL_ERROR "no line for level ${lod}")
  endif()
endforeach()
if(NOT out MATCHES "end of stream: ${size} bytes, 4 levels")
  message(FATAL_ERROR "no end-of-stream line")
endif()
