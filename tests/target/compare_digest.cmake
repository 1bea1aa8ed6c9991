# Runs the host digest program and the Cortex-M4 digest image and fails unless both
# print the same "core_digest: <hex>" line.
#   cmake -DHOST_COMMAND=<exe> -DTARGET_COMMAND=<qemu...;elf> -P compare_digest.cmake
cmake_minimum_required(VERSION 3.25)
if(NOT EXISTS "${HOST_COMMAND}")
  message(FATAL_ERROR "host digest program ${HOST_COMMAND} not built: build the host "
                      "preset first (./test does), or set MJC_HOST_BUILD_DIR")
endif()
foreach(side HOST TARGET)
  execute_process(COMMAND ${${side}_COMMAND} OUTPUT_VARIABLE out RESULT_VARIABLE rc
                  TIMEOUT 1700)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${side} digest run failed (${rc}):\n${out}")
  endif()
  string(REGEX MATCH "core_digest: [0-9a-f]+ \\([0-9]+ steps\\)" line "${out}")
  if(NOT line)
    message(FATAL_ERROR "${side} printed no digest:\n${out}")
  endif()
  set(${side}_LINE "${line}")
  message(STATUS "${side}: ${line}")
endforeach()
if(NOT HOST_LINE STREQUAL TARGET_LINE)
  message(FATAL_ERROR "x86-64 and Cortex-M4 differ:\n  host   ${HOST_LINE}\n  target ${TARGET_LINE}")
endif()
message(STATUS "bit-exact: x86-64 and Cortex-M4 agree")
