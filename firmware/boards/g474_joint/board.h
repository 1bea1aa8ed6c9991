// The joint board's hardware as the firmware's composition root sees it: the drivers,
// bound to this board's pins and memory map, behind the interfaces the application
// uses (hal::JointIo for the tick, hal::CanPort, hal::Flash).
//
// Two entries run this code. The image (startup.cc and main.cc, chip only: the vector
// table, Reset_Handler's stack switch, the memory initialisation) and the virtual board
// (sim_host/g474_board: the same sources built for x86 against the register models of
// sim_host/g474) both call
//   BringUp();  // the start-up report (did the last run crash?) and the clock tree
//   Run();      // pins, watchdog, drivers, JointBoard, the tick, the main loop
// with the interrupt entries of interrupts.h as the handlers of their IRQs.
//
// Interrupts (vector table in startup.cc, priorities in hal/stm32g4/nvic.h):
//   TIM1_UP_TIM16 (IRQ 25, priority 0): the 10 kHz control tick
//   FDCAN1_IT0    (IRQ 21, priority 4): received frames → the CAN port's queue
//   FDCAN1_IT1    (IRQ 22, priority 4): bus-off → recovery, reported by TakeBusOff()
//   everything else: DefaultHandler (bridge stopped, crash recorded, reset)
#pragma once

#include <array>
#include <cstdint>
#include <optional>

#include "hal/stm32g4/clock.h"
#include "hal/stm32g4/fdcan.h"
#include "hal/stm32g4/flash.h"
#include "hal/stm32g4/joint_io.h"
#include "hal/stm32g4/watchdog.h"
#include "mjc/app/joint_board.h"
#include "mjc/boot/handoff.h"
#include "mjc/protocol/can_frame.h"
#include "mjc/protocol/messages.h"
#include "pins.h"

namespace mjc::board {

inline constexpr stm32g4::JointIoBlocks kJointIoBlocks{
    .joint_cs = stm32g4::At(kJointCs),
    .bridge_enable = stm32g4::At(kBridgeEnable),
    .bridge_low_side_min_ns = kBridgeLowSideMinNs};
using JointIo = stm32g4::Stm32g4JointIo<kJointIoBlocks>;
static_assert(hal::JointIo<JointIo>);

// The board's CAN node id when its identity pages hold no record (commissioning writes
// one, mjc/boot/identity_store.h; every image and every update keeps it).
inline constexpr std::uint8_t kNodeId = 1;

// Acceptance filters: exactly the host → board messages addressed to `node` (one
// identifier each, mask 0x7FF); every other identifier is rejected by the controller.
constexpr std::array<stm32g4::CanFilter, 9> NodeFilters(std::uint8_t node) {
  using protocol::Function;
  constexpr Function kTaken[] = {
      Function::kCommand,       Function::kSetpoint,     Function::kTrialConfig,
      Function::kSweepConfig,   Function::kParamWrite,   Function::kParamRead,
      Function::kHostHeartbeat, Function::kIsoTpToBoard, Function::kBootHold,
  };
  std::array<stm32g4::CanFilter, 9> filters{};
  for (std::size_t i = 0; i < filters.size(); ++i) {
    filters[i] = {static_cast<std::uint16_t>(
                      protocol::MakeId(static_cast<std::uint8_t>(kTaken[i]), node)),
                  0x7FF};
  }
  return filters;
}

// What the start-up code leaves for Run(): the clock bring-up's result (a failed one
// leaves the chip on HSI16: the board must not run the motor) and, when the last reset
// came from a fault handler, which exception it was.
struct StartupReport {
  stm32g4::ClockResult clock = stm32g4::ClockResult::kOk;
  // When `clock` failed: the bring-up from HSI16 (the same frequencies, HSI16's
  // accuracy), which lets the board report the fault on the bus.
  std::optional<stm32g4::ClockResult> fallback;
  bool crashed = false;  // the previous run ended in DefaultHandler
  std::uint32_t crash_exception =
      0;  // its exception number (IPSR): 2 NMI, 3 HardFault, ..
};
const StartupReport& Startup();

// Survives a reset (.noinit: neither copied nor zeroed); valid when `magic` matches.
// DefaultHandler (startup.cc) writes it; BringUp() reads it into the report.
struct CrashRecord {
  std::uint32_t magic;
  std::uint32_t exception;
};
inline constexpr std::uint32_t kCrashMagic = 0x43524153u;  // "CRAS"
extern CrashRecord g_crash;

// After the memory is initialised: takes the crash record into Startup()'s report,
// then brings the clock tree up to 170 MHz (its result is in the report too).
void BringUp();

// What the image runs with its defaults; the virtual board passes its command line's.
struct RunOptions {
  // The node id when the identity pages hold no record (an identity record's wins, as
  // on the chip).
  std::uint8_t node = kNodeId;
  // The host supervision timeout (CanNodeConfig::host_timeout_ms); none: the node's
  // default. A board simulated faster than real time scales it with its speed.
  std::optional<std::uint16_t> host_timeout_ms;
};

// The board, from the pins to the main loop; never returns. Every RAM object the
// board's code keeps (the drivers, the board, the tick count) is rebuilt here first:
// on the chip the start-up code has just zeroed their memory and this writes the same
// values again; the host build enters Run() again after a reset of its virtual chip,
// where nothing zeroes them (nothing here relies on a static's first use either).
[[noreturn]] void Run(const RunOptions& options = {});

// The calibration pages' first byte on the chip's bus (2 × 2 KB, the linker script's
// CAL region): from the linker's symbol on the chip, from the same script's map on
// the host.
std::uint32_t CalibrationAddress();

// The 32 bytes the bootloader and this image tell each other across a reset (the
// linker script's HANDOFF region on the chip, 0x2001_3FE0; memory no reset of the
// virtual chip touches on the host). Run() confirms a healthy start there
// (boot::ConfirmHealthyBoot) once its tick and main loop have run 2 s.
volatile boot::BootHandoff& Handoff();

// The ticks (at 10 kHz) the tick and the main loop must run, the watchdog refreshed,
// before Run() confirms a healthy start: until then a reset counts as a failed start, and
// after three the bootloader stays (firmware/bootloader/BOOTLOADER.md).
inline constexpr std::uint32_t kHealthyBootTicks = 20'000;

// What a debugger would read in the board's RAM: the board once Run() has built it
// (nullptr before), and what its boot found in flash. The virtual board reads them
// between interrupts (its summary, the tests); nothing on the chip calls them.
const app::JointBoard* Instance();
struct BootFacts {
  bool calibration_restored = false;
  std::uint32_t calibration_sequence = 0;
};
const BootFacts& LastBoot();
// The last tick's duration in core cycles (DWT CYCCNT, from its start to the end of its
// writes): what the virtual board's figures sample.
std::uint32_t LastTickCycles();

// Any context: bridge enable low and TIM1's outputs to their idle level (low sides on).
inline void StopBridge() { JointIo::EmergencyStop(); }

}  // namespace mjc::board
