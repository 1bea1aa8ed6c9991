// Flash memory as the STM32G4 has it (RM0440 §5): 2 KB pages; erasing a page sets every
// byte to 0xFF; programming writes one 64-bit double-word at an 8-byte-aligned offset
// and only into an erased double-word (the ECC of a written double-word cannot be
// rewritten); reads are plain. A slow device behind a small virtual interface (called
// from the main loop, never from the control tick).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

namespace mjc::hal {

// Stable codes.
enum class FlashResult : std::uint8_t {
  kOk = 0,
  kBadAddress = 1,     // page or offset outside the device, or offset not 8-aligned
  kNotErased = 2,      // programming a double-word that is not all 0xFF
  kHardwareError = 3,  // the controller reported an error (or power failed)
};

class Flash {
 public:
  static constexpr std::size_t kPageSize = 2048;
  static constexpr std::size_t kDoubleWord = 8;

  virtual ~Flash() = default;

  FlashResult ErasePage(std::uint32_t page) { return DoErasePage(page); }
  FlashResult ProgramDoubleWord(std::uint32_t page, std::uint32_t offset,
                                std::uint64_t value) {
    return DoProgram(page, offset, value);
  }
  FlashResult Read(std::uint32_t page, std::uint32_t offset,
                   std::span<std::uint8_t> out) const {
    return DoRead(page, offset, out);
  }
  std::uint32_t page_count() const { return DoPageCount(); }

 private:
  virtual FlashResult DoErasePage(std::uint32_t page) = 0;
  virtual FlashResult DoProgram(std::uint32_t page, std::uint32_t offset,
                                std::uint64_t value) = 0;
  virtual FlashResult DoRead(std::uint32_t page, std::uint32_t offset,
                             std::span<std::uint8_t> out) const = 0;
  virtual std::uint32_t DoPageCount() const = 0;
};

}  // namespace mjc::hal
