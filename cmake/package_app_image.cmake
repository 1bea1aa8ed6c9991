# Packs a linked application image with its header (firmware/bootloader/BOOTLOADER.md):
# the load address is the ELF's `__vector_table`, the build's identity the generated
# build_id.cc of this build (what the image was built from), and mjc-image does the
# rest. Run after every link of an application image:
#   cmake -DTOOL=<mjc-image> -DNM=<nm> -DELF=<image.elf> -DBIN=<image.bin>
#         -DOUT=<file.bin> -DBUILD_ID_CC=<build_id.cc> -DBOARD_TYPE=<n>
#         -DHARDWARE=<min>;<max> [-DFLIPPED=<file.bin>] -P package_app_image.cmake
# FLIPPED also writes a copy with one image byte inverted (a corrupted image for tests).
cmake_minimum_required(VERSION 3.25)

execute_process(COMMAND ${NM} ${ELF} OUTPUT_VARIABLE symbols COMMAND_ERROR_IS_FATAL ANY)
if(NOT symbols MATCHES "([0-9a-fA-F]+) [A-Za-z] __vector_table\n")
  message(FATAL_ERROR "${ELF}: no __vector_table symbol (the linker script defines it)")
endif()
set(load_address "0x${CMAKE_MATCH_1}")

file(READ ${BUILD_ID_CC} id)
if(NOT id MATCHES "kDescribe\\[\\] = \"([^\"]*)\";" )
  message(FATAL_ERROR "${BUILD_ID_CC}: no kDescribe")
endif()
set(describe "${CMAKE_MATCH_1}")
string(REGEX MATCH "kCommit = 0x([0-9a-f]+)u;" _ "${id}")
set(commit "${CMAKE_MATCH_1}")
string(REGEX MATCH "kDirty = (true|false);" _ "${id}")
set(dirty 0)
if(CMAKE_MATCH_1 STREQUAL "true")
  set(dirty 1)
endif()
string(REGEX MATCH "kCommitTimeUnix = ([0-9]+)u;" _ "${id}")
set(time "${CMAKE_MATCH_1}")
if(commit STREQUAL "" OR time STREQUAL "")
  message(FATAL_ERROR "${BUILD_ID_CC}: build identity not understood")
endif()

list(GET HARDWARE 0 hw_min)
list(GET HARDWARE 1 hw_max)
set(common --board-type ${BOARD_TYPE} --hardware ${hw_min} ${hw_max}
    --load-address ${load_address} --commit ${commit} --dirty ${dirty}
    --commit-time ${time} --describe ${describe})
execute_process(COMMAND ${TOOL} pack ${BIN} ${OUT} ${common} COMMAND_ERROR_IS_FATAL ANY)
if(FLIPPED)
  # A byte in the middle of the image: inside the CRC, away from the vector table.
  file(SIZE ${BIN} size)
  math(EXPR middle "${size} / 2")
  execute_process(COMMAND ${TOOL} pack ${BIN} ${FLIPPED} ${common} --flip-byte ${middle}
                  COMMAND_ERROR_IS_FATAL ANY)
endif()
