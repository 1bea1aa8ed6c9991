#include "mjc/boot/app_region.h"

#include <algorithm>

namespace mjc::boot {
namespace {

using protocol::BootError;

BootError FromFlash(hal::FlashResult r) {
  switch (r) {
    case hal::FlashResult::kOk:
      return BootError::kNone;
    case hal::FlashResult::kBadAddress:
      return BootError::kOutOfRegion;
    case hal::FlashResult::kNotErased:
    case hal::FlashResult::kHardwareError:
      break;
  }
  return BootError::kFlashError;
}

}  // namespace

BootError AppRegion::ErasePageAt(std::uint32_t offset) {
  if (offset >= size()) return BootError::kOutOfRegion;
  return FromFlash(
      flash_->ErasePage(layout_.app_first_page + offset / layout_.PageBytes()));
}

BootError AppRegion::Program(std::uint32_t offset, std::uint64_t value) {
  if (offset >= size() || size() - offset < hal::Flash::kDoubleWord ||
      offset % hal::Flash::kDoubleWord != 0) {
    return BootError::kOutOfRegion;
  }
  return FromFlash(
      flash_->ProgramDoubleWord(layout_.app_first_page + offset / layout_.PageBytes(),
                                offset % layout_.PageBytes(), value));
}

BootError AppRegion::Read(std::uint32_t offset, std::span<std::uint8_t> out) const {
  if (offset > size() || out.size() > size() - offset) return BootError::kOutOfRegion;
  std::size_t done = 0;
  while (done < out.size()) {
    const std::uint32_t at = offset + static_cast<std::uint32_t>(done);
    const std::uint32_t in_page = at % layout_.PageBytes();
    const std::size_t n =
        std::min<std::size_t>(out.size() - done, layout_.PageBytes() - in_page);
    const hal::FlashResult r = flash_->Read(
        layout_.app_first_page + at / layout_.PageBytes(), in_page, out.subspan(done, n));
    if (r != hal::FlashResult::kOk) return FromFlash(r);
    done += n;
  }
  return BootError::kNone;
}

}  // namespace mjc::boot
