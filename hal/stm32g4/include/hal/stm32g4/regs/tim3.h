// TIM3, a general-purpose 16-bit timer counting the motor's quadrature encoder (RM0440
// §29.5, "TIM2/TIM3/TIM4/TIM5 registers"). CCMR1 is listed in its input-capture view.
// SMCR bit 16 is SMS[3] in RM0440; the SVD v2.9 names it SMS_1.
#pragma once

#include "hal/stm32g4/regs/register_table.h"

namespace mjc::stm32g4::tim3 {

inline constexpr FieldDef kCr1Fields[] = {
    {"CEN", 0, 1},
    {"CKD", 8, 2},  // tDTS = tCK_INT × 2^CKD: the input filters' sampling base
};
inline constexpr FieldDef kSmcrFields[] = {
    {"SMS", 0, 3},     // SMS[2:0]
    {"SMS_1", 16, 1},  // SMS[3]
};
inline constexpr FieldDef kEgrFields[] = {{"UG", 0, 1}};
inline constexpr FieldDef kCcmr1Fields[] = {
    {"CC1S", 0, 2}, {"IC1PSC", 2, 2},  {"IC1F", 4, 4},
    {"CC2S", 8, 2}, {"IC2PSC", 10, 2}, {"IC2F", 12, 4},
};
inline constexpr FieldDef kCcerFields[] = {
    {"CC1E", 0, 1}, {"CC1P", 1, 1}, {"CC1NP", 3, 1},
    {"CC2E", 4, 1}, {"CC2P", 5, 1}, {"CC2NP", 7, 1},
};
inline constexpr FieldDef kCntFields[] = {{"CNT", 0, 16}};
inline constexpr FieldDef kPscFields[] = {{"PSC", 0, 16}};
// 20 bits: the low 4 are the dithering fraction with CR1.DITHEN = 1 (off here).
inline constexpr FieldDef kArrFields[] = {{"ARR", 0, 20}};

inline constexpr RegisterDef kRegisters[] = {
    {"CR1", 0x00, kCr1Fields},     {"SMCR", 0x08, kSmcrFields}, {"EGR", 0x14, kEgrFields},
    {"CCMR1", 0x18, kCcmr1Fields}, {"CCER", 0x20, kCcerFields}, {"CNT", 0x24, kCntFields},
    {"PSC", 0x28, kPscFields},     {"ARR", 0x2C, kArrFields},
};

inline constexpr BlockDef kBlock{"TIM3", 0x40000400u, kRegisters};
static_assert(WellFormed(kBlock));
inline constexpr Address kBase = kBlock.base;

inline constexpr std::uint32_t kCr1 = OffsetOf(kBlock, "CR1");
inline constexpr std::uint32_t kSmcr = OffsetOf(kBlock, "SMCR");
inline constexpr std::uint32_t kEgr = OffsetOf(kBlock, "EGR");
inline constexpr std::uint32_t kCcmr1 = OffsetOf(kBlock, "CCMR1");
inline constexpr std::uint32_t kCcer = OffsetOf(kBlock, "CCER");
inline constexpr std::uint32_t kCnt = OffsetOf(kBlock, "CNT");
inline constexpr std::uint32_t kPsc = OffsetOf(kBlock, "PSC");
inline constexpr std::uint32_t kArr = OffsetOf(kBlock, "ARR");

namespace cr1 {
inline constexpr Field kCen = FieldOf(kBlock, "CR1", "CEN");
inline constexpr Field kCkd = FieldOf(kBlock, "CR1", "CKD");
}  // namespace cr1
namespace smcr {
inline constexpr Field kSms = FieldOf(kBlock, "SMCR", "SMS");
inline constexpr Field kSms3 = FieldOf(kBlock, "SMCR", "SMS_1");
}  // namespace smcr
namespace egr {
inline constexpr Field kUg = FieldOf(kBlock, "EGR", "UG");
}  // namespace egr
namespace ccmr1 {
inline constexpr Field kCc1s = FieldOf(kBlock, "CCMR1", "CC1S");
inline constexpr Field kIc1f = FieldOf(kBlock, "CCMR1", "IC1F");
inline constexpr Field kCc2s = FieldOf(kBlock, "CCMR1", "CC2S");
inline constexpr Field kIc2f = FieldOf(kBlock, "CCMR1", "IC2F");
}  // namespace ccmr1
namespace ccer {
inline constexpr Field kCc1p = FieldOf(kBlock, "CCER", "CC1P");
inline constexpr Field kCc1np = FieldOf(kBlock, "CCER", "CC1NP");
inline constexpr Field kCc2p = FieldOf(kBlock, "CCER", "CC2P");
inline constexpr Field kCc2np = FieldOf(kBlock, "CCER", "CC2NP");
}  // namespace ccer
namespace cnt {
inline constexpr Field kCnt = FieldOf(kBlock, "CNT", "CNT");
}  // namespace cnt
namespace psc {
inline constexpr Field kPsc = FieldOf(kBlock, "PSC", "PSC");
}  // namespace psc
namespace arr {
inline constexpr Field kArr = FieldOf(kBlock, "ARR", "ARR");
}  // namespace arr

}  // namespace mjc::stm32g4::tim3
