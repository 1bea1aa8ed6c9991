// Firmware image files on the host: the packer's side (an image linked by the build →
// the file with its header, maestro-jc-g474-app.bin) and the reader's (a file → its
// header, checked). `mjc-image` and the tests use it; `mjc flash` will.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "mjc/boot/image_header.h"

namespace mjc::boot {

// The file for `image` (the linked image's bytes from its vector table on, as objcopy
// writes them): the header area (the header, then 0xFF to kHeaderArea), then the image
// padded with 0xFF to a multiple of 8 bytes. `header` gives everything but the length
// and the CRC, which are computed here.
std::vector<std::uint8_t> PackImage(std::span<const std::uint8_t> image,
                                    ImageHeader header);

struct ImageFile {
  std::vector<std::uint8_t> bytes;  // the whole file
  ImageHeader header;               // valid when check is not kNoImage / kBadHeader
  ImageCheck check = ImageCheck::kNoImage;
  std::span<const std::uint8_t> image() const {
    return std::span<const std::uint8_t>(bytes).subspan(
        bytes.size() < kHeaderArea ? bytes.size() : kHeaderArea);
  }
};

// The whole file at `path`; false when it cannot be read.
bool ReadFileBytes(const std::string& path, std::vector<std::uint8_t>* out);

// Reads and checks `path` (CheckImageFile). False, with the reason in *why, only when
// the file cannot be read; a file that reads but does not check out is returned with
// its check result.
bool ReadImageFile(const std::string& path, ImageFile* out, std::string* why);

// The header as the table of README's image format: one "offset size field value"
// line each.
std::string HeaderTable(const ImageHeader& header);

// The describe string of a header, up to its NUL.
std::string DescribeOf(const ImageHeader& header);

}  // namespace mjc::boot
