#include "semihost.h"

namespace mjc::qemu {
namespace {

constexpr std::uint32_t kSysWrite0 = 0x04;
constexpr std::uint32_t kSysExitExtended = 0x20;
constexpr std::uint32_t kAdpStoppedApplicationExit = 0x20026;

std::uint32_t Call(std::uint32_t op, const void* arg) {
  register std::uint32_t r0 asm("r0") = op;
  register const void* r1 asm("r1") = arg;
  asm volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
  return r0;
}

}  // namespace

void SemihostWrite(const char* text) { Call(kSysWrite0, text); }

void SemihostExit(int code) {
  const std::uint32_t block[2] = {kAdpStoppedApplicationExit,
                                  static_cast<std::uint32_t>(code)};
  Call(kSysExitExtended, block);
  for (;;) {
  }
}

}  // namespace mjc::qemu
