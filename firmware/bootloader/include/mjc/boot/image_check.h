// The check the bootloader makes before it hands over to an image, at every reset and
// after writing one: the header (structure, board, hardware revision, length, load
// address), the vector table (an initial stack pointer into RAM, a Thumb reset handler
// inside the image), and the CRC-32 of every byte of the image as it is in flash.
#pragma once

#include <cstdint>
#include <optional>

#include "mjc/boot/app_region.h"
#include "mjc/boot/image_header.h"

namespace mjc::boot {

struct InstalledImage {
  ImageCheck check = ImageCheck::kNoImage;
  ImageHeader header;               // meaningful unless kNoImage / kBadHeader
  std::uint32_t stack_pointer = 0;  // the image's vector table, words 0 and 1
  std::uint32_t reset_handler = 0;
};

// Called between blocks of long work (the image's CRC reads up to 240 KB, ~60 ms on the
// G474 at 170 MHz): the board refreshes its watchdog there. May be null.
using ServiceHook = void (*)();

// The vector table's two first words against the layout and the header.
ImageCheck CheckVectors(std::uint32_t stack_pointer, std::uint32_t reset_handler,
                        const ImageHeader& header, const BootLayout& layout);

// The CRC-32 of region bytes [offset, offset + length), read a block at a time; false
// when the flash cannot be read.
bool RegionCrc(const AppRegion& region, std::uint32_t offset, std::uint32_t length,
               ServiceHook service, std::uint32_t* crc);

// The header at the region's start when its structure checks out (DecodeHeader: magic,
// version, header CRC, commit mark); nullopt otherwise. What a running application
// reads to report the build it was installed as (its BoardInfo): the bootloader checked
// the rest before it handed over.
std::optional<ImageHeader> ReadInstalledHeader(const AppRegion& region);

// The whole check of what the region holds, for a board that accepts `target`.
InstalledImage CheckInstalledImage(const AppRegion& region, const ImageTarget& target,
                                   ServiceHook service);

}  // namespace mjc::boot
