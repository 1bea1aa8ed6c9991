// The application side of the bootloader's target test: started by the bootloader on
// QEMU's mps2-an386, it checks that it was handed over as the core would start it —
// VTOR at its own vector table, the main stack from its word 0, privileged thread mode
// on MSP, PRIMASK clear — and reads the handoff block the bootloader wrote (its start
// counted for its own image, named by the CRC in its header at 0x4000), then confirms
// a healthy start. Exit status 0 when all holds.
#include "mjc/boot/handoff.h"
#include "mjc/boot/image_header.h"
#include "qemu_layout.h"
#include "semihost.h"

extern "C" {
extern const std::uint32_t __vector_table[];
extern std::uint32_t __stack_top[];
extern mjc::boot::BootHandoff __boot_handoff;
}

int main() {
  using namespace mjc::boot;
  std::uint32_t msp = 0, control = 0, primask = 0;
  asm volatile("mrs %0, msp" : "=r"(msp));
  asm volatile("mrs %0, control" : "=r"(control));
  asm volatile("mrs %0, primask" : "=r"(primask));
  const std::uint32_t vtor =
      *reinterpret_cast<const volatile std::uint32_t*>(0xE000ED08u);
  const auto table =
      static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(__vector_table));
  const auto top =
      static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(__stack_top));
  ImageHeader header;
  const bool header_ok =
      DecodeHeader(std::span<const std::uint8_t, kHeaderSize>(
                       reinterpret_cast<const std::uint8_t*>(0x4000u), kHeaderSize),
                   &header) == ImageCheck::kValid;
  const std::uint32_t attempts =
      header_ok ? BootAttempts(__boot_handoff, header.image_crc) : 0;
  const bool ok = vtor == table && __vector_table[0] == top && msp <= top &&
                  msp > top - 8192 && (control & 3u) == 0 && primask == 0 &&
                  attempts == 1;
  qemu::Line line;
  line << "application: running: VTOR ";
  line.Hex(vtor) << " (its table ";
  line.Hex(table) << "), MSP ";
  line.Hex(msp) << " (top ";
  line.Hex(top) << "), CONTROL ";
  line.Dec(control) << ", PRIMASK ";
  line.Dec(primask) << ", start ";
  line.Dec(attempts) << " of its image: " << (ok ? "ok" : "WRONG") << "\n";
  mjc::qemu::SemihostWrite(line.c_str());
  ConfirmHealthyBoot(__boot_handoff);
  return ok && BootAttempts(__boot_handoff, header.image_crc) == 0 ? 0 : 1;
}
