// The bootloader's target test on QEMU's mps2-an386: the board's layout with the code
// memory at 0 standing for flash (linker/mps2_an386_bootloader.ld, mps2_an386_app.ld),
// and a read-only hal::Flash over it (QEMU's code memory is RAM; this test writes
// nothing: the update itself is proven on the host).
#pragma once

#include <cstdint>
#include <span>

#include "hal/flash.h"
#include "mjc/boot/layout.h"

namespace mjc::boot::qemu {

// The board's pages and regions (kG474Layout) with flash at 0 and the stacks in QEMU's
// 4 MB of SRAM.
inline constexpr BootLayout kQemuLayout = [] {
  BootLayout layout = kG474Layout;
  layout.flash_base = 0x00000000u;
  layout.stack_ranges = {{{0x20000000u, 0x20400000u}, {0x20000000u, 0x20400000u}}};
  return layout;
}();
static_assert(kQemuLayout.RegionAddress() == 0x4000u);
static_assert(kQemuLayout.ImageAddress() == 0x4200u);

class MappedFlash final : public hal::Flash {
 private:
  hal::FlashResult DoErasePage(std::uint32_t) override {
    return hal::FlashResult::kHardwareError;
  }
  hal::FlashResult DoProgram(std::uint32_t, std::uint32_t, std::uint64_t) override {
    return hal::FlashResult::kHardwareError;
  }
  hal::FlashResult DoRead(std::uint32_t page, std::uint32_t offset,
                          std::span<std::uint8_t> out) const override {
    if (page < kQemuLayout.app_first_page || page >= 256 || offset > kPageSize ||
        out.size() > kPageSize - offset) {
      return hal::FlashResult::kBadAddress;
    }
    const std::uintptr_t at = kQemuLayout.flash_base + page * kPageSize + offset;
    for (std::size_t i = 0; i < out.size(); ++i) {
      out[i] = *reinterpret_cast<const volatile std::uint8_t*>(at + i);
    }
    return hal::FlashResult::kOk;
  }
  std::uint32_t DoPageCount() const override { return 256; }
};

// A line of output built without newlib's stdio (which these images do not link).
class Line {
 public:
  Line& operator<<(const char* text) {
    while (*text != '\0' && n_ + 1 < sizeof buffer_) buffer_[n_++] = *text++;
    buffer_[n_] = '\0';
    return *this;
  }
  Line& Dec(std::uint32_t v) {
    char digits[11];
    int k = 0;
    do {
      digits[k++] = static_cast<char>('0' + v % 10);
      v /= 10;
    } while (v != 0);
    while (k > 0 && n_ + 1 < sizeof buffer_) buffer_[n_++] = digits[--k];
    buffer_[n_] = '\0';
    return *this;
  }
  Line& Hex(std::uint32_t v) {
    *this << "0x";
    for (int shift = 28; shift >= 0; shift -= 4) {
      const char c[2] = {"0123456789ABCDEF"[(v >> shift) & 0xFu], '\0'};
      *this << c;
    }
    return *this;
  }
  const char* c_str() const { return buffer_; }

 private:
  char buffer_[256] = {};
  std::size_t n_ = 0;
};

}  // namespace mjc::boot::qemu
