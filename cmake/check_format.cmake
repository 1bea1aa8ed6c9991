# Fails if any C++ source of ours is not formatted as .clang-format says.
#   cmake -DSOURCE_DIR=<repo> -P check_format.cmake
cmake_minimum_required(VERSION 3.25)
find_program(CLANG_FORMAT NAMES clang-format clang-format-14 REQUIRED)
file(GLOB_RECURSE sources
  ${SOURCE_DIR}/firmware/*.h ${SOURCE_DIR}/firmware/*.cc
  ${SOURCE_DIR}/hal/*.h ${SOURCE_DIR}/hal/*.cc
  ${SOURCE_DIR}/sim_host/*.h ${SOURCE_DIR}/sim_host/*.cc
  ${SOURCE_DIR}/host_tools/*.h ${SOURCE_DIR}/host_tools/*.cc
  ${SOURCE_DIR}/tests/*.h ${SOURCE_DIR}/tests/*.cc)
execute_process(COMMAND ${CLANG_FORMAT} --dry-run --Werror ${sources}
                RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "not clang-formatted (run clang-format -i on these):\n${err}")
endif()
list(LENGTH sources n)
message(STATUS "${n} files clang-format clean")
