// DBGMCU of the STM32G474 (RM0440 "Debug support (DBG)", DBGMCU registers; offsets,
// fields and reset values from ST's SVD v2.9 and the CMSIS header stm32g474xx.h):
// IDCODE (DEV_ID 0x469, the STM32G47x/G48x), CR (low-power debug, trace), APB1FZR1,
// APB1FZR2 and APB2FZR, the freeze bits that decide what the peripherals do while a
// debugger holds the core halted. The bits this board's firmware and the virtual chip
// act on:
//   APB1FZR1 bit 1  DBG_TIM3_STOP   TIM3's counter stops while the core is halted
//   APB1FZR1 bit 12 DBG_IWDG_STOP   the IWDG's counter stops while the core is halted
//   APB2FZR  bit 11 DBG_TIM1_STOP   TIM1's counter stops and its outputs are disabled as
//                                   if MOE were cleared (RM0440 TIM1 "Debug mode")
// The others are stored and read back (nothing else they freeze is modelled). The
// registers belong to the debug domain: a system reset (IWDG, SYSRESETREQ, NRST) leaves
// them as they are, only a power-on reset clears them (RM0440 DBGMCU, "reset by POR").
//
// Not covered: DEV_ID/REV_ID of other parts (REV_ID reads 0), the low-power debug
// bits' effect (the chip models no Stop/Standby), trace pin assignment.
#pragma once

#include <cstdint>

#include "mjc/g474model/common.h"
#include "mjc/g474model/register_table.h"

namespace mjc::g474model {

class Dbgmcu final : public Peripheral {
 public:
  static constexpr std::uint32_t kBase = 0xE0042000;
  static constexpr std::uint32_t kDevId = 0x469;
  static constexpr std::uint32_t kTim3Stop = 1u << 1, kIwdgStop = 1u << 12;
  static constexpr std::uint32_t kTim1Stop = 1u << 11;

  Dbgmcu() { PowerOn(); }

  bool Read(const Access& a, std::uint32_t* value) override;
  bool Write(const Access& a) override;
  // A system reset: the debug domain keeps its registers.
  void Reset() override {}
  // A power-on reset: every register to its reset value (0).
  void PowerOn() { cr_ = apb1fzr1_ = apb1fzr2_ = apb2fzr_ = 0; }

  bool iwdg_stop() const { return (apb1fzr1_ & kIwdgStop) != 0; }
  bool tim1_stop() const { return (apb2fzr_ & kTim1Stop) != 0; }
  bool tim3_stop() const { return (apb1fzr1_ & kTim3Stop) != 0; }

 private:
  static RegisterTable<Dbgmcu> Registers();

  std::uint32_t cr_ = 0, apb1fzr1_ = 0, apb1fzr2_ = 0, apb2fzr_ = 0;
};

}  // namespace mjc::g474model
