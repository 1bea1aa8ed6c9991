// The joint board's hardware as the firmware's composition root sees it: the drivers,
// bound to this board's pins and memory map, behind the interfaces the application
// uses (hal::JointIo for the tick, hal::CanPort, hal::Flash).
//
// Interrupts (vector table in startup.cc, priorities in hal/stm32g4/nvic.h):
//   TIM1_UP_TIM16 (IRQ 25, priority 0): the 10 kHz control tick
//   FDCAN1_IT0    (IRQ 21, priority 4): received frames → the CAN port's queue
//   FDCAN1_IT1    (IRQ 22, priority 4): bus-off → recovery, reported by TakeBusOff()
//   everything else: DefaultHandler (bridge stopped, crash recorded, reset)
#pragma once

#include <array>
#include <cstdint>

#include "hal/stm32g4/clock.h"
#include "hal/stm32g4/fdcan.h"
#include "hal/stm32g4/flash.h"
#include "hal/stm32g4/joint_io.h"
#include "hal/stm32g4/watchdog.h"
#include "mjc/protocol/can_frame.h"
#include "mjc/protocol/messages.h"
#include "pins.h"

namespace mjc::board {

inline constexpr stm32g4::JointIoBlocks kJointIoBlocks{
    .joint_cs = stm32g4::At(kJointCs), .bridge_enable = stm32g4::At(kBridgeEnable)};
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

// What the start-up code leaves for main(): the clock bring-up's result (a failed one
// leaves the chip on HSI16: the board must not run the motor) and, when the last reset
// came from a fault handler, which exception it was.
struct StartupReport {
  stm32g4::ClockResult clock = stm32g4::ClockResult::kOk;
  bool crashed = false;  // the previous run ended in DefaultHandler
  std::uint32_t crash_exception =
      0;  // its exception number (IPSR): 2 NMI, 3 HardFault, ..
};
const StartupReport& Startup();

// Any context: bridge enable low and TIM1's outputs to their idle level (low sides on).
inline void StopBridge() { JointIo::EmergencyStop(); }

}  // namespace mjc::board
