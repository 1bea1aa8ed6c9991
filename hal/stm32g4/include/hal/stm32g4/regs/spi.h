// SPI1 (RM0440 §39.6, "SPI registers"). The frame size is CR2.DS (4..16 bits); the SVD
// still lists CR1 bit 11 as DFF, which this chip does not use.
#pragma once

#include "hal/stm32g4/regs/register_table.h"

namespace mjc::stm32g4::spi1 {

inline constexpr FieldDef kCr1Fields[] = {
    {"CPHA", 0, 1}, {"CPOL", 1, 1},
    {"MSTR", 2, 1}, {"BR", 3, 3},  // f_PCLK / 2^(BR+1)
    {"SPE", 6, 1},  {"LSBFIRST", 7, 1},
    {"SSI", 8, 1},  {"SSM", 9, 1},
};
inline constexpr FieldDef kCr2Fields[] = {
    {"SSOE", 2, 1},
    {"DS", 8, 4},      // frame bits - 1 (1111: 16 bits)
    {"FRXTH", 12, 1},  // 0: RXNE at 16 bits in the RX FIFO
};
inline constexpr FieldDef kSrFields[] = {
    {"RXNE", 0, 1}, {"TXE", 1, 1},   {"OVR", 6, 1},
    {"BSY", 7, 1},  {"FRLVL", 9, 2}, {"FTLVL", 11, 2},
};
inline constexpr FieldDef kDrFields[] = {{"DR", 0, 16}};

inline constexpr RegisterDef kRegisters[] = {
    {"CR1", 0x00, kCr1Fields},
    {"CR2", 0x04, kCr2Fields},
    {"SR", 0x08, kSrFields},
    {"DR", 0x0C, kDrFields},
};

inline constexpr BlockDef kBlock{"SPI1", 0x40013000u, kRegisters};
static_assert(WellFormed(kBlock));
inline constexpr Address kBase = kBlock.base;

inline constexpr std::uint32_t kCr1 = OffsetOf(kBlock, "CR1");
inline constexpr std::uint32_t kCr2 = OffsetOf(kBlock, "CR2");
inline constexpr std::uint32_t kSr = OffsetOf(kBlock, "SR");
inline constexpr std::uint32_t kDr = OffsetOf(kBlock, "DR");

namespace cr1 {
inline constexpr Field kCpha = FieldOf(kBlock, "CR1", "CPHA");
inline constexpr Field kCpol = FieldOf(kBlock, "CR1", "CPOL");
inline constexpr Field kMstr = FieldOf(kBlock, "CR1", "MSTR");
inline constexpr Field kBr = FieldOf(kBlock, "CR1", "BR");
inline constexpr Field kSpe = FieldOf(kBlock, "CR1", "SPE");
inline constexpr Field kSsi = FieldOf(kBlock, "CR1", "SSI");
inline constexpr Field kSsm = FieldOf(kBlock, "CR1", "SSM");
}  // namespace cr1
namespace cr2 {
inline constexpr Field kDs = FieldOf(kBlock, "CR2", "DS");
inline constexpr Field kFrxth = FieldOf(kBlock, "CR2", "FRXTH");
}  // namespace cr2
namespace sr {
inline constexpr Field kRxne = FieldOf(kBlock, "SR", "RXNE");
inline constexpr Field kTxe = FieldOf(kBlock, "SR", "TXE");
inline constexpr Field kOvr = FieldOf(kBlock, "SR", "OVR");
inline constexpr Field kBsy = FieldOf(kBlock, "SR", "BSY");
inline constexpr Field kFrlvl = FieldOf(kBlock, "SR", "FRLVL");
}  // namespace sr
namespace dr {
inline constexpr Field kDr = FieldOf(kBlock, "DR", "DR");
}  // namespace dr

}  // namespace mjc::stm32g4::spi1
