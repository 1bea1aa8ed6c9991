// A register space for driver tests: it records every access in order and answers
// reads from what was last written, unless the test's rules say what the hardware would
// answer at that point (a ready bit after an enable, a status word). The expectations
// in the tests are written from the reference manual, independently of the drivers'
// register tables.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <vector>

#include "hal/stm32g4/mmio.h"

namespace mjc::stm32g4::testing {

struct Access {
  bool write = false;
  Address address = 0;
  std::uint32_t value = 0;
  unsigned bytes = 4;
};

inline constexpr Address kCyccntAddress = 0xE0001004u;

class ScriptedSpace : public RegisterSpace {
 public:
  ScriptedSpace() { BindRegisterSpace(this); }
  ~ScriptedSpace() override { BindRegisterSpace(nullptr); }
  ScriptedSpace(const ScriptedSpace&) = delete;
  ScriptedSpace& operator=(const ScriptedSpace&) = delete;

  std::uint32_t Read(Address address, unsigned bytes) override {
    std::uint32_t value = 0;
    if (address == kCyccntAddress) {
      cycles += cycles_per_read;
      value = cycles;
    } else if (auto answer = on_read ? on_read(address) : std::nullopt) {
      value = *answer;
    } else {
      value = Peek(address);
    }
    log.push_back({false, address, value, bytes});
    return value;
  }
  void Write(Address address, std::uint32_t value, unsigned bytes) override {
    log.push_back({true, address, value, bytes});
    memory[address] = value;
    if (after_write) after_write(address, value);
  }

  std::uint32_t Peek(Address address) const {
    const auto it = memory.find(address);
    return it == memory.end() ? 0u : it->second;
  }

  // The writes to `address`, in order.
  std::vector<std::uint32_t> WritesTo(Address address) const {
    std::vector<std::uint32_t> out;
    for (const Access& a : log) {
      if (a.write && a.address == address) out.push_back(a.value);
    }
    return out;
  }
  // Index in the log of the first write to `address` whose value satisfies `match`, at
  // or after `from`; -1 when there is none.
  long FirstWrite(Address address, const std::function<bool(std::uint32_t)>& match,
                  long from = 0) const {
    for (std::size_t i = static_cast<std::size_t>(from); i < log.size(); ++i) {
      if (log[i].write && log[i].address == address && match(log[i].value)) {
        return static_cast<long>(i);
      }
    }
    return -1;
  }
  long CountWritesIn(Address first, Address last) const {
    long n = 0;
    for (const Access& a : log) n += (a.write && a.address >= first && a.address <= last);
    return n;
  }

  std::vector<Access> log;
  std::map<Address, std::uint32_t> memory;
  std::function<std::optional<std::uint32_t>(Address)> on_read;
  std::function<void(Address, std::uint32_t)> after_write;
  std::uint32_t cycles = 0;
  std::uint32_t cycles_per_read = 10;
};

inline auto Any() {
  return [](std::uint32_t) { return true; };
}
inline auto Equals(std::uint32_t v) {
  return [v](std::uint32_t x) { return x == v; };
}
inline auto HasBits(std::uint32_t bits) {
  return [bits](std::uint32_t x) { return (x & bits) == bits; };
}
inline auto LacksBits(std::uint32_t bits) {
  return [bits](std::uint32_t x) { return (x & bits) == 0; };
}

}  // namespace mjc::stm32g4::testing
