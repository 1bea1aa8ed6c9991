#include "mjc/boot/image_check.h"

#include <array>

#include "mjc/protocol/crc32.h"
#include "mjc/protocol/little_endian.h"

namespace mjc::boot {

ImageCheck CheckVectors(std::uint32_t sp, std::uint32_t reset, const ImageHeader& header,
                        const BootLayout& layout) {
  // The core loads SP from word 0 (its low two bits forced to 0, ARMv7-M B1.5.5) and
  // starts at word 1, which must be a Thumb address (bit 0 set; a clear bit 0 is a
  // UsageFault at the first instruction, B1.4.2).
  bool sp_ok = false;
  for (const AddressRange& r : layout.stack_ranges) {
    if (sp > r.begin && sp <= r.end) sp_ok = true;
  }
  const std::uint32_t entry = reset & ~1u;
  const bool reset_ok = (reset & 1u) != 0 && entry >= header.load_address &&
                        entry - header.load_address < header.length;
  return sp_ok && sp % 4 == 0 && reset_ok ? ImageCheck::kValid : ImageCheck::kBadVectors;
}

bool RegionCrc(const AppRegion& region, std::uint32_t offset, std::uint32_t length,
               ServiceHook service, std::uint32_t* crc) {
  std::array<std::uint8_t, 256> block{};
  std::uint32_t state = protocol::kCrc32Init;
  for (std::uint32_t done = 0; done < length;) {
    const std::uint32_t n = length - done < block.size()
                                ? length - done
                                : static_cast<std::uint32_t>(block.size());
    const auto piece = std::span<std::uint8_t>(block).first(n);
    if (region.Read(offset + done, piece) != protocol::BootError::kNone) return false;
    state = protocol::Crc32Update(state, piece);
    done += n;
    if (service != nullptr && done % 2048 == 0) service();
  }
  *crc = protocol::Crc32Final(state);
  return true;
}

std::optional<ImageHeader> ReadInstalledHeader(const AppRegion& region) {
  HeaderBytes bytes{};
  ImageHeader header;
  if (region.Read(0, bytes) != protocol::BootError::kNone ||
      DecodeHeader(bytes, &header) != ImageCheck::kValid) {
    return std::nullopt;
  }
  return header;
}

InstalledImage CheckInstalledImage(const AppRegion& region, const ImageTarget& target,
                                   ServiceHook service) {
  InstalledImage out;
  HeaderBytes bytes{};
  // A read the flash fails (an ECC double error left by a cut erase or program of the
  // header page) is no image to hand over to: the bootloader stays, ready for an
  // update, and names why.
  if (region.Read(0, bytes) != protocol::BootError::kNone) {
    out.check = ImageCheck::kUnreadable;
    return out;
  }
  out.check = DecodeHeader(bytes, &out.header);
  if (out.check != ImageCheck::kValid) return out;
  out.check = CheckHeaderFor(out.header, target);
  if (out.check != ImageCheck::kValid) return out;
  const auto image = static_cast<std::uint32_t>(kHeaderArea);
  std::array<std::uint8_t, 8> vectors{};
  if (region.Read(image, vectors) != protocol::BootError::kNone) {
    out.check = ImageCheck::kUnreadable;
    return out;
  }
  out.stack_pointer = static_cast<std::uint32_t>(protocol::GetLe(&vectors[0], 4));
  out.reset_handler = static_cast<std::uint32_t>(protocol::GetLe(&vectors[4], 4));
  out.check =
      CheckVectors(out.stack_pointer, out.reset_handler, out.header, region.layout());
  if (out.check != ImageCheck::kValid) return out;
  std::uint32_t crc = 0;
  if (!RegionCrc(region, image, out.header.length, service, &crc)) {
    out.check = ImageCheck::kUnreadable;
  } else if (crc != out.header.image_crc) {
    out.check = ImageCheck::kImageCrc;
  }
  return out;
}

}  // namespace mjc::boot
