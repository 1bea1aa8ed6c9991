// The bootloader on QEMU's mps2-an386: the same logic as on the board
// (mjc::boot::Bootloader, no hold window: there is no CAN here), reading the image QEMU
// placed at 0x4000, then the same hand-over (mjc/boot/jump.h) — or it stays and says
// why. Output over semihosting; exit status 3 when it stays (the application's own
// status otherwise).
#include <cstddef>

#include "mjc/boot/bootloader.h"
#include "mjc/boot/jump.h"
#include "qemu_layout.h"
#include "semihost.h"

extern "C" {
extern mjc::boot::BootHandoff __boot_handoff;
}

// No heap: hal::Flash's vtable names its deleting destructor, which calls operator
// delete; these keep libstdc++'s (and with it the allocator) out of the image.
void operator delete(void* /*pointer*/) noexcept { mjc::qemu::SemihostExit(99); }
void operator delete(void* /*pointer*/, std::size_t /*bytes*/) noexcept {
  mjc::qemu::SemihostExit(99);
}

int main() {
  using namespace mjc::boot;
  qemu::MappedFlash flash;
  BootloaderConfig config;
  config.layout = qemu::kQemuLayout;
  config.board_type = static_cast<std::uint16_t>(BoardType::kQemuMps2An386);
  config.hardware_revision = 1;
  config.hold_window_ms = 0;
  // QEMU's RAM is zero at start, not random: the handoff block is as after a power-on.
  Bootloader boot(config, &flash, nullptr, &__boot_handoff);
  if (boot.Start(0, /*software_reset=*/false) == BootAction::kBoot) {
    const InstalledImage& image = boot.image();
    qemu::Line line;
    line << "bootloader: image valid: ";
    line.Dec(image.header.length) << " bytes, CRC-32 ";
    line.Hex(image.header.image_crc) << ", reset handler ";
    line.Hex(image.reset_handler) << ", start ";
    line.Dec(BootAttempts(__boot_handoff, image.header.image_crc))
        << "; handing over to the vector table at ";
    line.Hex(boot.boot_address()) << "\n";
    mjc::qemu::SemihostWrite(line.c_str());
    // Interrupts off and none pending (this image enabled none), then the jump.
    asm volatile("cpsid i" ::: "memory");
    for (std::uint32_t i = 0; i < 4; ++i) {
      reinterpret_cast<volatile std::uint32_t*>(0xE000E180u)[i] = 0xFFFFFFFFu;  // ICER
      reinterpret_cast<volatile std::uint32_t*>(0xE000E280u)[i] = 0xFFFFFFFFu;  // ICPR
    }
    JumpToImage(boot.boot_address());
  }
  qemu::Line line;
  line << "bootloader: stays: reason ";
  line.Dec(static_cast<std::uint32_t>(boot.reason())) << ", error ";
  line.Dec(static_cast<std::uint32_t>(boot.error()))
      << " (" << ImageCheckName(boot.image().check) << ")\n";
  mjc::qemu::SemihostWrite(line.c_str());
  return 3;
}
