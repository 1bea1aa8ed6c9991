// DBGMCU, the MCU debug component (RM0440 "Debug support (DBG)", DBGMCU registers): the
// freeze bits that stop a peripheral's counter while a debugger holds the core halted.
// Register names as ST's SVD spells them (CMSIS stm32g474xx.h: APB1FZR1, APB2FZ). The
// registers belong to the debug domain: only a power-on reset clears them.
#pragma once

#include "hal/stm32g4/regs/register_table.h"

namespace mjc::stm32g4::dbgmcu {

inline constexpr FieldDef kApb1lFzFields[] = {
    {"DBG_TIM3_STOP", 1, 1},   // TIM3's counter stops while the core is halted
    {"DBG_IWDG_STOP", 12, 1},  // the IWDG's counter stops while the core is halted
};
inline constexpr FieldDef kApb2FzFields[] = {
    // TIM1's counter stops and its outputs are disabled as if MOE were cleared.
    {"DBG_TIM1_STOP", 11, 1},
};

inline constexpr RegisterDef kRegisters[] = {
    {"APB1L_FZ", 0x08, kApb1lFzFields},
    {"APB2_FZ", 0x10, kApb2FzFields},
};

inline constexpr BlockDef kBlock{"DBGMCU", 0xE0042000u, kRegisters};
static_assert(WellFormed(kBlock));
inline constexpr Address kBase = kBlock.base;

inline constexpr std::uint32_t kApb1lFz = OffsetOf(kBlock, "APB1L_FZ");
inline constexpr std::uint32_t kApb2Fz = OffsetOf(kBlock, "APB2_FZ");

namespace apb1l_fz {
inline constexpr Field kDbgTim3Stop = FieldOf(kBlock, "APB1L_FZ", "DBG_TIM3_STOP");
inline constexpr Field kDbgIwdgStop = FieldOf(kBlock, "APB1L_FZ", "DBG_IWDG_STOP");
}  // namespace apb1l_fz
namespace apb2_fz {
inline constexpr Field kDbgTim1Stop = FieldOf(kBlock, "APB2_FZ", "DBG_TIM1_STOP");
}  // namespace apb2_fz

}  // namespace mjc::stm32g4::dbgmcu
