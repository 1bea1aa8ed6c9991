#include "mjc/g474model/option_bytes.h"

#include <unistd.h>

#include <cstring>

namespace mjc::g474model {
namespace {
// The persistence block: a tag, the stored word, its complement, a spare word.
constexpr std::uint32_t kTag = 0x4254504Fu;  // "OPTB"
}  // namespace

const char* BootSourceName(BootSource s) {
  switch (s) {
    case BootSource::kMainFlash:
      return "main flash";
    case BootSource::kSystemMemory:
      return "system memory (ST's ROM bootloader)";
    case BootSource::kSram:
      return "embedded SRAM";
  }
  return "?";
}

BootSource BootFrom(std::uint32_t optr, bool pin) {
  const bool boot0 =
      (optr & OptionBytes::kNSwBoot0) != 0 ? pin : (optr & OptionBytes::kNBoot0) == 0;
  if (!boot0) return BootSource::kMainFlash;
  return (optr & OptionBytes::kNBoot1) != 0 ? BootSource::kSystemMemory
                                            : BootSource::kSram;
}

OptionBytes::OptionBytes(ViolationLog* log, Picoseconds program_time)
    : log_(log), program_time_(program_time) {}

void OptionBytes::Restore(const std::uint8_t* block, std::uint32_t bytes) {
  std::uint32_t w[4] = {};
  if (bytes >= sizeof w) std::memcpy(w, block, sizeof w);
  if (w[0] == kTag) {
    stored_ = w[1];
    stored_complement_ = w[2];
  }
  Load(0);
  Reset();
}

void OptionBytes::Persist(int fd, std::uint32_t offset) {
  fd_ = fd;
  file_offset_ = offset;
  Save();
}

void OptionBytes::Save() const {
  if (fd_ < 0) return;
  const std::uint32_t w[4] = {kTag, stored_, stored_complement_, 0xFFFFFFFFu};
  // One write of 16 bytes: a process killed around it leaves the old block or the new.
  (void)::pwrite(fd_, w, sizeof w, static_cast<off_t>(file_offset_));
}

void OptionBytes::Write(const Access& a, bool optlock, Picoseconds now) {
  if (optlock) {
    log_->Report(now, "FLASH",
                 "FLASH_OPTR written while FLASH_CR.OPTLOCK = 1: ignored (the option "
                 "keys come first, RM0440 §5.4.2)");
    return;
  }
  if (busy()) {
    log_->Report(now, "FLASH", "FLASH_OPTR written during option programming: ignored");
    return;
  }
  reg_ = (a.Merged(reg_) & kWritable) | ~kWritable;
}

void OptionBytes::Start(bool optlock, bool array_busy, Picoseconds now) {
  if (optlock) {
    log_->Report(now, "FLASH", "FLASH_CR.OPTSTRT while OPTLOCK = 1: ignored");
    return;
  }
  if (array_busy || busy()) {
    log_->Report(now, "FLASH", "FLASH_CR.OPTSTRT while BSY = 1: ignored");
    return;
  }
  pending_ = reg_;
  end_ = now + program_time_;
}

void OptionBytes::Launch(bool optlock, Picoseconds now) {
  if (optlock) {
    log_->Report(now, "FLASH", "FLASH_CR.OBL_LAUNCH while OPTLOCK = 1: ignored");
    return;
  }
  if (busy()) Complete();  // the loader waits for the option page
  if (launch_hook_) launch_hook_();
}

void OptionBytes::Advance(Picoseconds now) {
  if (busy() && now >= end_) Complete();
}

void OptionBytes::Complete() {
  stored_ = pending_;
  stored_complement_ = ~pending_;
  end_ = kNever;
  Save();
}

void OptionBytes::Reset() {
  if (busy()) Complete();
  reg_ = loaded_;
}

void OptionBytes::Load(Picoseconds now) {
  load_error_ = !stored_valid();
  loaded_ = load_error_ ? kFactory : stored_;
  reg_ = loaded_;
  if (load_error_) {
    log_->Report(now, "FLASH",
                 "option bytes and their complement disagree (an interrupted option "
                 "programming): OPTVERR, the chip runs with the factory word");
  }
  if ((loaded_ & kDbank) == 0) {
    log_->Report(now, "FLASH",
                 "option bytes loaded with DBANK = 0: single-bank mode is not modelled "
                 "(the array keeps its dual-bank geometry)");
  }
  if ((loaded_ & kBfb2) != 0) {
    log_->Report(now, "FLASH",
                 "option bytes loaded with BFB2 = 1: the dual-bank boot is not modelled "
                 "(the boot decision ignores it)");
  }
}

bool OptionBytes::PowerLost() {
  if (!busy()) return false;
  // The option page was being erased and programmed: some bits of the word and of its
  // complement made it, others did not.
  const auto mask = static_cast<std::uint32_t>(rng_());
  stored_ = (pending_ & mask) | (0xFFFFFFFFu & ~mask);
  stored_complement_ = static_cast<std::uint32_t>(rng_() >> 32);
  if (stored_valid()) stored_complement_ ^= 1u;  // a cut never leaves a valid pair here
  end_ = kNever;
  Save();
  return true;
}

}  // namespace mjc::g474model
