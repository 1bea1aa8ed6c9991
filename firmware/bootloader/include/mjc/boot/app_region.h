// The application region of a board's flash, the only flash the bootloader writes:
// every erase and program names an offset from the region's start (its header) and is
// refused, touching nothing, when it falls outside. The bootloader's own pages, the
// identity and the calibration pages lie outside by construction (BootLayout), and on
// the G474 the flash driver's write window (Stm32g4Flash) refuses them a second time.
#pragma once

#include <cstdint>
#include <span>

#include "hal/flash.h"
#include "mjc/boot/layout.h"
#include "mjc/protocol/messages.h"

namespace mjc::boot {

class AppRegion {
 public:
  AppRegion(hal::Flash* flash, const BootLayout& layout)
      : flash_(flash), layout_(layout) {}

  std::uint32_t size() const { return layout_.RegionBytes(); }
  const BootLayout& layout() const { return layout_; }

  // Erases the page holding region offset `offset`.
  protocol::BootError ErasePageAt(std::uint32_t offset);
  // Programs the double-word at `offset` (8-aligned, erased: hal::Flash's rules).
  protocol::BootError Program(std::uint32_t offset, std::uint64_t value);
  // Reads `out.size()` bytes from `offset`, across pages.
  protocol::BootError Read(std::uint32_t offset, std::span<std::uint8_t> out) const;

 private:
  hal::Flash* flash_;
  BootLayout layout_;
};

}  // namespace mjc::boot
