// Where things are in a board's flash and RAM, as the bootloader needs them: the
// application region (its header page first), the identity pages, and where an
// image's initial stack pointer may point. One constant per board (kG474Layout here,
// the QEMU test board's in its own folder); the linker scripts assert the same numbers.
#pragma once

#include <array>
#include <cstdint>

#include "hal/flash.h"
#include "mjc/boot/image_header.h"

namespace mjc::boot {

struct AddressRange {
  std::uint32_t begin = 0;  // first byte
  std::uint32_t end = 0;    // one past the last byte
};

struct BootLayout {
  std::uint32_t flash_base = 0;      // bus address of hal::Flash page 0
  std::uint32_t app_first_page = 0;  // the application region: the header's page first
  std::uint32_t app_pages = 0;
  std::uint32_t identity_page_a = 0;  // the board identity record's pages
  std::uint32_t identity_page_b = 0;
  // RAM an image's initial stack pointer may point into (its top included).
  std::array<AddressRange, 2> stack_ranges{};

  constexpr std::uint32_t PageBytes() const {
    return static_cast<std::uint32_t>(hal::Flash::kPageSize);
  }
  // Bus address of the region (its header).
  constexpr std::uint32_t RegionAddress() const {
    return flash_base + app_first_page * PageBytes();
  }
  constexpr std::uint32_t RegionBytes() const { return app_pages * PageBytes(); }
  // Bus address of the image, its vector table first.
  constexpr std::uint32_t ImageAddress() const {
    return RegionAddress() + static_cast<std::uint32_t>(kHeaderArea);
  }
  constexpr std::uint32_t MaxImageLength() const {
    return RegionBytes() - static_cast<std::uint32_t>(kHeaderArea);
  }
};

// The joint board (linker/stm32g474.ld, linker/stm32g474_bootloader.ld): hal::Flash
// pages of Stm32g4Flash (page p at 0x0800_0000 + p × 2 KB); the bootloader in pages 0-7,
// the application region pages 8-127 (the rest of bank 1), identity pages 252-253 and
// calibration pages 254-255 in bank 2; SRAM 96 KB and CCM SRAM 32 KB.
inline constexpr BootLayout kG474Layout{
    .flash_base = 0x08000000u,
    .app_first_page = 8,
    .app_pages = 120,
    .identity_page_a = 252,
    .identity_page_b = 253,
    .stack_ranges = {{{0x20000000u, 0x20018000u}, {0x10000000u, 0x10008000u}}},
};
static_assert(kG474Layout.RegionAddress() == 0x08004000u);
static_assert(kG474Layout.ImageAddress() == 0x08004200u);
static_assert(kG474Layout.RegionAddress() + kG474Layout.RegionBytes() == 0x08040000u,
              "the application region ends with bank 1");
static_assert(kG474Layout.app_first_page * 2048 == 16 * 1024,
              "the bootloader keeps the first 16 KB");
static_assert(kG474Layout.identity_page_b + 1 == 254,
              "identity pages: beside the "
              "calibration's");
static_assert(kG474Layout.ImageAddress() % 512 == 0, "VTOR: 512-aligned");

// The image target a board with this layout accepts.
constexpr ImageTarget TargetFor(const BootLayout& layout, std::uint16_t board_type,
                                std::uint8_t hardware_revision) {
  return {.board_type = board_type,
          .hardware_revision = hardware_revision,
          .load_address = layout.ImageAddress(),
          .max_length = layout.MaxImageLength()};
}

}  // namespace mjc::boot
