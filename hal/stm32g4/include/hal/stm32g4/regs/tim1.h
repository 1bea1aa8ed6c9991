// TIM1, the advanced-control timer driving the H-bridge (RM0440 §28.6, "TIM1/TIM8/TIM20
// registers"). CCMR1 is listed in its output-compare view (the SVD describes it as the
// alternate of the input-capture view at the same offset).
#pragma once

#include "hal/stm32g4/regs/register_table.h"

namespace mjc::stm32g4::tim1 {

inline constexpr FieldDef kCr1Fields[] = {
    {"CEN", 0, 1},  {"UDIS", 1, 1}, {"URS", 2, 1},
    {"OPM", 3, 1},  {"DIR", 4, 1},  {"CMS", 5, 2},  // 01: centre-aligned mode 1
    {"ARPE", 7, 1}, {"CKD", 8, 2},                  // tDTS = tCK_INT × 2^CKD
};
inline constexpr FieldDef kCr2Fields[] = {
    // Output idle states with MOE = 0 (after the dead time), RM0440 §28.6.2.
    {"OIS1", 8, 1},
    {"OIS1N", 9, 1},
    {"OIS2", 10, 1},
    {"OIS2N", 11, 1},
};
inline constexpr FieldDef kDierFields[] = {{"UIE", 0, 1}};
inline constexpr FieldDef kSrFields[] = {{"UIF", 0, 1}};
inline constexpr FieldDef kEgrFields[] = {{"UG", 0, 1}};
inline constexpr FieldDef kCcmr1Fields[] = {
    {"CC1S", 0, 2},
    {"OC1FE", 2, 1},
    {"OC1PE", 3, 1},
    {"OC1M", 4, 3},
    {"CC2S", 8, 2},
    {"OC2FE", 10, 1},
    {"OC2PE", 11, 1},
    {"OC2M", 12, 3},
    // OCxM[3] (RM0440), which the SVD v2.9 names OCxM_1.
    {"OC1M_1", 16, 1},
    {"OC2M_1", 24, 1},
};
inline constexpr FieldDef kCcerFields[] = {
    {"CC1E", 0, 1}, {"CC1P", 1, 1}, {"CC1NE", 2, 1}, {"CC1NP", 3, 1},
    {"CC2E", 4, 1}, {"CC2P", 5, 1}, {"CC2NE", 6, 1}, {"CC2NP", 7, 1},
};
inline constexpr FieldDef kCntFields[] = {{"CNT", 0, 16}};
inline constexpr FieldDef kPscFields[] = {{"PSC", 0, 16}};
// ARR and CCRx are 20 bits: with CR1.DITHEN = 1 the low 4 bits are the dithering
// fraction (RM0440 §28.3, "Dithering"). Dithering stays off here, so values are the
// plain 16-bit counts.
inline constexpr FieldDef kArrFields[] = {{"ARR", 0, 20}};
inline constexpr FieldDef kRcrFields[] = {{"REP", 0, 16}};
inline constexpr FieldDef kCcr1Fields[] = {{"CCR1", 0, 20}};
inline constexpr FieldDef kCcr2Fields[] = {{"CCR2", 0, 20}};
inline constexpr FieldDef kBdtrFields[] = {
    {"DTG", 0, 8},  {"LOCK", 8, 2}, {"OSSI", 10, 1}, {"OSSR", 11, 1},
    {"BKE", 12, 1}, {"BKP", 13, 1}, {"AOE", 14, 1},  {"MOE", 15, 1},
};

inline constexpr RegisterDef kRegisters[] = {
    {"CR1", 0x00, kCr1Fields},   {"CR2", 0x04, kCr2Fields},
    {"DIER", 0x0C, kDierFields}, {"SR", 0x10, kSrFields},
    {"EGR", 0x14, kEgrFields},   {"CCMR1", 0x18, kCcmr1Fields},
    {"CCER", 0x20, kCcerFields}, {"CNT", 0x24, kCntFields},
    {"PSC", 0x28, kPscFields},   {"ARR", 0x2C, kArrFields},
    {"RCR", 0x30, kRcrFields},   {"CCR1", 0x34, kCcr1Fields},
    {"CCR2", 0x38, kCcr2Fields}, {"BDTR", 0x44, kBdtrFields},
};

inline constexpr BlockDef kBlock{"TIM1", 0x40012C00u, kRegisters};
static_assert(WellFormed(kBlock));
inline constexpr Address kBase = kBlock.base;

inline constexpr std::uint32_t kCr1 = OffsetOf(kBlock, "CR1");
inline constexpr std::uint32_t kCr2 = OffsetOf(kBlock, "CR2");
inline constexpr std::uint32_t kDier = OffsetOf(kBlock, "DIER");
inline constexpr std::uint32_t kSr = OffsetOf(kBlock, "SR");
inline constexpr std::uint32_t kEgr = OffsetOf(kBlock, "EGR");
inline constexpr std::uint32_t kCcmr1 = OffsetOf(kBlock, "CCMR1");
inline constexpr std::uint32_t kCcer = OffsetOf(kBlock, "CCER");
inline constexpr std::uint32_t kCnt = OffsetOf(kBlock, "CNT");
inline constexpr std::uint32_t kPsc = OffsetOf(kBlock, "PSC");
inline constexpr std::uint32_t kArr = OffsetOf(kBlock, "ARR");
inline constexpr std::uint32_t kRcr = OffsetOf(kBlock, "RCR");
inline constexpr std::uint32_t kCcr1 = OffsetOf(kBlock, "CCR1");
inline constexpr std::uint32_t kCcr2 = OffsetOf(kBlock, "CCR2");
inline constexpr std::uint32_t kBdtr = OffsetOf(kBlock, "BDTR");

namespace cr1 {
inline constexpr Field kCen = FieldOf(kBlock, "CR1", "CEN");
inline constexpr Field kUrs = FieldOf(kBlock, "CR1", "URS");
inline constexpr Field kCms = FieldOf(kBlock, "CR1", "CMS");
inline constexpr Field kArpe = FieldOf(kBlock, "CR1", "ARPE");
inline constexpr Field kCkd = FieldOf(kBlock, "CR1", "CKD");
}  // namespace cr1
namespace cr2 {
inline constexpr Field kOis1 = FieldOf(kBlock, "CR2", "OIS1");
inline constexpr Field kOis1n = FieldOf(kBlock, "CR2", "OIS1N");
inline constexpr Field kOis2 = FieldOf(kBlock, "CR2", "OIS2");
inline constexpr Field kOis2n = FieldOf(kBlock, "CR2", "OIS2N");
}  // namespace cr2
namespace dier {
inline constexpr Field kUie = FieldOf(kBlock, "DIER", "UIE");
}  // namespace dier
namespace sr {
inline constexpr Field kUif = FieldOf(kBlock, "SR", "UIF");
}  // namespace sr
namespace egr {
inline constexpr Field kUg = FieldOf(kBlock, "EGR", "UG");
}  // namespace egr
namespace ccmr1 {
inline constexpr Field kCc1s = FieldOf(kBlock, "CCMR1", "CC1S");
inline constexpr Field kOc1pe = FieldOf(kBlock, "CCMR1", "OC1PE");
inline constexpr Field kOc1m = FieldOf(kBlock, "CCMR1", "OC1M");
inline constexpr Field kOc1m3 = FieldOf(kBlock, "CCMR1", "OC1M_1");
inline constexpr Field kCc2s = FieldOf(kBlock, "CCMR1", "CC2S");
inline constexpr Field kOc2pe = FieldOf(kBlock, "CCMR1", "OC2PE");
inline constexpr Field kOc2m = FieldOf(kBlock, "CCMR1", "OC2M");
inline constexpr Field kOc2m3 = FieldOf(kBlock, "CCMR1", "OC2M_1");
}  // namespace ccmr1
namespace ccer {
inline constexpr Field kCc1e = FieldOf(kBlock, "CCER", "CC1E");
inline constexpr Field kCc1p = FieldOf(kBlock, "CCER", "CC1P");
inline constexpr Field kCc1ne = FieldOf(kBlock, "CCER", "CC1NE");
inline constexpr Field kCc1np = FieldOf(kBlock, "CCER", "CC1NP");
inline constexpr Field kCc2e = FieldOf(kBlock, "CCER", "CC2E");
inline constexpr Field kCc2p = FieldOf(kBlock, "CCER", "CC2P");
inline constexpr Field kCc2ne = FieldOf(kBlock, "CCER", "CC2NE");
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
namespace rcr {
inline constexpr Field kRep = FieldOf(kBlock, "RCR", "REP");
}  // namespace rcr
namespace ccr1 {
inline constexpr Field kCcr1 = FieldOf(kBlock, "CCR1", "CCR1");
}  // namespace ccr1
namespace ccr2 {
inline constexpr Field kCcr2 = FieldOf(kBlock, "CCR2", "CCR2");
}  // namespace ccr2
namespace bdtr {
inline constexpr Field kDtg = FieldOf(kBlock, "BDTR", "DTG");
inline constexpr Field kLock = FieldOf(kBlock, "BDTR", "LOCK");
inline constexpr Field kOssi = FieldOf(kBlock, "BDTR", "OSSI");
inline constexpr Field kOssr = FieldOf(kBlock, "BDTR", "OSSR");
inline constexpr Field kMoe = FieldOf(kBlock, "BDTR", "MOE");
}  // namespace bdtr

}  // namespace mjc::stm32g4::tim1
