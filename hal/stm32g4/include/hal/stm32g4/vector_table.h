// The STM32G474's vector table, built at compile time from the IRQ table (regs/irq.h):
// position 0 is the initial stack pointer, 1..15 the Cortex-M4 system exceptions
// (ARMv7-M B1.5.2), 16 + IRQn the peripheral interrupts (RM0440 §13.3). A handler is
// placed by its IRQ number, never by counting lines, and every position without one
// gets the default handler. The same builder prints the layout the SVD check compares
// (svd_dump instantiates it with names for handlers).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <utility>

#include "hal/stm32g4/regs/irq.h"

namespace mjc::stm32g4 {

inline constexpr std::size_t kVectorCount = 16 + kIrqCount;

template <class Handler>
struct SystemHandlers {
  Handler reset;
  Handler nmi;
  Handler hard_fault;
  Handler mem_manage;
  Handler bus_fault;
  Handler usage_fault;
  Handler svcall;
  Handler debug_monitor;
  Handler pendsv;
  Handler systick;
};

template <class Handler>
struct IrqHandler {
  std::uint8_t irq;  // IRQn, from regs/irq.h
  Handler handler;
};

// Positions 1..kVectorCount-1 (position 0, the stack pointer, is the caller's). Reserved
// system positions (7..10, 13) hold `reserved`. An IRQ named twice or out of range makes
// the build fail where the table is constant-initialised.
template <class Handler, std::size_t kN>
constexpr std::array<Handler, kVectorCount - 1> BuildVectorTable(
    const SystemHandlers<Handler>& system, Handler default_irq, Handler reserved,
    const std::array<IrqHandler<Handler>, kN>& irqs) {
  std::array<Handler, kVectorCount - 1> table{};
  // Index i holds vector position i + 1.
  table[0] = system.reset;
  table[1] = system.nmi;
  table[2] = system.hard_fault;
  table[3] = system.mem_manage;
  table[4] = system.bus_fault;
  table[5] = system.usage_fault;
  for (std::size_t p = 7; p <= 10; ++p) table[p - 1] = reserved;
  table[10] = system.svcall;
  table[11] = system.debug_monitor;
  table[12] = reserved;
  table[13] = system.pendsv;
  table[14] = system.systick;
  for (std::size_t p = 16; p < kVectorCount; ++p) table[p - 1] = default_irq;
  std::array<bool, kIrqCount> placed{};
  for (const IrqHandler<Handler>& h : irqs) {
    if (h.irq >= kIrqCount || placed[h.irq]) regs_detail::RegisterOrFieldNotInTable();
    placed[h.irq] = true;
    table[16 + h.irq - 1] = h.handler;
  }
  return table;
}

}  // namespace mjc::stm32g4
