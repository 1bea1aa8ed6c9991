#include "mjc/boot/image_header.h"

#include <algorithm>

#include "mjc/protocol/crc32.h"
#include "mjc/protocol/little_endian.h"

namespace mjc::boot {
namespace {

using protocol::GetLe;
using protocol::PutLe;
namespace off = header_offset;

constexpr std::uint32_t kKnownFlags = kFlagDirty | kFlagDescribeCut;

std::uint32_t HeaderCrc(std::span<const std::uint8_t, kHeaderSize> b) {
  return protocol::Crc32(b.first<off::kHeaderCrc>());
}

}  // namespace

HeaderBytes EncodeHeader(const ImageHeader& h) {
  HeaderBytes b{};
  PutLe(&b[off::kMagic], kImageMagic, 4);
  PutLe(&b[off::kVersion], kImageFormatVersion, 2);
  PutLe(&b[off::kSize], kHeaderSize, 2);
  PutLe(&b[off::kBoardType], h.board_type, 2);
  b[off::kHardwareMin] = h.hardware_min;
  b[off::kHardwareMax] = h.hardware_max;
  PutLe(&b[off::kLength], h.length, 4);
  PutLe(&b[off::kImageCrc], h.image_crc, 4);
  PutLe(&b[off::kLoadAddress], h.load_address, 4);
  PutLe(&b[off::kCommit], h.commit, 4);
  PutLe(&b[off::kFlags],
        (h.dirty ? kFlagDirty : 0u) | (h.describe_cut ? kFlagDescribeCut : 0u), 4);
  PutLe(&b[off::kCommitTime], h.commit_time_unix, 8);
  // At most kDescribeSize - 1 characters, so the field always ends with a NUL.
  for (std::size_t i = 0; i + 1 < kDescribeSize && h.describe[i] != '\0'; ++i) {
    b[off::kDescribe + i] = static_cast<std::uint8_t>(h.describe[i]);
  }
  PutLe(&b[off::kHeaderCrc], HeaderCrc(b), 4);
  PutLe(&b[off::kCommitMark], kCommitMark, 4);
  return b;
}

ImageCheck DecodeHeader(std::span<const std::uint8_t, kHeaderSize> b, ImageHeader* out) {
  if (GetLe(&b[off::kMagic], 4) != kImageMagic) return ImageCheck::kNoImage;
  if (GetLe(&b[off::kVersion], 2) != kImageFormatVersion ||
      GetLe(&b[off::kSize], 2) != kHeaderSize ||
      GetLe(&b[off::kCommitMark], 4) != kCommitMark ||
      GetLe(&b[off::kHeaderCrc], 4) != HeaderCrc(b)) {
    return ImageCheck::kBadHeader;
  }
  const auto flags = static_cast<std::uint32_t>(GetLe(&b[off::kFlags], 4));
  if ((flags & ~kKnownFlags) != 0 || b[off::kHeaderCrc - 1] != 0) {
    return ImageCheck::kBadHeader;  // unknown flags, or a describe without its NUL
  }
  ImageHeader h;
  h.board_type = static_cast<std::uint16_t>(GetLe(&b[off::kBoardType], 2));
  h.hardware_min = b[off::kHardwareMin];
  h.hardware_max = b[off::kHardwareMax];
  h.length = static_cast<std::uint32_t>(GetLe(&b[off::kLength], 4));
  h.image_crc = static_cast<std::uint32_t>(GetLe(&b[off::kImageCrc], 4));
  h.load_address = static_cast<std::uint32_t>(GetLe(&b[off::kLoadAddress], 4));
  h.commit = static_cast<std::uint32_t>(GetLe(&b[off::kCommit], 4));
  h.dirty = (flags & kFlagDirty) != 0;
  h.describe_cut = (flags & kFlagDescribeCut) != 0;
  h.commit_time_unix = GetLe(&b[off::kCommitTime], 8);
  for (std::size_t i = 0; i < kDescribeSize; ++i) {
    h.describe[i] = static_cast<char>(b[off::kDescribe + i]);
  }
  *out = h;
  return ImageCheck::kValid;
}

ImageCheck CheckHeaderFor(const ImageHeader& h, const ImageTarget& t) {
  if (h.board_type != t.board_type) return ImageCheck::kWrongBoard;
  if (t.hardware_revision < h.hardware_min || t.hardware_revision > h.hardware_max) {
    return ImageCheck::kWrongHardware;
  }
  if (h.length < 8 || h.length % 8 != 0 || h.length > t.max_length) {
    return ImageCheck::kBadLength;
  }
  if (h.load_address != t.load_address) return ImageCheck::kBadLoadAddress;
  return ImageCheck::kValid;
}

ImageCheck CheckImageFile(std::span<const std::uint8_t> file, ImageHeader* out) {
  if (file.size() < kHeaderArea) {
    return file.size() < kHeaderSize ? ImageCheck::kNoImage : ImageCheck::kBadLength;
  }
  ImageHeader h;
  const ImageCheck structure = DecodeHeader(file.first<kHeaderSize>(), &h);
  if (structure != ImageCheck::kValid) return structure;
  *out = h;
  if (h.length < 8 || h.length % 8 != 0 || file.size() != kHeaderArea + h.length) {
    return ImageCheck::kBadLength;
  }
  if (protocol::Crc32(file.subspan(kHeaderArea)) != h.image_crc) {
    return ImageCheck::kImageCrc;
  }
  return ImageCheck::kValid;
}

const char* ImageCheckName(ImageCheck check) {
  switch (check) {
    case ImageCheck::kValid:
      return "valid";
    case ImageCheck::kNoImage:
      return "no_image";
    case ImageCheck::kBadHeader:
      return "bad_header";
    case ImageCheck::kWrongBoard:
      return "wrong_board";
    case ImageCheck::kWrongHardware:
      return "wrong_hardware";
    case ImageCheck::kBadLength:
      return "bad_length";
    case ImageCheck::kBadLoadAddress:
      return "bad_load_address";
    case ImageCheck::kBadVectors:
      return "bad_vectors";
    case ImageCheck::kImageCrc:
      return "image_crc";
    case ImageCheck::kUnreadable:
      return "unreadable";
  }
  return "unknown";
}

}  // namespace mjc::boot
