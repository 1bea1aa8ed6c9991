// Interrupt enables and priorities (ARMv7-M B3.4, NVIC) and the system reset request
// (B3.2.6, AIRCR). The STM32G474 implements the top 4 bits of each 8-bit priority
// (kNvicPriorityBits): priority p (0 = most urgent .. 15) is written as p << 4.
#pragma once

#include <cstdint>

#include "hal/stm32g4/mmio.h"
#include "hal/stm32g4/regs/cortex_m4.h"

namespace mjc::stm32g4 {

// Priorities of this board's interrupts: the control tick pre-empts everything else.
inline constexpr std::uint8_t kPriorityTick = 0;
inline constexpr std::uint8_t kPriorityCan = 4;

// Sets `irq`'s priority (0..15), clears a stale pending request, then enables it.
// Initialisation context (the priority word is read-modified-written).
inline void EnableIrq(std::uint8_t irq, std::uint8_t priority) {
  const Address ipr = nvic::kBase + nvic::IprOffset(irq);
  const unsigned shift = nvic::IprShift(irq);
  const std::uint32_t value =
      static_cast<std::uint32_t>(priority << (8 - kNvicPriorityBits)) & 0xFFu;
  Write32(ipr, (Read32(ipr) & ~(0xFFu << shift)) | (value << shift));
  Write32(nvic::kBase + nvic::IcprOffset(irq), nvic::IrqBit(irq));
  Write32(nvic::kBase + nvic::IserOffset(irq), nvic::IrqBit(irq));
}

inline void DisableIrq(std::uint8_t irq) {
  Write32(nvic::kBase + nvic::IcerOffset(irq), nvic::IrqBit(irq));
  DataSyncBarrier();
  InstructionSyncBarrier();
}

// Requests a system reset (AIRCR.SYSRESETREQ with the key; PRIGROUP kept) and waits for
// it. On the host the request is only recorded by the bound register space, so this
// returns there.
inline void RequestSystemReset() {
  DataSyncBarrier();
  const Address aircr = scb::kBase + scb::kAircr;
  const std::uint32_t keep = Read32(aircr) & scb::aircr::kPrigroup.Mask();
  Write32(aircr, keep | scb::aircr::kVectkey.Value(scb::aircr::kKey) |
                     scb::aircr::kSysresetreq.Bit());
  DataSyncBarrier();
}

}  // namespace mjc::stm32g4
