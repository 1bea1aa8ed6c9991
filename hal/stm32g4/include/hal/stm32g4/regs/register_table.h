// The form of every register definition the drivers use: per peripheral a constexpr
// table (base address; registers with their offset; fields with name, bit position and
// width), and compile-time lookups that turn a (register, field) name pair into the
// constant a driver writes with:
//
//   Write32(kTim + tim1::kCr1, tim1::cr1::kCms.Value(1) | tim1::cr1::kCen.Bit());
//
// A Field can only be made by FieldOf() (its constructor is private), and FieldOf() is
// consteval: naming a register or field that is not in the table does not compile. So
// every field a driver touches is a table entry, and the SVD check (svd_dump + the
// checker in hal/stm32g4/svd/) sees all of them by construction.
//
// Names follow ST's SVD v2.9 where it differs from RM0440's text (e.g. FLASH_CR.START
// for the manual's STRT); each table says where.
#pragma once

#include <cstdint>
#include <span>
#include <string_view>

#include "hal/stm32g4/mmio.h"

namespace mjc::stm32g4 {

struct FieldDef {
  std::string_view name;
  std::uint8_t position;  // lowest bit
  std::uint8_t width;     // bits, 1..32
};

struct RegisterDef {
  std::string_view name;
  std::uint32_t offset;  // bytes from the block's base
  std::span<const FieldDef> fields;
};

// Where a block's definition comes from, and so how the SVD check treats it.
enum class BlockSource : std::uint8_t {
  kVendorSvd = 0,  // an STM32G474 peripheral: checked against ST's SVD
  kCortexM4 = 1,   // a Cortex-M4 core block (ARMv7-M ARM): the SVD does not describe it
};

struct BlockDef {
  std::string_view name;  // the SVD's peripheral name (GPIOA, TIM1, FDCAN1, ...)
  Address base;
  std::span<const RegisterDef> registers;
  BlockSource source = BlockSource::kVendorSvd;
};

namespace regs_detail {
// Reached only when a lookup fails. Not constexpr: a failing consteval lookup is a
// compile error whose message names this function.
inline void RegisterOrFieldNotInTable() {}
}  // namespace regs_detail

class Field {
 public:
  constexpr unsigned position() const { return position_; }
  constexpr unsigned width() const { return width_; }
  // The field's bits in place.
  constexpr std::uint32_t Mask() const { return LowMask() << position_; }
  // A one-bit field, set. (A wider field's Bit() does not compile where it is a
  // constant expression; elsewhere it is its lowest bit.)
  constexpr std::uint32_t Bit() const {
    if (width_ != 1) regs_detail::RegisterOrFieldNotInTable();
    return 1u << position_;
  }
  // `value` in place; bits of `value` beyond the field's width are dropped.
  constexpr std::uint32_t Value(std::uint32_t value) const {
    return (value & LowMask()) << position_;
  }
  // The field's value read from a whole register word.
  constexpr std::uint32_t Get(std::uint32_t word) const {
    return (word >> position_) & LowMask();
  }
  constexpr bool IsSet(std::uint32_t word) const { return (word & Mask()) != 0; }
  // `word` with this field replaced by `value`.
  constexpr std::uint32_t With(std::uint32_t word, std::uint32_t value) const {
    return (word & ~Mask()) | Value(value);
  }

 private:
  constexpr Field(std::uint8_t position, std::uint8_t width)
      : position_(position), width_(width) {}
  constexpr std::uint32_t LowMask() const {
    return width_ >= 32 ? 0xFFFFFFFFu : ((1u << width_) - 1u);
  }

  friend consteval Field FieldOf(const BlockDef& block, std::string_view reg,
                                 std::string_view field);
  friend constexpr Field FieldAt(const BlockDef& block, std::string_view reg,
                                 std::size_t index);

  std::uint8_t position_;
  std::uint8_t width_;
};

constexpr const RegisterDef& RegisterOf(const BlockDef& block, std::string_view reg) {
  for (const RegisterDef& r : block.registers) {
    if (r.name == reg) return r;
  }
  regs_detail::RegisterOrFieldNotInTable();
  return block.registers.front();
}

// The offset of `reg` in `block`.
consteval std::uint32_t OffsetOf(const BlockDef& block, std::string_view reg) {
  return RegisterOf(block, reg).offset;
}

// The field `field` of register `reg` in `block`.
consteval Field FieldOf(const BlockDef& block, std::string_view reg,
                        std::string_view field) {
  for (const FieldDef& f : RegisterOf(block, reg).fields) {
    if (f.name == field) return Field(f.position, f.width);
  }
  regs_detail::RegisterOrFieldNotInTable();
  return Field(0, 1);
}

// The index-th field of `reg` as the table lists it (for per-pin fields, which the
// tables list in pin order; see gpio.h). Still only a table's field; constexpr rather
// than consteval so that consteval builders of field arrays can call it.
constexpr Field FieldAt(const BlockDef& block, std::string_view reg, std::size_t index) {
  const RegisterDef& r = RegisterOf(block, reg);
  if (index >= r.fields.size()) regs_detail::RegisterOrFieldNotInTable();
  return Field(r.fields[index].position, r.fields[index].width);
}

// Layout sanity every table must pass (asserted in each header): fields inside 32 bits,
// no two fields of a register overlapping, and registers word-aligned.
constexpr bool WellFormed(const BlockDef& block) {
  for (const RegisterDef& r : block.registers) {
    if (r.offset % 4 != 0) return false;
    std::uint64_t used = 0;
    for (const FieldDef& f : r.fields) {
      if (f.width == 0 || f.position + f.width > 32) return false;
      const std::uint64_t bits = ((std::uint64_t{1} << f.width) - 1u) << f.position;
      if ((used & bits) != 0) return false;
      used |= bits;
    }
  }
  return true;
}

}  // namespace mjc::stm32g4
