# How much of the machine each test takes, so that ctest can run many tests at once
# without oversubscribing it (ctest's resource allocation). Included at the end of the
# top-level CMakeLists.txt before the folders that add tests.
#
# The one resource is `cpu`, counted in twelfths of a core: the spec file written here
# gives ctest 12 slots per core of this machine. A kernel-layer VM slowed F times takes
# 12/F of them (mjc_add_kernel_test: kernel-vm's duty cycle lets QEMU run 1/F of the
# time), so at the 3x slowdown three VMs share a core and the suite's longest layer runs
# several scripts at once. The tests that keep a core busy for long take a whole one
# (mjc_test_takes_a_core); the rest (the unit and sim layers that GoogleTest discovers,
# seconds in all, and the quick checks) carry no resource and are bounded by -j alone.
#
# The presets point ctest at the spec file (CMakePresets.json, "resourceSpecFile"), and
# ./test raises -j so the slots, not -j, are what bounds the kernel layer.
cmake_host_system_information(RESULT mjc_cores QUERY NUMBER_OF_LOGICAL_CORES)
if(NOT mjc_cores GREATER 0)
  set(mjc_cores 1)
endif()
math(EXPR mjc_cpu_slots "${mjc_cores} * 12")
file(WRITE "${CMAKE_BINARY_DIR}/ctest-resources.json"
"{\n  \"version\": { \"major\": 1, \"minor\": 0 },\n  \"local\": [ { \"cpu\": [ { \"id\": \"0\", \"slots\": ${mjc_cpu_slots} } ] } ]\n}\n")

# mjc_test_takes_a_core(<test>...): tests that keep a core busy while they run (the
# fuzzers, the power-cut sweeps, QEMU) take a whole core of the `cpu` resource.
function(mjc_test_takes_a_core)
  set_tests_properties(${ARGV} PROPERTIES RESOURCE_GROUPS "cpu:12")
endfunction()
