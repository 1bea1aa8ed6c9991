# Settings every platform shares: warnings, Eigen, sanitizers, layering checks.

# Warnings as errors on every target of ours (not on third-party headers, which come in
# as SYSTEM includes). -Wconversion is what catches a silent Q-format truncation.
add_library(mjc_warnings INTERFACE)
target_compile_options(mjc_warnings INTERFACE
  -Wall -Wextra -Werror -Wconversion -Wsign-conversion -Wdouble-promotion -Wshadow
  -Wundef -Wnon-virtual-dtor -Wold-style-cast -Wcast-align -Wnull-dereference)

# Everything of ours links mjc_defaults: warnings plus, on the target, the CPU flags.
add_library(mjc_defaults INTERFACE)
target_link_libraries(mjc_defaults INTERFACE mjc_warnings)

# Eigen 3.4, header-only, found on the build machine for every platform. The defines
# that make it fit a Cortex-M (no heap, no SIMD paths, no iostream) sit on this one
# target, and everything that uses Eigen links it; the host uses them too, so host and
# target compile the same code paths.
find_package(Eigen3 3.4 REQUIRED NO_MODULE)
add_library(mjc_eigen INTERFACE)
target_link_libraries(mjc_eigen INTERFACE Eigen3::Eigen)
target_compile_definitions(mjc_eigen INTERFACE
  EIGEN_NO_MALLOC EIGEN_DONT_VECTORIZE EIGEN_NO_IO EIGEN_MPL2_ONLY)

option(MJC_SANITIZE "Build with AddressSanitizer and UndefinedBehaviorSanitizer" OFF)
if(MJC_SANITIZE)
  add_compile_options(-fsanitize=address,undefined -fno-sanitize-recover=all
                      -fno-omit-frame-pointer)
  add_link_options(-fsanitize=address,undefined)
endif()

# Fails the configure step if `target` reaches, through any chain of link dependencies,
# a target whose name matches `pattern`.
function(mjc_forbid_dependency target pattern)
  set(seen "")
  set(queue ${target})
  while(queue)
    list(POP_FRONT queue current)
    if(current IN_LIST seen OR NOT TARGET ${current})
      continue()
    endif()
    list(APPEND seen ${current})
    get_target_property(deps ${current} INTERFACE_LINK_LIBRARIES)
    get_target_property(type ${current} TYPE)
    if(NOT type STREQUAL "INTERFACE_LIBRARY")
      get_target_property(private ${current} LINK_LIBRARIES)
      if(private)
        list(APPEND deps ${private})
      endif()
    endif()
    foreach(dep IN LISTS deps)
      string(REGEX REPLACE "^\\$<LINK_ONLY:(.*)>$" "\\1" dep "${dep}")
      if(dep MATCHES "${pattern}")
        message(FATAL_ERROR "layering: ${target} must not depend on ${dep} (via ${current})")
      endif()
      list(APPEND queue ${dep})
    endforeach()
  endwhile()
endfunction()
