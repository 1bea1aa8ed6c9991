// PWR: power control (RM0440 §6.4). Range 1 boost mode for 170 MHz.
#pragma once

#include "hal/stm32g4/regs/register_table.h"

namespace mjc::stm32g4::pwr {

inline constexpr FieldDef kCr1Fields[] = {
    {"VOS", 9, 2},  // voltage range: 01 = Range 1 (reset value), 10 = Range 2
};
inline constexpr FieldDef kSr2Fields[] = {
    {"VOSF", 10, 1},  // 1 while the regulator is reaching a new voltage level
};
inline constexpr FieldDef kCr5Fields[] = {
    {"R1MODE", 8, 1},  // 0 = Range 1 boost (reset value 1 = Range 1 normal)
};
inline constexpr RegisterDef kRegisters[] = {
    {"CR1", 0x00, kCr1Fields},
    {"SR2", 0x14, kSr2Fields},
    {"CR5", 0x80, kCr5Fields},
};

inline constexpr BlockDef kBlock{"PWR", 0x40007000u, kRegisters};
static_assert(WellFormed(kBlock));
inline constexpr Address kBase = kBlock.base;

inline constexpr std::uint32_t kCr1 = OffsetOf(kBlock, "CR1");
inline constexpr std::uint32_t kSr2 = OffsetOf(kBlock, "SR2");
inline constexpr std::uint32_t kCr5 = OffsetOf(kBlock, "CR5");

namespace cr1 {
inline constexpr Field kVos = FieldOf(kBlock, "CR1", "VOS");
}  // namespace cr1
namespace sr2 {
inline constexpr Field kVosf = FieldOf(kBlock, "SR2", "VOSF");
}  // namespace sr2
namespace cr5 {
inline constexpr Field kR1mode = FieldOf(kBlock, "CR5", "R1MODE");
}  // namespace cr5

}  // namespace mjc::stm32g4::pwr
