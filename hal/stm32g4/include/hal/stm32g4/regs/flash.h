// FLASH: the embedded flash interface (RM0440 §5.7) and the flash array's geometry
// (§5.3.1, dual-bank mode: DBANK = 1 gives two banks of 2 KB pages).
// SVD v2.9 names CR bit 16 START and SR bit 8 MISSERR (RM0440: STRT, MISERR).
#pragma once

#include "hal/stm32g4/regs/register_table.h"

namespace mjc::stm32g4::flash {

inline constexpr FieldDef kAcrFields[] = {
    {"LATENCY", 0, 4},  // wait states
    {"PRFTEN", 8, 1},  {"ICEN", 9, 1},   {"DCEN", 10, 1},
    {"ICRST", 11, 1},  {"DCRST", 12, 1},
};
inline constexpr FieldDef kKeyrFields[] = {{"KEYR", 0, 32}};
inline constexpr FieldDef kSrFields[] = {
    {"EOP", 0, 1},     {"OPERR", 1, 1},  {"PROGERR", 3, 1},  {"WRPERR", 4, 1},
    {"PGAERR", 5, 1},  {"SIZERR", 6, 1}, {"PGSERR", 7, 1},   {"MISSERR", 8, 1},
    {"FASTERR", 9, 1}, {"RDERR", 14, 1}, {"OPTVERR", 15, 1}, {"BSY", 16, 1},
};
inline constexpr FieldDef kCrFields[] = {
    {"PG", 0, 1},    {"PER", 1, 1},    {"MER1", 2, 1},  {"PNB", 3, 7},
    {"BKER", 11, 1}, {"START", 16, 1}, {"LOCK", 31, 1},
};
inline constexpr FieldDef kEccrFields[] = {
    {"ADDR_ECC", 0, 19}, {"BK_ECC", 21, 1}, {"SYSF_ECC", 22, 1}, {"ECCCIE", 24, 1},
    {"ECCD2", 29, 1},    {"ECCC", 30, 1},   {"ECCD", 31, 1},
};
inline constexpr FieldDef kOptrFields[] = {
    {"DBANK", 22, 1},  // 1: dual bank, 2 KB pages
};
inline constexpr RegisterDef kRegisters[] = {
    {"ACR", 0x00, kAcrFields}, {"KEYR", 0x08, kKeyrFields}, {"SR", 0x10, kSrFields},
    {"CR", 0x14, kCrFields},   {"OPTR", 0x20, kOptrFields}, {"ECCR", 0x18, kEccrFields},
};

inline constexpr BlockDef kBlock{"FLASH", 0x40022000u, kRegisters};
static_assert(WellFormed(kBlock));
inline constexpr Address kBase = kBlock.base;

inline constexpr std::uint32_t kAcr = OffsetOf(kBlock, "ACR");
inline constexpr std::uint32_t kKeyr = OffsetOf(kBlock, "KEYR");
inline constexpr std::uint32_t kSr = OffsetOf(kBlock, "SR");
inline constexpr std::uint32_t kCr = OffsetOf(kBlock, "CR");
inline constexpr std::uint32_t kOptr = OffsetOf(kBlock, "OPTR");
inline constexpr std::uint32_t kEccr = OffsetOf(kBlock, "ECCR");

namespace acr {
inline constexpr Field kLatency = FieldOf(kBlock, "ACR", "LATENCY");
inline constexpr Field kPrften = FieldOf(kBlock, "ACR", "PRFTEN");
inline constexpr Field kIcen = FieldOf(kBlock, "ACR", "ICEN");
inline constexpr Field kDcen = FieldOf(kBlock, "ACR", "DCEN");
inline constexpr Field kIcrst = FieldOf(kBlock, "ACR", "ICRST");
inline constexpr Field kDcrst = FieldOf(kBlock, "ACR", "DCRST");
}  // namespace acr
namespace keyr {
inline constexpr Field kKeyr = FieldOf(kBlock, "KEYR", "KEYR");
// The unlock sequence (RM0440 §5.3.5 "Flash program and erase operations", unlocking
// the FLASH_CR register): KEY1 then KEY2; any other write locks FLASH_CR until reset.
inline constexpr std::uint32_t kKey1 = 0x45670123u;
inline constexpr std::uint32_t kKey2 = 0xCDEF89ABu;
}  // namespace keyr
namespace sr {
inline constexpr Field kEop = FieldOf(kBlock, "SR", "EOP");
inline constexpr Field kOperr = FieldOf(kBlock, "SR", "OPERR");
inline constexpr Field kProgerr = FieldOf(kBlock, "SR", "PROGERR");
inline constexpr Field kWrperr = FieldOf(kBlock, "SR", "WRPERR");
inline constexpr Field kPgaerr = FieldOf(kBlock, "SR", "PGAERR");
inline constexpr Field kSizerr = FieldOf(kBlock, "SR", "SIZERR");
inline constexpr Field kPgserr = FieldOf(kBlock, "SR", "PGSERR");
inline constexpr Field kMiserr = FieldOf(kBlock, "SR", "MISSERR");
inline constexpr Field kFasterr = FieldOf(kBlock, "SR", "FASTERR");
inline constexpr Field kRderr = FieldOf(kBlock, "SR", "RDERR");
inline constexpr Field kOptverr = FieldOf(kBlock, "SR", "OPTVERR");
inline constexpr Field kBsy = FieldOf(kBlock, "SR", "BSY");
// Every error flag of a program or erase (write 1 to clear).
inline constexpr std::uint32_t kProgramErrors =
    kOperr.Bit() | kProgerr.Bit() | kWrperr.Bit() | kPgaerr.Bit() | kSizerr.Bit() |
    kPgserr.Bit() | kMiserr.Bit() | kFasterr.Bit() | kRderr.Bit() | kOptverr.Bit();
}  // namespace sr
namespace cr {
inline constexpr Field kPg = FieldOf(kBlock, "CR", "PG");
inline constexpr Field kPer = FieldOf(kBlock, "CR", "PER");
inline constexpr Field kPnb = FieldOf(kBlock, "CR", "PNB");
inline constexpr Field kBker = FieldOf(kBlock, "CR", "BKER");
inline constexpr Field kStrt = FieldOf(kBlock, "CR", "START");
inline constexpr Field kLock = FieldOf(kBlock, "CR", "LOCK");
}  // namespace cr
// ECC (RM0440 §5.3 "Error code correction (ECC)"): a read that finds two wrong bits in
// a double word sets ECCD and raises the NMI; ADDR_ECC (the double word's offset in its
// bank) and BK_ECC keep the first error until ECCD/ECCC are cleared by writing 1.
namespace eccr {
inline constexpr Field kAddrEcc = FieldOf(kBlock, "ECCR", "ADDR_ECC");
inline constexpr Field kBkEcc = FieldOf(kBlock, "ECCR", "BK_ECC");
inline constexpr Field kSysfEcc = FieldOf(kBlock, "ECCR", "SYSF_ECC");
inline constexpr Field kEcccie = FieldOf(kBlock, "ECCR", "ECCCIE");
inline constexpr Field kEccc = FieldOf(kBlock, "ECCR", "ECCC");
inline constexpr Field kEccd = FieldOf(kBlock, "ECCR", "ECCD");
// The SVD also lists ECCD2 (a detection flag of its own, cleared by writing 1); the NMI
// handler treats it as ECCD, so whichever flag a double error sets, the handler takes it
// instead of the reset a DefaultHandler would make of it.
inline constexpr Field kEccd2 = FieldOf(kBlock, "ECCR", "ECCD2");
}  // namespace eccr
namespace optr {
inline constexpr Field kDbank = FieldOf(kBlock, "OPTR", "DBANK");
}  // namespace optr

// The flash array (RM0440 §5.3.1, Table "Flash module - 512 KB dual bank organization"):
// main memory from 0x0800_0000; in dual-bank mode bank 2 starts at half the device's
// size (0x0804_0000 on 512 KB parts) and both banks have 2 KB pages.
inline constexpr Address kMainMemory = 0x08000000u;
inline constexpr std::uint32_t kDualBankPageBytes = 2048;
// The device's flash size in KB, a 16-bit word in the engineering bytes (RM0440 §48.2
// "Flash size data register").
inline constexpr Address kFlashSizeRegister = 0x1FFF75E0u;

}  // namespace mjc::stm32g4::flash
