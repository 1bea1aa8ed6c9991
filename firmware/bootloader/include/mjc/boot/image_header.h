// The firmware image header: what the build puts in front of an application image so
// that the bootloader can tell, before it hands over, that the image is whole and built
// for this board. Little-endian, fixed layout, 128 bytes, at the start of the
// application region; the image itself (its vector table first) follows at byte 512.
//
//   offset size field
//        0    4 magic 'MJCI' (0x49434A4D)
//        4    2 format version (1)
//        6    2 header size in bytes (128)
//        8    2 board type (BoardType)
//       10    1 lowest hardware revision the image supports
//       11    1 highest hardware revision the image supports
//       12    4 image length in bytes (a multiple of 8; the packer pads with 0xFF)
//       16    4 CRC-32 of the image's `length` bytes
//       20    4 load address: the bus address of the image's first byte (its vector
//               table), where the image was linked to run
//       24    4 build: the commit, first 32 bits of its hash (0 outside git)
//       28    4 build flags: bit 0 the tree had uncommitted changes ("dirty"), bit 1 the
//               describe string was cut to fit; other bits 0
//       32    8 the commit's time, Unix seconds (the commit's, not the build's, so one
//               commit always gives the same image)
//       40   80 `git describe --always --dirty`, NUL-padded; at most 79 characters
//      120    4 CRC-32 of bytes 0..119
//      124    4 commit mark 0xB007C0DE
//
// Why in front, and why 512 bytes: the image starts with its vector table, and VTOR
// takes a table aligned to its size rounded up to a power of two (ARMv7-M B3.2.5:
// TBLOFF; the STM32G474's 16 + 102 vectors are 472 bytes → 512-byte alignment). A
// header at the region's start (itself page-aligned) followed by the table at +512
// keeps that alignment for any image length, and the bootloader finds the header at
// one fixed place without searching. A header behind the image would sit at an
// address that moves with every build. The 384 bytes between the header and the table
// stay erased.
//
// Why the last double-word holds the CRC and the commit mark: flash is programmed 64
// bits at a time, and the bootloader programs this double-word after everything else,
// once the image's CRC has been checked in flash. Until that one program completes the
// header does not check out, whatever a power cut left; after it, the image is whole.
//
// Standalone (no project headers but the CRC and byte-order helpers), so the host's
// packer builds it alone.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

namespace mjc::boot {

inline constexpr std::uint32_t kImageMagic = 0x49434A4Du;  // "MJCI"
inline constexpr std::uint16_t kImageFormatVersion = 1;
inline constexpr std::size_t kHeaderSize = 128;
inline constexpr std::size_t kHeaderArea = 512;  // the image starts here in the region
inline constexpr std::size_t kDescribeSize = 80;
inline constexpr std::uint32_t kCommitMark = 0xB007C0DEu;

// Byte offsets of the fields (the table above).
namespace header_offset {
inline constexpr std::size_t kMagic = 0, kVersion = 4, kSize = 6, kBoardType = 8,
                             kHardwareMin = 10, kHardwareMax = 11, kLength = 12,
                             kImageCrc = 16, kLoadAddress = 20, kCommit = 24, kFlags = 28,
                             kCommitTime = 32, kDescribe = 40, kHeaderCrc = 120,
                             kCommitMark = 124;
}  // namespace header_offset

static_assert(header_offset::kDescribe + kDescribeSize == header_offset::kHeaderCrc);
static_assert(header_offset::kCommitMark + 4 == kHeaderSize);
// The CRC and the commit mark fill the last double-word, programmed last.
static_assert(header_offset::kHeaderCrc % 8 == 0 &&
              header_offset::kHeaderCrc + 8 == kHeaderSize);
static_assert(kHeaderSize % 8 == 0 && kHeaderSize <= kHeaderArea);
// 118 vectors × 4 bytes = 472 → VTOR alignment 512 (ARMv7-M B3.2.5).
static_assert(kHeaderArea % 512 == 0 && kHeaderArea >= 118 * 4);

inline constexpr std::uint32_t kFlagDirty = 1u << 0;
inline constexpr std::uint32_t kFlagDescribeCut = 1u << 1;

// Boards that take images. Stable numbers: never renumbered.
enum class BoardType : std::uint16_t {
  kG474Joint = 1,      // the joint board, STM32G474 (firmware/boards/g474_joint)
  kQemuMps2An386 = 2,  // QEMU's mps2-an386, the bootloader's target test
};

struct ImageHeader {
  std::uint16_t board_type = 0;  // a BoardType's number
  std::uint8_t hardware_min = 0;
  std::uint8_t hardware_max = 0;
  std::uint32_t length = 0;        // bytes
  std::uint32_t image_crc = 0;     // CRC-32 of the image
  std::uint32_t load_address = 0;  // bus address of the image's first byte
  std::uint32_t commit = 0;
  bool dirty = false;
  bool describe_cut = false;
  std::uint64_t commit_time_unix = 0;          // seconds
  std::array<char, kDescribeSize> describe{};  // NUL-terminated
};

// What a header or an image can be found to be. The numbers are protocol::BootError's
// (messages.h; checked where both are known): a board reports them as they are.
enum class ImageCheck : std::uint8_t {
  kValid = 0,
  kNoImage = 1,         // no header: erased or no magic
  kBadHeader = 2,       // damaged: size, version, CRC, commit mark or reserved bits
  kWrongBoard = 3,      // built for another board type
  kWrongHardware = 4,   // the board's hardware revision is outside the image's range
  kBadLength = 5,       // 0, not a multiple of 8, or larger than the region holds
  kBadLoadAddress = 6,  // linked to run elsewhere than the board's application region
  kBadVectors = 7,      // initial stack pointer or reset vector implausible
  kImageCrc = 8,        // the image does not match the header's CRC
  kUnreadable = 9,      // the flash failed a read of the header or image: an ECC
                        // double error, which an erase or program cut by a power
                        // loss leaves behind (RM0440 §5.3)
};

// What one board accepts.
struct ImageTarget {
  std::uint16_t board_type = 0;
  std::uint8_t hardware_revision = 0;
  std::uint32_t load_address = 0;  // bus address of the image's first byte
  std::uint32_t max_length = 0;    // bytes the region holds after the header area
};

using HeaderBytes = std::array<std::uint8_t, kHeaderSize>;

// The 128 bytes of `header`, with magic, version, size, header CRC and commit mark.
// `describe` is taken up to its first NUL (at most 79 characters).
HeaderBytes EncodeHeader(const ImageHeader& header);

// Decodes and checks the structure (magic, version, size, reserved bits, header CRC,
// commit mark). *out is written only when the result is kValid; an all-0xFF or
// magic-less header is kNoImage, any other defect kBadHeader.
ImageCheck DecodeHeader(std::span<const std::uint8_t, kHeaderSize> bytes,
                        ImageHeader* out);

// A structurally valid header against a board: type, hardware revision, load address,
// and length (8 ≤ length ≤ max_length, a multiple of 8).
ImageCheck CheckHeaderFor(const ImageHeader& header, const ImageTarget& target);

// A whole image file as the packer writes it (header area, then the image): the
// header's structure, the file's length (exactly kHeaderArea + length) and the CRC.
// Board-independent. *out gets the header when the structure is valid.
ImageCheck CheckImageFile(std::span<const std::uint8_t> file, ImageHeader* out);

// The stable name of a check result ("valid", "image_crc", …), for tools and logs.
const char* ImageCheckName(ImageCheck check);

}  // namespace mjc::boot
