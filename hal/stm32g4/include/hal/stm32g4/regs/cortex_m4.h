// The Cortex-M4 core's own registers the drivers and the start-up code use: NVIC, SCB
// (with CPACR, the FPU's access control), DWT's cycle counter and the debug exception
// and monitor control register (DEMCR). They are architectural, not ST's: addresses and
// fields from the ARMv7-M Architecture Reference Manual (ARM DDI 0403E), §B3.2 (system
// control space: SCB, CPACR §B3.2.20), §B3.4 (NVIC), §C1.8 (DWT), §C1.6.5 (DEMCR). The
// vendor SVD does not describe them; the SVD check lists them as unchecked.
//
// The STM32G474 implements 4 priority bits (RM0440 §13.1; the SVD's <nvicPrioBits>,
// which the check compares with kNvicPriorityBits).
#pragma once

#include <array>
#include <utility>

#include "hal/stm32g4/regs/irq.h"
#include "hal/stm32g4/regs/register_table.h"

namespace mjc::stm32g4 {

inline constexpr unsigned kNvicPriorityBits = 4;

namespace nvic {

inline constexpr FieldDef kSetEnaFields[] = {{"SETENA", 0, 32}};
inline constexpr FieldDef kClrEnaFields[] = {{"CLRENA", 0, 32}};
inline constexpr FieldDef kClrPendFields[] = {{"CLRPEND", 0, 32}};
// Four 8-bit priority fields per register; only the top kNvicPriorityBits exist.
inline constexpr FieldDef kIprFields[] = {
    {"PRI_N0", 0, 8}, {"PRI_N1", 8, 8}, {"PRI_N2", 16, 8}, {"PRI_N3", 24, 8}};

// Enough registers for IRQ 0..kIrqCount-1 (ARMv7-M B3.4.3: 32 IRQs per ISER/ICER/ICPR
// word, 4 per IPR word).
inline constexpr RegisterDef kRegisters[] = {
    {"ISER0", 0x000, kSetEnaFields},  {"ISER1", 0x004, kSetEnaFields},
    {"ISER2", 0x008, kSetEnaFields},  {"ISER3", 0x00C, kSetEnaFields},
    {"ICER0", 0x080, kClrEnaFields},  {"ICER1", 0x084, kClrEnaFields},
    {"ICER2", 0x088, kClrEnaFields},  {"ICER3", 0x08C, kClrEnaFields},
    {"ICPR0", 0x180, kClrPendFields}, {"ICPR1", 0x184, kClrPendFields},
    {"ICPR2", 0x188, kClrPendFields}, {"ICPR3", 0x18C, kClrPendFields},
    {"IPR0", 0x300, kIprFields},      {"IPR1", 0x304, kIprFields},
    {"IPR2", 0x308, kIprFields},      {"IPR3", 0x30C, kIprFields},
    {"IPR4", 0x310, kIprFields},      {"IPR5", 0x314, kIprFields},
    {"IPR6", 0x318, kIprFields},      {"IPR7", 0x31C, kIprFields},
    {"IPR8", 0x320, kIprFields},      {"IPR9", 0x324, kIprFields},
    {"IPR10", 0x328, kIprFields},     {"IPR11", 0x32C, kIprFields},
    {"IPR12", 0x330, kIprFields},     {"IPR13", 0x334, kIprFields},
    {"IPR14", 0x338, kIprFields},     {"IPR15", 0x33C, kIprFields},
    {"IPR16", 0x340, kIprFields},     {"IPR17", 0x344, kIprFields},
    {"IPR18", 0x348, kIprFields},     {"IPR19", 0x34C, kIprFields},
    {"IPR20", 0x350, kIprFields},     {"IPR21", 0x354, kIprFields},
    {"IPR22", 0x358, kIprFields},     {"IPR23", 0x35C, kIprFields},
    {"IPR24", 0x360, kIprFields},     {"IPR25", 0x364, kIprFields},
};
inline constexpr BlockDef kBlock{"NVIC", 0xE000E100u, kRegisters, BlockSource::kCortexM4};
static_assert(WellFormed(kBlock));
inline constexpr Address kBase = kBlock.base;
static_assert(4 * 32 >= kIrqCount && 26 * 4 >= kIrqCount);

inline constexpr std::uint32_t kIser0 = OffsetOf(kBlock, "ISER0");
inline constexpr std::uint32_t kIcer0 = OffsetOf(kBlock, "ICER0");
inline constexpr std::uint32_t kIcpr0 = OffsetOf(kBlock, "ICPR0");
inline constexpr std::uint32_t kIpr0 = OffsetOf(kBlock, "IPR0");
// The arrays are contiguous words (checked against the table: the last entries sit
// where the stride says).
static_assert(OffsetOf(kBlock, "ISER3") == kIser0 + 12);
static_assert(OffsetOf(kBlock, "ICER3") == kIcer0 + 12);
static_assert(OffsetOf(kBlock, "ICPR3") == kIcpr0 + 12);
static_assert(OffsetOf(kBlock, "IPR25") == kIpr0 + 100);

// The enable-set / enable-clear / pending-clear word and bit of `irq`.
constexpr std::uint32_t IserOffset(std::uint32_t irq) { return kIser0 + 4 * (irq / 32); }
constexpr std::uint32_t IcerOffset(std::uint32_t irq) { return kIcer0 + 4 * (irq / 32); }
constexpr std::uint32_t IcprOffset(std::uint32_t irq) { return kIcpr0 + 4 * (irq / 32); }
constexpr std::uint32_t IrqBit(std::uint32_t irq) { return 1u << (irq % 32); }
// The priority word of `irq` and the shift of its byte in it.
constexpr std::uint32_t IprOffset(std::uint32_t irq) { return kIpr0 + 4 * (irq / 4); }
constexpr unsigned IprShift(std::uint32_t irq) { return 8 * (irq % 4); }

}  // namespace nvic

namespace scb {

inline constexpr FieldDef kIcsrFields[] = {{"VECTACTIVE", 0, 9}};
inline constexpr FieldDef kVtorFields[] = {{"TBLOFF", 7, 25}};
inline constexpr FieldDef kAircrFields[] = {
    {"VECTRESET", 0, 1}, {"VECTCLRACTIVE", 1, 1}, {"SYSRESETREQ", 2, 1},
    {"PRIGROUP", 8, 3},  {"ENDIANNESS", 15, 1},   {"VECTKEY", 16, 16},
};
inline constexpr FieldDef kCcrFields[] = {
    {"UNALIGN_TRP", 3, 1}, {"DIV_0_TRP", 4, 1}, {"STKALIGN", 9, 1}};
inline constexpr FieldDef kShcsrFields[] = {
    {"MEMFAULTENA", 16, 1}, {"BUSFAULTENA", 17, 1}, {"USGFAULTENA", 18, 1}};
inline constexpr FieldDef kCpacrFields[] = {{"CP10", 20, 2}, {"CP11", 22, 2}};

inline constexpr RegisterDef kRegisters[] = {
    {"ICSR", 0x04, kIcsrFields},   {"VTOR", 0x08, kVtorFields},
    {"AIRCR", 0x0C, kAircrFields}, {"CCR", 0x14, kCcrFields},
    {"SHCSR", 0x24, kShcsrFields}, {"CPACR", 0x88, kCpacrFields},
};
inline constexpr BlockDef kBlock{"SCB", 0xE000ED00u, kRegisters, BlockSource::kCortexM4};
static_assert(WellFormed(kBlock));
inline constexpr Address kBase = kBlock.base;

inline constexpr std::uint32_t kIcsr = OffsetOf(kBlock, "ICSR");
inline constexpr std::uint32_t kVtor = OffsetOf(kBlock, "VTOR");
inline constexpr std::uint32_t kAircr = OffsetOf(kBlock, "AIRCR");
inline constexpr std::uint32_t kCcr = OffsetOf(kBlock, "CCR");
inline constexpr std::uint32_t kShcsr = OffsetOf(kBlock, "SHCSR");
inline constexpr std::uint32_t kCpacr = OffsetOf(kBlock, "CPACR");

namespace icsr {
inline constexpr Field kVectactive = FieldOf(kBlock, "ICSR", "VECTACTIVE");
}  // namespace icsr
namespace aircr {
inline constexpr Field kSysresetreq = FieldOf(kBlock, "AIRCR", "SYSRESETREQ");
inline constexpr Field kPrigroup = FieldOf(kBlock, "AIRCR", "PRIGROUP");
inline constexpr Field kVectkey = FieldOf(kBlock, "AIRCR", "VECTKEY");
// A write without this key is ignored (ARMv7-M B3.2.6).
inline constexpr std::uint32_t kKey = 0x05FAu;
}  // namespace aircr
namespace ccr {
inline constexpr Field kDiv0Trp = FieldOf(kBlock, "CCR", "DIV_0_TRP");
}  // namespace ccr
namespace shcsr {
inline constexpr Field kMemfaultena = FieldOf(kBlock, "SHCSR", "MEMFAULTENA");
inline constexpr Field kBusfaultena = FieldOf(kBlock, "SHCSR", "BUSFAULTENA");
inline constexpr Field kUsgfaultena = FieldOf(kBlock, "SHCSR", "USGFAULTENA");
}  // namespace shcsr
namespace cpacr {
// 11: full access to the coprocessor (CP10 and CP11 together are the FPU).
inline constexpr Field kCp10 = FieldOf(kBlock, "CPACR", "CP10");
inline constexpr Field kCp11 = FieldOf(kBlock, "CPACR", "CP11");
}  // namespace cpacr

}  // namespace scb

namespace dwt {

inline constexpr FieldDef kCtrlFields[] = {{"CYCCNTENA", 0, 1}, {"NOCYCCNT", 25, 1}};
inline constexpr FieldDef kCyccntFields[] = {{"CYCCNT", 0, 32}};
inline constexpr RegisterDef kRegisters[] = {
    {"CTRL", 0x00, kCtrlFields},
    {"CYCCNT", 0x04, kCyccntFields},
};
inline constexpr BlockDef kBlock{"DWT", 0xE0001000u, kRegisters, BlockSource::kCortexM4};
static_assert(WellFormed(kBlock));
inline constexpr Address kBase = kBlock.base;
inline constexpr std::uint32_t kCtrl = OffsetOf(kBlock, "CTRL");
inline constexpr std::uint32_t kCyccnt = OffsetOf(kBlock, "CYCCNT");
namespace ctrl {
inline constexpr Field kCyccntena = FieldOf(kBlock, "CTRL", "CYCCNTENA");
}  // namespace ctrl

}  // namespace dwt

// The debug control block's DEMCR (ARMv7-M C1.6.5): TRCENA powers DWT and ITM.
namespace dcb {

inline constexpr FieldDef kDemcrFields[] = {{"TRCENA", 24, 1}};
inline constexpr RegisterDef kRegisters[] = {{"DEMCR", 0x0C, kDemcrFields}};
inline constexpr BlockDef kBlock{"CoreDebug", 0xE000EDF0u, kRegisters,
                                 BlockSource::kCortexM4};
static_assert(WellFormed(kBlock));
inline constexpr Address kBase = kBlock.base;
inline constexpr std::uint32_t kDemcr = OffsetOf(kBlock, "DEMCR");
namespace demcr {
inline constexpr Field kTrcena = FieldOf(kBlock, "DEMCR", "TRCENA");
}  // namespace demcr

}  // namespace dcb

// The memory protection unit (ARMv7-M B3.5; the Cortex-M4's has 8 regions, TRM §4.2):
// MPU_TYPE (DREGION: how many regions, 0 without an MPU), MPU_CTRL, the region number
// register and the selected region's base address and attribute/size registers.
namespace mpu {

inline constexpr FieldDef kTypeFields[] = {{"SEPARATE", 0, 1}, {"DREGION", 8, 8}};
inline constexpr FieldDef kCtrlFields[] = {
    {"ENABLE", 0, 1},
    {"HFNMIENA", 1, 1},    // the MPU also during HardFault/NMI/FAULTMASK handlers
    {"PRIVDEFENA", 2, 1},  // privileged accesses outside every region: the default map
};
inline constexpr FieldDef kRnrFields[] = {{"REGION", 0, 8}};
inline constexpr FieldDef kRbarFields[] = {
    {"REGION", 0, 4}, {"VALID", 4, 1}, {"ADDR", 5, 27}};
inline constexpr FieldDef kRasrFields[] = {
    {"ENABLE", 0, 1},  // the region takes part
    {"SIZE", 1, 5},    // 2^(SIZE+1) bytes, SIZE ≥ 4 (32 B); the base aligned to it
    {"SRD", 8, 8},     // subregion disables
    {"B", 16, 1},     {"C", 17, 1},  {"S", 18, 1},
    {"TEX", 19, 3},   {"AP", 24, 3},  // 000: no access, privileged or not
    {"XN", 28, 1},                    // no instruction fetch
};
inline constexpr RegisterDef kRegisters[] = {
    {"TYPE", 0x00, kTypeFields}, {"CTRL", 0x04, kCtrlFields}, {"RNR", 0x08, kRnrFields},
    {"RBAR", 0x0C, kRbarFields}, {"RASR", 0x10, kRasrFields},
};
inline constexpr BlockDef kBlock{"MPU", 0xE000ED90u, kRegisters, BlockSource::kCortexM4};
static_assert(WellFormed(kBlock));
inline constexpr Address kBase = kBlock.base;
inline constexpr std::uint32_t kType = OffsetOf(kBlock, "TYPE");
inline constexpr std::uint32_t kCtrl = OffsetOf(kBlock, "CTRL");
inline constexpr std::uint32_t kRnr = OffsetOf(kBlock, "RNR");
inline constexpr std::uint32_t kRbar = OffsetOf(kBlock, "RBAR");
inline constexpr std::uint32_t kRasr = OffsetOf(kBlock, "RASR");
namespace type {
inline constexpr Field kDregion = FieldOf(kBlock, "TYPE", "DREGION");
}  // namespace type
namespace ctrl {
inline constexpr Field kEnable = FieldOf(kBlock, "CTRL", "ENABLE");
inline constexpr Field kPrivdefena = FieldOf(kBlock, "CTRL", "PRIVDEFENA");
}  // namespace ctrl
namespace rnr {
inline constexpr Field kRegion = FieldOf(kBlock, "RNR", "REGION");
}  // namespace rnr
namespace rasr {
inline constexpr Field kEnable = FieldOf(kBlock, "RASR", "ENABLE");
inline constexpr Field kSize = FieldOf(kBlock, "RASR", "SIZE");
inline constexpr Field kAp = FieldOf(kBlock, "RASR", "AP");
inline constexpr Field kXn = FieldOf(kBlock, "RASR", "XN");
inline constexpr Field kC = FieldOf(kBlock, "RASR", "C");
}  // namespace rasr

}  // namespace mpu

}  // namespace mjc::stm32g4
