// IWDG, the independent watchdog (RM0440 §42.4).
#pragma once

#include "hal/stm32g4/regs/register_table.h"

namespace mjc::stm32g4::iwdg {

inline constexpr FieldDef kKrFields[] = {{"KEY", 0, 16}};
inline constexpr FieldDef kPrFields[] = {{"PR", 0, 3}};    // /4 × 2^PR (/4 .. /256)
inline constexpr FieldDef kRlrFields[] = {{"RL", 0, 12}};  // reload value
inline constexpr FieldDef kSrFields[] = {
    {"PVU", 0, 1},  // a PR update is still propagating to the LSI domain
    {"RVU", 1, 1},  // an RLR update is
    {"WVU", 2, 1},  // a WINR update is
};

inline constexpr RegisterDef kRegisters[] = {
    {"KR", 0x00, kKrFields},
    {"PR", 0x04, kPrFields},
    {"RLR", 0x08, kRlrFields},
    {"SR", 0x0C, kSrFields},
};

inline constexpr BlockDef kBlock{"IWDG", 0x40003000u, kRegisters};
static_assert(WellFormed(kBlock));
inline constexpr Address kBase = kBlock.base;

inline constexpr std::uint32_t kKr = OffsetOf(kBlock, "KR");
inline constexpr std::uint32_t kPr = OffsetOf(kBlock, "PR");
inline constexpr std::uint32_t kRlr = OffsetOf(kBlock, "RLR");
inline constexpr std::uint32_t kSr = OffsetOf(kBlock, "SR");

namespace kr {
inline constexpr Field kKey = FieldOf(kBlock, "KR", "KEY");
// RM0440 §42.3.2: 0xCCCC starts the watchdog (and the LSI), 0x5555 unlocks PR/RLR/WINR,
// 0xAAAA reloads the counter from RLR.
inline constexpr std::uint32_t kStart = 0xCCCCu;
inline constexpr std::uint32_t kUnlock = 0x5555u;
inline constexpr std::uint32_t kReload = 0xAAAAu;
}  // namespace kr
namespace pr {
inline constexpr Field kPr = FieldOf(kBlock, "PR", "PR");
}  // namespace pr
namespace rlr {
inline constexpr Field kRl = FieldOf(kBlock, "RLR", "RL");
}  // namespace rlr
namespace sr {
inline constexpr Field kPvu = FieldOf(kBlock, "SR", "PVU");
inline constexpr Field kRvu = FieldOf(kBlock, "SR", "RVU");
}  // namespace sr

}  // namespace mjc::stm32g4::iwdg
