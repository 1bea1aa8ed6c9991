# Post-link check of a Cortex-M image: writes <elf>.size.txt (section sizes) and fails
# if the image defines or references any symbol in FORBIDDEN; prints the value of each
# (absolute) symbol in REPORT, e.g. the linker script's budget figures.
#   cmake -DELF=<image> -DNM=<nm> -DSIZE=<size> -DFORBIDDEN=<sym;...> [-DREPORT=<sym;...>]
#         -P check_image.cmake
cmake_minimum_required(VERSION 3.25)
execute_process(COMMAND ${SIZE} -A -d ${ELF} OUTPUT_FILE ${ELF}.size.txt
                COMMAND_ERROR_IS_FATAL ANY)
execute_process(COMMAND ${SIZE} -B -d ${ELF} OUTPUT_VARIABLE berkeley COMMAND_ERROR_IS_FATAL ANY)
message(STATUS "size of ${ELF}:\n${berkeley}")
if(FORBIDDEN)
  execute_process(COMMAND ${NM} ${ELF} OUTPUT_VARIABLE symbols COMMAND_ERROR_IS_FATAL ANY)
  string(REPLACE "\n" ";" lines "${symbols}")
  foreach(line IN LISTS lines)
    string(REGEX REPLACE "^.* " "" sym "${line}")
    if(sym IN_LIST FORBIDDEN)
      message(FATAL_ERROR "${ELF}: forbidden symbol '${sym}' (heap or double on target)")
    endif()
  endforeach()
endif()
if(REPORT)
  execute_process(COMMAND ${NM} ${ELF} OUTPUT_VARIABLE symbols COMMAND_ERROR_IS_FATAL ANY)
  string(REPLACE "\n" ";" lines "${symbols}")
  set(report "")
  foreach(line IN LISTS lines)
    if(line MATCHES "^([0-9a-fA-F]+) [A-Za-z] (.+)$" AND CMAKE_MATCH_2 IN_LIST REPORT)
      math(EXPR value "0x${CMAKE_MATCH_1}")
      string(APPEND report "  ${CMAKE_MATCH_2} = ${value}\n")
    endif()
  endforeach()
  message(STATUS "${ELF}:\n${report}")
endif()
