#include "mjc/g474model/as5047p.h"

#include <string>

namespace mjc::g474model {
namespace {
constexpr Picoseconds kTl = Nanoseconds(350);    // CSn falling edge → first SCK edge
constexpr Picoseconds kTcsn = Nanoseconds(350);  // CSn high between transmissions
constexpr double kMaxSckHz = 10e6;
constexpr std::uint16_t kFrerr = 1u << 0, kInvcomm = 1u << 1, kParerr = 1u << 2;

std::uint16_t WithParity(std::uint16_t v) {
  v &= 0x7FFFu;
  return static_cast<std::uint16_t>(v | (OddBitCount(v) ? 0x8000u : 0));
}
}  // namespace

std::uint16_t As5047p::Command(std::uint16_t address, bool read) {
  return WithParity(
      static_cast<std::uint16_t>((address & 0x3FFFu) | (read ? 0x4000u : 0)));
}

bool As5047p::Known(std::uint16_t a) {
  return a == kNop || a == kErrfl || a == kProg || (a >= kZposm && a <= kSettings2) ||
         (a >= kDiaagc && a <= kAngleCom);
}

void As5047p::OnChipSelect(bool level, Picoseconds now) {
  if (level == cs_high_) return;
  if (!level) {  // falling: selected
    if (now - cs_rise_ < kTcsn) {
      log_->Report(now, "AS5047P",
                   "CSn high for " + std::to_string((now - cs_rise_) / 1000) +
                       " ns between frames (t_CSn >= 350 ns)");
    }
    cs_fall_ = now;
    frames_in_window_ = 0;
  } else {
    if (in_frame_) {
      log_->Report(now, "AS5047P", "CSn raised during a frame: framing error");
      errfl_ |= kFrerr;
      in_frame_ = false;
    }
    cs_rise_ = now;
  }
  cs_high_ = level;
}

void As5047p::OnFrameStart(const SpiFrame& f) {
  in_frame_ = true;
  if (f.start - cs_fall_ < kTl) {
    log_->Report(f.start, "AS5047P",
                 "first SCK edge " + std::to_string((f.start - cs_fall_) / 1000) +
                     " ns after CSn fell (t_L >= 350 ns)");
  }
  if (f.sck_hz > kMaxSckHz) {
    log_->Report(f.start, "AS5047P",
                 "SCK " + std::to_string(f.sck_hz / 1e6) + " MHz above 10 MHz");
  }
  if (++frames_in_window_ > 1) {
    log_->Report(f.start, "AS5047P",
                 "second frame in one CSn low period (CSn must toggle between frames)");
  }
}

std::uint16_t As5047p::Register(std::uint16_t address, AngleSample* sample) {
  switch (address) {
    case kNop:
      return 0;
    case kErrfl:
      return errfl_;
    case kProg:
      return 0;
    case kZposm:
      return zposm_;
    case kZposl:
      return zposl_;
    case kSettings1:
      return settings1_;
    case kSettings2:
      return settings2_;
    case kDiaagc:
      return 0x0180;  // LF = 1 (offset loop finished), AGC = 0x80
    case kMag:
      return 0x0E00;  // a magnet in range (CORDIC magnitude)
    default:
      break;
  }
  *sample = source_ ? source_() : AngleSample{fixed_, false, false};
  const std::uint16_t raw = sample->count & 0x3FFFu;
  if (address == kAngleUnc) return raw;
  const std::uint16_t zero =
      static_cast<std::uint16_t>(((zposm_ & 0xFFu) << 6) | (zposl_ & 0x3Fu));
  return static_cast<std::uint16_t>((raw - zero) & 0x3FFFu);
}

std::uint16_t As5047p::Exchange(const SpiFrame& f) {
  in_frame_ = false;
  ++frames_;
  // The answer to the previous command.
  AngleSample sample;
  std::uint16_t data = 0;
  bool error_flag = errfl_ != 0;
  if (next_ == Next::kRead) {
    data = Register(next_address_, &sample);
    if (next_address_ == kErrfl) errfl_ = 0;  // "reading clears"
  } else if (next_ == Next::kWriteData) {
    data = Register(write_address_, &sample);  // old content
  }
  error_flag = error_flag || sample.error_flag;
  std::uint16_t answer = WithParity(
      static_cast<std::uint16_t>((data & 0x3FFFu) | (error_flag ? 0x4000u : 0)));
  if (sample.corrupt_parity) answer ^= 0x8000u;

  // The command in this frame.
  const std::uint16_t cmd = f.mosi;
  const Next was = next_;
  next_ = Next::kNothing;
  if (f.bits != 16) {
    errfl_ |= kFrerr;
    log_->Report(f.end, "AS5047P",
                 std::to_string(f.bits) + "-bit frame: framing error (16 bits)");
    return 0;
  }
  if (f.cpol || !f.cpha) {
    log_->Report(f.end, "AS5047P",
                 "SPI mode CPOL=" + std::to_string(f.cpol) +
                     " CPHA=" + std::to_string(f.cpha) +
                     ": the sensor samples on the falling edge (mode 1): bits shifted");
    answer = static_cast<std::uint16_t>(answer >> 1);
  }
  if (f.lsb_first) {
    log_->Report(f.end, "AS5047P", "LSB-first frame: the sensor shifts MSB first");
  }
  if (was == Next::kWriteData) {
    // This frame carries the data of a write command (bit 14 must be 0).
    if (OddBitCount(cmd)) {
      errfl_ |= kParerr;
      return answer;
    }
    const std::uint16_t d = cmd & 0x3FFFu;
    if (write_address_ == kZposm) zposm_ = d & 0xFFu;
    if (write_address_ == kZposl) zposl_ = d & 0xFFu;
    if (write_address_ == kSettings1) settings1_ = d & 0xFFu;
    if (write_address_ == kSettings2) settings2_ = d & 0xFFu;
    next_ = Next::kRead;  // the next frame shows the new content
    next_address_ = write_address_;
    return answer;
  }
  if (OddBitCount(cmd)) {
    errfl_ |= kParerr;
    log_->Report(f.end, "AS5047P", "command frame with odd parity: parity error");
    return answer;
  }
  const std::uint16_t address = cmd & 0x3FFFu;
  if (!Known(address)) {
    errfl_ |= kInvcomm;
    return answer;
  }
  if (cmd & 0x4000u) {
    next_ = Next::kRead;
    next_address_ = address;
  } else {
    next_ = Next::kWriteData;
    write_address_ = address;
  }
  return answer;
}

}  // namespace mjc::g474model
