// The STM32G474's flash as hal::Flash (RM0440 §5, FLASH): 512 KB in dual-bank mode
// (FLASH_OPTR.DBANK = 1, the factory setting), two banks of 128 pages of 2 KB.
//
// hal page p (0..255) is the 2 KB at 0x0800_0000 + p × 2 KB: bank p / 128, page p % 128
// in its bank (FLASH_CR.BKER, PNB). Erase and program are allowed only in a window of
// pages given at construction (the linker script's calibration pages), so no caller can
// erase the running program; reads are allowed anywhere in the main memory.
//
// The window lies in bank 2 and the program runs from bank 1: the dual-bank flash reads
// one bank while the other is erased or programmed (read-while-write, RM0440 §5.3
// "Read-while-write"), so the CPU does not stall meanwhile — but the calls below wait for
// the operation (an erase takes up to ~40 ms): main-loop context only.
//
// Reads go through the register access layer (mmio.h), so on the host they reach the
// bound model of the flash array like every other access.
//
// ECC: a double word whose erase or program was cut by a power loss or a reset holds
// data that do not match its ECC; reading it sets FLASH_ECCR.ECCD and raises the NMI
// (RM0440 §5.3). Each image's NMI handler calls HandleFlashEccNmi, which records the
// error and clears ECCD; a Read (or the erased-check before a program) during which
// one was recorded fails with kHardwareError instead of the board resetting — a
// reset would read the same double word again at the next start, forever.
#pragma once

#include <cstdint>
#include <span>

#include "hal/flash.h"
#include "hal/stm32g4/mmio.h"

namespace mjc::stm32g4 {

// For the NMI handler: when FLASH_ECCR.ECCD is set, records the failing double word's
// address (from ADDR_ECC and BK_ECC), clears ECCD and returns true; false when the NMI
// had another cause (the handler then stops the board as for a fault).
bool HandleFlashEccNmi();
// ECC double errors recorded since reset, and the last one's bus address.
std::uint32_t FlashEccErrors();
std::uint32_t LastFlashEccAddress();

class Stm32g4Flash final : public hal::Flash {
 public:
  static constexpr std::uint32_t kPagesPerBank = 128;
  static constexpr std::uint32_t kPages = 2 * kPagesPerBank;

  // Pages [first_writable, first_writable + writable_count) may be erased and programmed.
  constexpr Stm32g4Flash(std::uint32_t first_writable, std::uint32_t writable_count)
      : first_writable_(first_writable), writable_count_(writable_count) {}

  // Checks the geometry this driver is written for: dual-bank mode and a 512 KB device.
  // Until it has returned true every erase and program answers kHardwareError.
  bool Init();

  // The bus address of byte `offset` of hal page `page`.
  static constexpr Address PageAddress(std::uint32_t page) {
    return 0x08000000u + page * static_cast<std::uint32_t>(kPageSize);
  }

 private:
  hal::FlashResult DoErasePage(std::uint32_t page) override;
  hal::FlashResult DoProgram(std::uint32_t page, std::uint32_t offset,
                             std::uint64_t value) override;
  hal::FlashResult DoRead(std::uint32_t page, std::uint32_t offset,
                          std::span<std::uint8_t> out) const override;
  std::uint32_t DoPageCount() const override { return kPages; }

  bool Writable(std::uint32_t page) const {
    return geometry_ok_ && page >= first_writable_ &&
           page - first_writable_ < writable_count_ && page < kPages;
  }

  std::uint32_t first_writable_;
  std::uint32_t writable_count_;
  bool geometry_ok_ = false;
};

}  // namespace mjc::stm32g4
