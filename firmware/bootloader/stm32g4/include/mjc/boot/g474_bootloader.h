// The CAN bootloader's whole run on the joint board (STM32G474), up to the moment it
// hands over or resets: what firmware/boards/g474_bootloader's main() runs, and what
// the host's tests run against the chip's register models.
//
// In order: the bridge's enable low; the reset flags read (cleared only once it stays);
// the clock tree (170 MHz; FDCAN from PLLQ, 85 MHz; from HSI16 when the crystal is not
// ready within 5 ms); the watchdog (100 ms); the flash
// driver with only the application region writable; the board's identity (node id,
// hardware revision) from its pages, or node 1 / revision 1 without a record; FDCAN1 with
// three filters (BootHold, BootCommand and the bootloader's ISO-TP channel, to this
// node). Then the logic (mjc/boot/bootloader.h) decides, and the loop serves the bus: the
// CAN controller polled (PRIMASK stays set: no interrupt is taken), the watchdog
// refreshed every pass and between the blocks of long flash work.
//
// Without the crystal the bootloader runs the same PLL from HSI16 (the same 170 MHz and
// 85 MHz, so the same bit timing), serves the bus at 1 Mbit/s with ChipInfo saying so,
// and stays (StayReason::kNoClock): it never hands over to the application on a clock
// other than the designed one. A host's Boot resets the chip, which tries the crystal
// again. Were even the PLL from HSI16 to fail, it would stay off the bus (a bit timing
// it cannot meet) and never hand over either. Why HSI16 is enough for the bus, and where
// it is not: hal/README.md, "Clock".
#pragma once

#include <cstdint>
#include <optional>

#include "hal/stm32g4/fdcan.h"
#include "hal/stm32g4/flash.h"
#include "mjc/boot/bootloader.h"
#include "mjc/boot/g474_platform.h"
#include "mjc/boot/handoff.h"

namespace mjc::boot::g474 {

// Until a board's identity record is written (commissioning), it answers as node 1
// (the application's compile-time kNodeId so far) with hardware revision 1.
inline constexpr std::uint8_t kDefaultNode = 1;
inline constexpr std::uint8_t kDefaultHardwareRevision = 1;

struct Exit {
  BootAction action = BootAction::kNone;  // kBoot: hand over; kReset: reset the chip
  std::uint32_t vector_table = 0;         // the image's, for kBoot
};

class G474Bootloader {
 public:
  explicit G474Bootloader(volatile BootHandoff* handoff);

  // From reset to the exit (does not return while the bootloader stays).
  Exit Run();

  const Bootloader* logic() const { return boot_ ? &*boot_ : nullptr; }
  std::uint8_t node() const { return node_; }

 private:
  volatile BootHandoff* handoff_;
  stm32g4::Stm32g4Flash flash_;
  stm32g4::Stm32g4Fdcan can_;
  std::optional<Bootloader> boot_;
  std::uint8_t node_ = kDefaultNode;
};

}  // namespace mjc::boot::g474
