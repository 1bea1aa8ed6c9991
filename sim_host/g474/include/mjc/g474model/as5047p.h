// An AS5047P-class 14-bit magnetic angle sensor on SPI, from ams' AS5047P datasheet
// (v1-06, "SPI interface (slave)", "Register description", "Timing characteristics";
// the register addresses and frame bits match open drivers such as moteus fw/as5047.h
// and its 16-bit, mode-1 SPI options).
//
// Covered: SPI mode 1 (CPOL 0, CPHA 1), 16-bit frames. Command frame: bit 15 PARC (even
// parity over the 16 bits), bit 14 R/W (1 = read), bits 13:0 address. Read data frame:
// bit 15 PARD (even parity), bit 14 EF, bits 13:0 data. The answer to a command
// arrives in the *next* frame (the first frame after power-up answers 0). Registers:
// NOP 0x0000 (reads 0), ERRFL 0x0001 (FRERR bit 0, INVCOMM bit 1, PARERR bit 2; reading
// clears it), PROG 0x0003, DIAAGC 0x3FFC, MAG 0x3FFD, ANGLEUNC 0x3FFE, ANGLECOM 0x3FFF
// (ANGLEUNC minus the zero position ZPOSM:ZPOSL), and the volatile copies of ZPOSM,
// ZPOSL, SETTINGS1, SETTINGS2 (0x0016..0x0019), writable with a write command followed by
// a data frame. A frame of other than 16 bits is a framing error, a command with bad
// parity a parity error, an unknown address an invalid command: each sets its ERRFL bit
// and EF in the next answer. Timing checks, each a reported violation: SCK ≤ 10 MHz,
// CSn low before the first clock ≥ t_L = 350 ns, CSn high between frames ≥ t_CSn = 350
// ns, one frame per CSn low period, CSn not raised during a frame.
//
// The angle comes from the world at the moment an answer frame starts (AngleSource):
// the 14-bit raw count plus, for the plant's injected sensor faults, a request to set EF
// or to corrupt the frame's parity.
//
// Not covered: OTP programming (PROG burns nothing), DAEC/hysteresis settings'
// effect on the angle, the ABI/UVW/PWM outputs, magnet-field diagnostics beyond fixed
// DIAAGC/MAG values, daisy chaining.
#pragma once

#include <cstdint>
#include <functional>

#include "mjc/g474model/common.h"
#include "mjc/g474model/spi.h"

namespace mjc::g474model {

struct AngleSample {
  std::uint16_t count = 0;      // raw 14-bit angle (0..16383)
  bool error_flag = false;      // answer with EF set (an injected sensor fault)
  bool corrupt_parity = false;  // answer with PARD flipped (an injected line fault)
};

class As5047p {
 public:
  static constexpr std::uint16_t kNop = 0x0000, kErrfl = 0x0001, kProg = 0x0003,
                                 kZposm = 0x0016, kZposl = 0x0017, kSettings1 = 0x0018,
                                 kSettings2 = 0x0019, kDiaagc = 0x3FFC, kMag = 0x3FFD,
                                 kAngleUnc = 0x3FFE, kAngleCom = 0x3FFF;

  explicit As5047p(ViolationLog* log) : log_(log) {}

  void SetAngleSource(std::function<AngleSample()> source) {
    source_ = std::move(source);
  }
  // A fixed angle (when no source is set).
  void SetAngle(std::uint16_t count) { fixed_ = count & 0x3FFFu; }

  // The chip-select line changed (low = selected) at time `now`.
  void OnChipSelect(bool level, Picoseconds now);
  // A frame starts (timing checks) / ends: returns the MISO word. Only called while
  // selected.
  void OnFrameStart(const SpiFrame& f);
  std::uint16_t Exchange(const SpiFrame& f);
  bool selected() const { return !cs_high_; }

  std::uint16_t errfl() const { return errfl_; }
  long frames() const { return frames_; }
  // A command frame with its parity bit set right (for tests and the world).
  static std::uint16_t Command(std::uint16_t address, bool read);

 private:
  std::uint16_t Register(std::uint16_t address, AngleSample* sample);
  static bool Known(std::uint16_t address);

  ViolationLog* log_;
  std::function<AngleSample()> source_;
  std::uint16_t fixed_ = 0;
  bool cs_high_ = true;
  Picoseconds cs_rise_ = -1'000'000'000;  // long ago
  Picoseconds cs_fall_ = 0;
  int frames_in_window_ = 0;
  bool in_frame_ = false;
  // What the next answer frame carries.
  enum class Next { kNothing, kRead, kWriteData } next_ = Next::kNothing;
  std::uint16_t next_address_ = 0;
  std::uint16_t write_address_ = 0;
  std::uint16_t errfl_ = 0;
  std::uint16_t zposm_ = 0, zposl_ = 0, settings1_ = 0x0001, settings2_ = 0;
  long frames_ = 0;
};

}  // namespace mjc::g474model
