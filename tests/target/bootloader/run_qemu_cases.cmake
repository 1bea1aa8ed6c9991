# The bootloader's target test: QEMU's mps2-an386 boots the bootloader image, with the
# application's packed file (or a corrupted copy, another board's image, or nothing)
# placed at 0x4000 by QEMU's generic loader. Each case's exit status and output are
# checked; the last line counts the cases as expected.
#   cmake -DQEMU=<qemu-system-arm> -DBOOTLOADER=<elf> -DGOOD=<bin> -DFLIPPED=<bin>
#         -DOTHER_BOARD=<bin> -P run_qemu_cases.cmake
cmake_minimum_required(VERSION 3.25)
set(qemu ${QEMU} -M mps2-an386 -display none -monitor none -serial none
    -semihosting-config enable=on,target=native,chardev=sh0 -chardev stdio,id=sh0
    -kernel ${BOOTLOADER})
set(passed 0)
set(total 0)
function(run_case name image status pattern)
  set(loader "")
  if(image)
    set(loader -device loader,file=${image},addr=0x4000)
  endif()
  execute_process(COMMAND ${qemu} ${loader} RESULT_VARIABLE rc OUTPUT_VARIABLE out
                  ERROR_VARIABLE err TIMEOUT 600)
  message("--- ${name}: exit ${rc}\n${out}${err}")
  math(EXPR total "${total} + 1")
  set(total ${total} PARENT_SCOPE)
  if(rc STREQUAL "${status}" AND out MATCHES "${pattern}")
    math(EXPR passed "${passed} + 1")
    set(passed ${passed} PARENT_SCOPE)
  else()
    message("    expected exit ${status} and output matching: ${pattern}")
  endif()
endfunction()

run_case("valid application" ${GOOD} 0
         "bootloader: image valid.*handing over to the vector table at 0x00004200\napplication: running: VTOR 0x00004200 .* start 1 of its image: ok")
run_case("corrupted application" ${FLIPPED} 3 "bootloader: stays: reason 1, error 8 \\(image_crc\\)")
run_case("another board's image" ${OTHER_BOARD} 3 "bootloader: stays: reason 1, error 3 \\(wrong_board\\)")
run_case("no application" "" 3 "bootloader: stays: reason 1, error 1 \\(no_image\\)")
message("bootloader_qemu: ${passed} of ${total} cases as expected")
if(NOT passed EQUAL total)
  message(FATAL_ERROR "bootloader_qemu: ${passed} of ${total}")
endif()
