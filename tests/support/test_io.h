// Console output for test and benchmark programs that build for both the host and the
// Cortex-M4 test image: on the host stdout is ready; under QEMU it goes over
// semihosting and must be opened first. The choice is made by which .cc is linked.
#pragma once

namespace mjc::test {

// Makes std::printf reach the console. Call once at the start of main().
void InitOutput();

}  // namespace mjc::test
