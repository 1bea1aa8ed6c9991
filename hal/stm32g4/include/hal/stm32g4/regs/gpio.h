// GPIO ports A..G (RM0440 §9.4). One layout for every port; the tables list the
// per-pin fields in pin order, so PinFields() can index them by pin number.
#pragma once

#include <array>
#include <utility>

#include "hal/stm32g4/regs/register_table.h"

namespace mjc::stm32g4::gpio {

inline constexpr FieldDef kModerFields[] = {
    {"MODER0", 0, 2},   {"MODER1", 2, 2},   {"MODER2", 4, 2},   {"MODER3", 6, 2},
    {"MODER4", 8, 2},   {"MODER5", 10, 2},  {"MODER6", 12, 2},  {"MODER7", 14, 2},
    {"MODER8", 16, 2},  {"MODER9", 18, 2},  {"MODER10", 20, 2}, {"MODER11", 22, 2},
    {"MODER12", 24, 2}, {"MODER13", 26, 2}, {"MODER14", 28, 2}, {"MODER15", 30, 2},
};
inline constexpr FieldDef kOtyperFields[] = {
    {"OT0", 0, 1},   {"OT1", 1, 1},   {"OT2", 2, 1},   {"OT3", 3, 1},
    {"OT4", 4, 1},   {"OT5", 5, 1},   {"OT6", 6, 1},   {"OT7", 7, 1},
    {"OT8", 8, 1},   {"OT9", 9, 1},   {"OT10", 10, 1}, {"OT11", 11, 1},
    {"OT12", 12, 1}, {"OT13", 13, 1}, {"OT14", 14, 1}, {"OT15", 15, 1},
};
inline constexpr FieldDef kOspeedrFields[] = {
    {"OSPEEDR0", 0, 2},   {"OSPEEDR1", 2, 2},   {"OSPEEDR2", 4, 2},
    {"OSPEEDR3", 6, 2},   {"OSPEEDR4", 8, 2},   {"OSPEEDR5", 10, 2},
    {"OSPEEDR6", 12, 2},  {"OSPEEDR7", 14, 2},  {"OSPEEDR8", 16, 2},
    {"OSPEEDR9", 18, 2},  {"OSPEEDR10", 20, 2}, {"OSPEEDR11", 22, 2},
    {"OSPEEDR12", 24, 2}, {"OSPEEDR13", 26, 2}, {"OSPEEDR14", 28, 2},
    {"OSPEEDR15", 30, 2},
};
inline constexpr FieldDef kPupdrFields[] = {
    {"PUPDR0", 0, 2},   {"PUPDR1", 2, 2},   {"PUPDR2", 4, 2},   {"PUPDR3", 6, 2},
    {"PUPDR4", 8, 2},   {"PUPDR5", 10, 2},  {"PUPDR6", 12, 2},  {"PUPDR7", 14, 2},
    {"PUPDR8", 16, 2},  {"PUPDR9", 18, 2},  {"PUPDR10", 20, 2}, {"PUPDR11", 22, 2},
    {"PUPDR12", 24, 2}, {"PUPDR13", 26, 2}, {"PUPDR14", 28, 2}, {"PUPDR15", 30, 2},
};
inline constexpr FieldDef kIdrFields[] = {
    {"IDR0", 0, 1},   {"IDR1", 1, 1},   {"IDR2", 2, 1},   {"IDR3", 3, 1},
    {"IDR4", 4, 1},   {"IDR5", 5, 1},   {"IDR6", 6, 1},   {"IDR7", 7, 1},
    {"IDR8", 8, 1},   {"IDR9", 9, 1},   {"IDR10", 10, 1}, {"IDR11", 11, 1},
    {"IDR12", 12, 1}, {"IDR13", 13, 1}, {"IDR14", 14, 1}, {"IDR15", 15, 1},
};
inline constexpr FieldDef kBsrrFields[] = {
    {"BS0", 0, 1},   {"BS1", 1, 1},   {"BS2", 2, 1},   {"BS3", 3, 1},   {"BS4", 4, 1},
    {"BS5", 5, 1},   {"BS6", 6, 1},   {"BS7", 7, 1},   {"BS8", 8, 1},   {"BS9", 9, 1},
    {"BS10", 10, 1}, {"BS11", 11, 1}, {"BS12", 12, 1}, {"BS13", 13, 1}, {"BS14", 14, 1},
    {"BS15", 15, 1}, {"BR0", 16, 1},  {"BR1", 17, 1},  {"BR2", 18, 1},  {"BR3", 19, 1},
    {"BR4", 20, 1},  {"BR5", 21, 1},  {"BR6", 22, 1},  {"BR7", 23, 1},  {"BR8", 24, 1},
    {"BR9", 25, 1},  {"BR10", 26, 1}, {"BR11", 27, 1}, {"BR12", 28, 1}, {"BR13", 29, 1},
    {"BR14", 30, 1}, {"BR15", 31, 1},
};
inline constexpr FieldDef kAfrlFields[] = {
    {"AFRL0", 0, 4},  {"AFRL1", 4, 4},  {"AFRL2", 8, 4},  {"AFRL3", 12, 4},
    {"AFRL4", 16, 4}, {"AFRL5", 20, 4}, {"AFRL6", 24, 4}, {"AFRL7", 28, 4},
};
inline constexpr FieldDef kAfrhFields[] = {
    {"AFRH8", 0, 4},   {"AFRH9", 4, 4},   {"AFRH10", 8, 4},  {"AFRH11", 12, 4},
    {"AFRH12", 16, 4}, {"AFRH13", 20, 4}, {"AFRH14", 24, 4}, {"AFRH15", 28, 4},
};

inline constexpr RegisterDef kRegisters[] = {
    {"MODER", 0x00, kModerFields},      // 00 input, 01 output, 10 alternate, 11 analog
    {"OTYPER", 0x04, kOtyperFields},    // 0 push-pull, 1 open drain
    {"OSPEEDR", 0x08, kOspeedrFields},  // 00 low .. 11 very high
    {"PUPDR", 0x0C, kPupdrFields},      // 00 none, 01 pull-up, 10 pull-down
    {"IDR", 0x10, kIdrFields},
    {"BSRR", 0x18, kBsrrFields},  // write-only: BSn sets, BRn resets, atomically
    {"AFRL", 0x20, kAfrlFields},  // alternate function of pins 0..7
    {"AFRH", 0x24, kAfrhFields},  // of pins 8..15
};

// Port index 0 = A .. 6 = G; ports are 0x400 apart from 0x4800_0000 (RM0440 §2.2.2,
// memory map).
inline constexpr BlockDef kBlocks[] = {
    {"GPIOA", 0x48000000u, kRegisters}, {"GPIOB", 0x48000400u, kRegisters},
    {"GPIOC", 0x48000800u, kRegisters}, {"GPIOD", 0x48000C00u, kRegisters},
    {"GPIOE", 0x48001000u, kRegisters}, {"GPIOF", 0x48001400u, kRegisters},
    {"GPIOG", 0x48001800u, kRegisters},
};
static_assert(WellFormed(kBlocks[0]));
inline constexpr std::size_t kPortCount = std::size(kBlocks);

// The ports' bases alone, for indexing at run time (indexing kBlocks itself would put
// the whole description, names included, into the image).
inline constexpr std::array<Address, kPortCount> kPortBases = [] {
  std::array<Address, kPortCount> bases{};
  for (std::size_t i = 0; i < kPortCount; ++i) bases[i] = kBlocks[i].base;
  return bases;
}();

inline constexpr std::uint32_t kModer = OffsetOf(kBlocks[0], "MODER");
inline constexpr std::uint32_t kOtyper = OffsetOf(kBlocks[0], "OTYPER");
inline constexpr std::uint32_t kOspeedr = OffsetOf(kBlocks[0], "OSPEEDR");
inline constexpr std::uint32_t kPupdr = OffsetOf(kBlocks[0], "PUPDR");
inline constexpr std::uint32_t kIdr = OffsetOf(kBlocks[0], "IDR");
inline constexpr std::uint32_t kBsrr = OffsetOf(kBlocks[0], "BSRR");
inline constexpr std::uint32_t kAfrl = OffsetOf(kBlocks[0], "AFRL");
inline constexpr std::uint32_t kAfrh = OffsetOf(kBlocks[0], "AFRH");

// The fields of `reg` from table index `first_index` on, each checked to sit where
// pin i's field must (position = first_bit + i × width): an index is a pin number.
template <std::size_t... kI>
consteval std::array<Field, sizeof...(kI)> PinFieldsOf(std::string_view reg,
                                                       unsigned first_bit,
                                                       std::size_t first_index,
                                                       std::index_sequence<kI...>) {
  const std::array<Field, sizeof...(kI)> out{
      FieldAt(kBlocks[0], reg, first_index + kI)...};
  for (std::size_t i = 0; i < out.size(); ++i) {
    if (out[i].position() != first_bit + i * out[i].width()) {
      regs_detail::RegisterOrFieldNotInTable();
    }
  }
  return out;
}
template <std::size_t kCount>
consteval std::array<Field, kCount> PinFields(std::string_view reg, unsigned first_bit,
                                              std::size_t first_index = 0) {
  return PinFieldsOf(reg, first_bit, first_index, std::make_index_sequence<kCount>{});
}

inline constexpr auto kMode = PinFields<16>("MODER", 0);
inline constexpr auto kOt = PinFields<16>("OTYPER", 0);
inline constexpr auto kOspeed = PinFields<16>("OSPEEDR", 0);
inline constexpr auto kPupd = PinFields<16>("PUPDR", 0);
inline constexpr auto kId = PinFields<16>("IDR", 0);
inline constexpr auto kBs = PinFields<16>("BSRR", 0);
inline constexpr auto kBr = PinFields<16>("BSRR", 16, 16);
inline constexpr auto kAfl = PinFields<8>("AFRL", 0);  // pins 0..7
inline constexpr auto kAfh = PinFields<8>("AFRH", 0);  // pins 8..15

}  // namespace mjc::stm32g4::gpio
