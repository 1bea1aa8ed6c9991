// ARM semihosting for test images under QEMU (`-semihosting-config enable=on`).
//
// Written by hand rather than taken from newlib's librdimon because firmware-style
// images (benchmarks, the no-heap proof) must not link newlib's stdio, which allocates:
// these two calls need nothing but a BKPT 0xAB.
#pragma once

#include <cstdint>

namespace mjc::qemu {

// Writes a NUL-terminated string to the host's stdout.
void SemihostWrite(const char* text);

// Ends the QEMU process with `code` as its exit status (SYS_EXIT_EXTENDED).
[[noreturn]] void SemihostExit(int code);

}  // namespace mjc::qemu
