// The CAN bootloader's image for the joint board (STM32G474): its run is
// mjc::boot::g474::G474Bootloader (firmware/bootloader/stm32g4, tested on the chip's
// register models); this file adds what only the chip can do — the hand-over to the
// application, or the reset a host's Boot asks for.
#include <cstdint>
#include <optional>

#include "hal/stm32g4/nvic.h"
#include "mjc/boot/g474_bootloader.h"
#include "mjc/boot/g474_platform.h"
#include "mjc/boot/jump.h"

extern "C" {
// The handoff block (linker/stm32g474_bootloader.ld, HANDOFF).
extern mjc::boot::BootHandoff __boot_handoff;
}

int main() {
  using namespace mjc;
  // Constructed at run time into .bss: a constant-initialised driver would be copied
  // from flash (.data), its 1.2 KB receive queue with it.
  static std::optional<boot::g474::G474Bootloader> bootloader;
  const boot::g474::Exit exit = bootloader.emplace(&__boot_handoff).Run();
  if (exit.action == boot::BootAction::kBoot) {
    boot::g474::ReleasePeripherals();
    boot::JumpToImage(exit.vector_table);
  }
  stm32g4::RequestSystemReset();
  for (;;) {
  }
}
