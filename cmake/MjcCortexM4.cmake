# Cortex-M4F images: CPU flags, firmware code generation rules, and mjc_add_cm4_image().

# The STM32G474 and QEMU's mps2-an386 are both Cortex-M4 with the single-precision FPU.
add_library(mjc_cortex_m4 INTERFACE)
set(MJC_CM4_CPU_FLAGS -mcpu=cortex-m4 -mthumb -mfpu=fpv4-sp-d16 -mfloat-abi=hard)
target_compile_options(mjc_cortex_m4 INTERFACE
  ${MJC_CM4_CPU_FLAGS}
  -ffunction-sections -fdata-sections -fno-common
  $<$<COMPILE_LANGUAGE:CXX>:-fno-exceptions -fno-rtti -fno-threadsafe-statics>
  -fstack-usage -fcallgraph-info=su
  # GCC notes that passing small structs changed ABI in GCC 7.1; every object here is
  # built by one compiler, so the note is noise.
  -Wno-psabi)
target_link_options(mjc_cortex_m4 INTERFACE
  ${MJC_CM4_CPU_FLAGS} -Wl,--gc-sections -nostartfiles)
target_link_libraries(mjc_defaults INTERFACE mjc_cortex_m4)

find_program(MJC_QEMU_ARM qemu-system-arm REQUIRED)

# QEMU running an image to completion: output over semihosting on stdout, exit status
# from SYS_EXIT_EXTENDED. ctest prepends this to the image path.
set(MJC_QEMU_MPS2_COMMAND
  ${MJC_QEMU_ARM} -M mps2-an386 -display none -monitor none -serial none
  -semihosting-config enable=on,target=native,chardev=sh0 -chardev stdio,id=sh0
  -kernel)

# Symbols a firmware image must never contain: any heap allocator, and (with
# NO_DOUBLE) the soft-float double routines that would mean a double on the hot path.
set(MJC_HEAP_SYMBOLS malloc _malloc_r calloc _calloc_r realloc _realloc_r _sbrk _sbrk_r
    _Znwj _Znaj _ZnwjRKSt9nothrow_t _ZnajRKSt9nothrow_t _ZnwjSt11align_val_t)

# mjc_check_image(<target> [FORBIDDEN <symbol>...] [REPORT <symbol>...])
#
# After <target> links (cmake/check_image.cmake): its size report (printed, and
# <target>.elf.size.txt), a failed build when it defines or references a FORBIDDEN
# symbol, and the values of the REPORT symbols printed.
function(mjc_check_image target)
  cmake_parse_arguments(ARG "" "" "FORBIDDEN;REPORT" ${ARGN})
  add_custom_command(TARGET ${target} POST_BUILD
    COMMAND ${CMAKE_COMMAND} -DELF=$<TARGET_FILE:${target}> -DNM=${CMAKE_NM}
            -DSIZE=${CMAKE_SIZE} "-DFORBIDDEN=${ARG_FORBIDDEN}" "-DREPORT=${ARG_REPORT}"
            -P ${PROJECT_SOURCE_DIR}/cmake/check_image.cmake
    VERBATIM)
endfunction()

# mjc_add_cm4_image(<name> SOURCES <src>... [LIBS <lib>...] [STDIO] [NO_HEAP] [NO_DOUBLE]
#                   [SCRIPT <linker script>])
#
# Builds <name>.elf for mps2-an386 with a link map (<name>.map) and a size report
# (<name>.size.txt, also printed), linked with SCRIPT (default linker/mps2_an386.ld). STDIO links newlib's semihosting syscalls (rdimon)
# so printf works: test images only. NO_HEAP proves at link time that nothing can
# allocate: every allocator entry is --wrap'ed to a symbol that does not exist, so a
# reference anywhere fails the link, and the final image is checked with nm.
function(mjc_add_cm4_image name)
  cmake_parse_arguments(ARG "STDIO;NO_HEAP;NO_DOUBLE" "SCRIPT" "SOURCES;LIBS" ${ARGN})
  if(NOT ARG_SCRIPT)
    set(ARG_SCRIPT ${PROJECT_SOURCE_DIR}/linker/mps2_an386.ld)
  endif()
  add_executable(${name} ${ARG_SOURCES} $<TARGET_OBJECTS:mjc_board_qemu_mps2>)
  set_target_properties(${name} PROPERTIES SUFFIX ".elf"
    CROSSCOMPILING_EMULATOR "${MJC_QEMU_MPS2_COMMAND}")
  target_include_directories(${name} PRIVATE
    $<TARGET_PROPERTY:mjc_board_qemu_mps2,INTERFACE_INCLUDE_DIRECTORIES>)
  target_link_libraries(${name} PRIVATE mjc_defaults ${ARG_LIBS})
  target_link_options(${name} PRIVATE
    -T${ARG_SCRIPT}
    -Wl,-Map=$<TARGET_FILE_DIR:${name}>/${name}.map -Wl,--print-memory-usage)
  set_property(TARGET ${name} APPEND PROPERTY LINK_DEPENDS ${ARG_SCRIPT})
  if(ARG_STDIO)
    target_link_options(${name} PRIVATE --specs=rdimon.specs)
  else()
    target_link_options(${name} PRIVATE --specs=nano.specs)
  endif()
  set(forbidden "")
  if(ARG_NO_HEAP)
    list(APPEND forbidden ${MJC_HEAP_SYMBOLS})
    foreach(sym IN LISTS MJC_HEAP_SYMBOLS)
      target_link_options(${name} PRIVATE -Wl,--wrap=${sym})
    endforeach()
  endif()
  if(ARG_NO_DOUBLE)
    list(APPEND forbidden __aeabi_dadd __aeabi_dsub __aeabi_dmul __aeabi_ddiv __aeabi_f2d
         __aeabi_i2d __aeabi_d2iz __aeabi_l2d __aeabi_d2lz)
  endif()
  mjc_check_image(${name} FORBIDDEN ${forbidden})
endfunction()

# mjc_package_app_image(<target> OUTPUT <file> BIN <raw image> BOARD_TYPE <n>
#                       HARDWARE <min> <max> [FLIPPED <file>])
#
# After <target> links, writes <file> in its directory: the image header
# (firmware/bootloader/BOOTLOADER.md) and the raw image BIN (objcopy -O binary, from
# the vector table on). The build id is this build's (mjc_build_id). FLIPPED also
# writes a copy with one image byte inverted, for the bootloader's tests.
function(mjc_package_app_image target)
  cmake_parse_arguments(ARG "" "OUTPUT;BIN;BOARD_TYPE;FLIPPED" "HARDWARE" ${ARGN})
  get_target_property(build_id_sources mjc_build_id SOURCES)
  list(GET build_id_sources 0 build_id_cc)
  add_dependencies(${target} mjc_build_id_update ${MJC_IMAGE_TOOL_TARGET})
  set(flipped "")
  if(ARG_FLIPPED)
    set(flipped -DFLIPPED=$<TARGET_FILE_DIR:${target}>/${ARG_FLIPPED})
  endif()
  add_custom_command(TARGET ${target} POST_BUILD
    COMMAND ${CMAKE_COMMAND} -DTOOL=${MJC_IMAGE_TOOL} -DNM=${CMAKE_NM}
            -DELF=$<TARGET_FILE:${target}> -DBIN=${ARG_BIN}
            -DOUT=$<TARGET_FILE_DIR:${target}>/${ARG_OUTPUT}
            -DBUILD_ID_CC=${build_id_cc} -DBOARD_TYPE=${ARG_BOARD_TYPE}
            "-DHARDWARE=${ARG_HARDWARE}" ${flipped}
            -P ${PROJECT_SOURCE_DIR}/cmake/package_app_image.cmake
    VERBATIM)
endfunction()

# mjc_add_g474_image(<name> SOURCES <src>... [LIBS <lib>...]
#                    [FLASH_BUDGET <bytes>] [RAM_BUDGET <bytes>]
#                    [SCRIPT <linker script>] [REPORT <symbol>...]
#                    [APP_IMAGE <file> BOARD_TYPE <n> HARDWARE <min> <max>])
#
# An STM32G474 firmware image linked with linker/stm32g474.ld (the board's start-up code
# is one of the SOURCES): <name>.elf, <name>.bin and <name>.hex (objcopy), <name>.map,
# the size report (printed, and <name>.elf.size.txt), the no-heap and no-double checks of
# firmware images (as mjc_add_cm4_image's NO_HEAP NO_DOUBLE), and the budgets: the link
# fails when the image's flash (code, constants, initial data) exceeds FLASH_BUDGET or
# its RAM (SRAM and CCM, both stacks included) exceeds RAM_BUDGET (defaults 64 KB and
# 32 KB; the linker script's ASSERTs). SCRIPT replaces linker/stm32g474.ld (the
# bootloader's own script), REPORT adds linker symbols to the printed figures, and
# APP_IMAGE writes <file> beside the image: the application with its image header
# (mjc_package_app_image).
function(mjc_add_g474_image name)
  cmake_parse_arguments(ARG "" "FLASH_BUDGET;RAM_BUDGET;SCRIPT;APP_IMAGE;BOARD_TYPE"
                        "SOURCES;LIBS;REPORT;HARDWARE" ${ARGN})
  if(NOT ARG_FLASH_BUDGET)
    set(ARG_FLASH_BUDGET 65536)
  endif()
  if(NOT ARG_RAM_BUDGET)
    set(ARG_RAM_BUDGET 32768)
  endif()
  set(script ${PROJECT_SOURCE_DIR}/linker/stm32g474.ld)
  if(ARG_SCRIPT)
    set(script ${ARG_SCRIPT})
  endif()
  add_executable(${name} ${ARG_SOURCES})
  set_target_properties(${name} PROPERTIES SUFFIX ".elf")
  target_link_libraries(${name} PRIVATE mjc_defaults ${ARG_LIBS})
  target_link_options(${name} PRIVATE
    -T${script} --specs=nano.specs
    -Wl,--defsym=__flash_budget=${ARG_FLASH_BUDGET}
    -Wl,--defsym=__ram_budget=${ARG_RAM_BUDGET}
    -Wl,-Map=$<TARGET_FILE_DIR:${name}>/${name}.map -Wl,--print-memory-usage)
  set_property(TARGET ${name} APPEND PROPERTY LINK_DEPENDS ${script})
  foreach(sym IN LISTS MJC_HEAP_SYMBOLS)
    target_link_options(${name} PRIVATE -Wl,--wrap=${sym})
  endforeach()
  set(forbidden ${MJC_HEAP_SYMBOLS} __aeabi_dadd __aeabi_dsub __aeabi_dmul __aeabi_ddiv
      __aeabi_f2d __aeabi_i2d __aeabi_d2iz __aeabi_l2d __aeabi_d2lz)
  # The linker script's figures, printed after every link.
  set(report __flash_used __flash_budget __ram_used __ram_budget __main_stack_size
      __interrupt_stack_size ${ARG_REPORT})
  add_custom_command(TARGET ${name} POST_BUILD
    COMMAND ${CMAKE_OBJCOPY} -O binary $<TARGET_FILE:${name}>
            $<TARGET_FILE_DIR:${name}>/${name}.bin
    COMMAND ${CMAKE_OBJCOPY} -O ihex $<TARGET_FILE:${name}>
            $<TARGET_FILE_DIR:${name}>/${name}.hex
    VERBATIM)
  mjc_check_image(${name} FORBIDDEN ${forbidden} REPORT ${report})
  if(ARG_APP_IMAGE)
    mjc_package_app_image(${name} OUTPUT ${ARG_APP_IMAGE} BIN
      $<TARGET_FILE_DIR:${name}>/${name}.bin BOARD_TYPE ${ARG_BOARD_TYPE}
      HARDWARE ${ARG_HARDWARE})
  endif()
endfunction()
