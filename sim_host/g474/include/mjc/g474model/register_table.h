// The registers of a model that need no code of their own, as a table: where each one
// sits in the block, the member that stores it and how software's accesses act on it,
// in RM0440's own access types (rw, r, rc_w1, rc_w0, a fixed value). A model's Read and
// Write handle the registers with side effects (a flag computed from the state, a key
// sequence, a check that reports a violation) in code and pass every other offset to
// ReadTableRegister / WriteTableRegister with the model's table.
//
// The table names members by pointer-to-member, so it lives in a private static member
// function of the model (one table for both directions, the writable masks beside the
// offsets, as the manual lists them).
#pragma once

#include <cstdint>
#include <span>

#include "mjc/g474model/common.h"

namespace mjc::g474model {

// How the bits of a table register answer software (RM0440 "Register description"
// access types).
enum class RegisterAccess : std::uint8_t {
  kReadWrite,        // rw: reads the stored value, writes the `writable` bits
  kReadOnly,         // r: reads the stored value, ignores writes
  kFixed,            // no storage: reads `fixed` (write-only, reserved or ID values)
  kClearByWriting1,  // rc_w1: a written 1 clears the bit (of `writable`), 0 leaves it
  kClearByWriting0,  // rc_w0: a written 0 clears the bit (of `writable`), 1 leaves it
};

template <class Model>
struct Register {
  using Field = std::uint32_t Model::*;

  std::uint32_t offset = 0;
  Field field = nullptr;
  std::uint32_t writable = 0xFFFFFFFFu;
  RegisterAccess access = RegisterAccess::kReadWrite;
  std::uint32_t fixed = 0;

  static constexpr Register ReadWrite(std::uint32_t offset, Field field,
                                      std::uint32_t writable = 0xFFFFFFFFu) {
    return {offset, field, writable, RegisterAccess::kReadWrite, 0};
  }
  static constexpr Register ReadOnly(std::uint32_t offset, Field field) {
    return {offset, field, 0, RegisterAccess::kReadOnly, 0};
  }
  // Reads `value` and ignores writes.
  static constexpr Register Fixed(std::uint32_t offset, std::uint32_t value = 0) {
    return {offset, nullptr, 0, RegisterAccess::kFixed, value};
  }
  static constexpr Register ClearByWriting1(std::uint32_t offset, Field field,
                                            std::uint32_t clearable = 0xFFFFFFFFu) {
    return {offset, field, clearable, RegisterAccess::kClearByWriting1, 0};
  }
  static constexpr Register ClearByWriting0(std::uint32_t offset, Field field,
                                            std::uint32_t clearable = 0xFFFFFFFFu) {
    return {offset, field, clearable, RegisterAccess::kClearByWriting0, 0};
  }
};

template <class Model>
using RegisterTable = std::span<const Register<Model>>;

// The table's entry for `offset`, or null (a model's blocks have a few dozen registers:
// a scan is as quick as a search).
template <class Model>
const Register<Model>* FindRegister(RegisterTable<Model> table, std::uint32_t offset) {
  for (const Register<Model>& r : table) {
    if (r.offset == offset) return &r;
  }
  return nullptr;
}

// Reads the table's register at `offset` into `*value`; false when the table has none.
template <class Model>
bool ReadTableRegister(RegisterTable<Model> table, const Model& model,
                       std::uint32_t offset, std::uint32_t* value) {
  const Register<Model>* r = FindRegister(table, offset);
  if (r == nullptr) return false;
  *value = r->access == RegisterAccess::kFixed ? r->fixed : model.*(r->field);
  return true;
}

// Writes the access to the table's register at its offset; false when the table has
// none.
template <class Model>
bool WriteTableRegister(RegisterTable<Model> table, Model& model, const Access& a) {
  const Register<Model>* r = FindRegister(table, a.offset);
  if (r == nullptr) return false;
  switch (r->access) {
    case RegisterAccess::kReadWrite:
      a.Apply(&(model.*(r->field)), r->writable);
      break;
    case RegisterAccess::kClearByWriting1:
      model.*(r->field) &= ~(a.value & a.mask & r->writable);
      break;
    case RegisterAccess::kClearByWriting0:
      model.*(r->field) &= ~(~a.value & a.mask & r->writable);
      break;
    case RegisterAccess::kReadOnly:
    case RegisterAccess::kFixed:
      break;
  }
  return true;
}

}  // namespace mjc::g474model
