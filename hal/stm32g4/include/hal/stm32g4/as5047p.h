// The joint's absolute encoder, an AS5047P-class 14-bit magnetic sensor on SPI1
// (RM0440 §39, SPI), 16-bit frames in SPI mode 1 (CPOL = 0, CPHA = 1: the sensor
// changes MISO on the rising edge and samples MOSI on the falling one).
//
// The device owns its chip-select line: a driver is handed an As5047p, never the pin.
//
// Pipelining. The sensor answers a read command in the *next* frame. Every tick sends
// the same command (read ANGLECOM), so the frame received for tick N's command, read at
// tick N + 1's start, holds the angle sampled during tick N's transfer:
//   ISR_Write of tick N:    CS low, command → 16 clocks (3 µs at 5.3 MHz)
//   ISR_Read of tick N + 1: the frame (complete for ~97 µs), CS high
// The first answer after power-up belongs to no command: Init() sends one command and
// drops its answer, so the first tick already reads an angle.
//
// Timing (AS5047P datasheet, SPI timing): CSn high between frames t_CSn ≥ 350 ns, CSn
// falling edge to the first clock t_L ≥ 350 ns. Both are measured with the cycle
// counter (60 cycles at 170 MHz) and waited out only if the tick has not already spent
// them (normally it has: CS stays high for the tick's computation, and the bridge
// writes fall between CS low and the command).
// Clock: f_PCLK2 / 32 = 5.3 MHz ≤ the sensor's 10 MHz.
#pragma once

#include <cstdint>

#include "hal/stm32g4/clock.h"
#include "hal/stm32g4/gpio.h"
#include "hal/stm32g4/mmio.h"
#include "hal/stm32g4/poll.h"
#include "hal/stm32g4/regs/spi.h"

namespace mjc::stm32g4 {

// Read command frames: bit 15 even parity over the word, bit 14 = 1 (read), address.
// ANGLECOM (0x3FFF, the DAEC-compensated angle): 0xFFFF.
inline constexpr std::uint16_t kAs5047pReadAngle = 0xFFFF;
// What ISR_Finish() returns when no frame arrived: odd parity, so the tick's decoder
// reports a parity fault (core encoder.h) rather than an angle.
inline constexpr std::uint16_t kAs5047pNoFrame = 0x8000;

// SPI CR1.BR: f_PCLK / 2^(BR+1). 100 → /32.
inline constexpr std::uint32_t kAs5047pBaudCode = 0b100;
inline constexpr std::uint32_t kAs5047pSckHz = kPclk2Hz >> (kAs5047pBaudCode + 1);
static_assert(kAs5047pSckHz <= 10'000'000);
// 350 ns in core cycles, rounded up.
inline constexpr std::uint32_t kAs5047pCsCycles =
    static_cast<std::uint32_t>((350ull * kSysclkHz + 999'999'999ull) / 1'000'000'000ull);
static_assert(kAs5047pCsCycles == 60);

template <Address kSpi, PortPin kCs, Address kDwt = dwt::kBase>
class As5047p {
 public:
  using Cs = OutputPin<kCs>;
  using Clock = CycleCounter<kDwt>;

  // SPI1's clock and SCK/MISO/MOSI must be set; the CS pin must be an output driven
  // high. Configures SPI1 (RM0440 §39.4.7 "Configuration of SPI": CR1 then CR2 with
  // SPE = 0, then SPE) and primes the pipeline. False if the primer frame never
  // completed (the sensor's frames will then read as kAs5047pNoFrame).
  bool Init() {
    using namespace spi1;
    Cs::Set();
    Write32(kSpi + kCr1, 0);
    // Master, mode 1, /32, MSB first, software slave management (SSM = SSI = 1: NSS is
    // not a pin; the CS line is ours).
    const std::uint32_t cr1 = cr1::kCpha.Bit() | cr1::kMstr.Bit() |
                              cr1::kBr.Value(kAs5047pBaudCode) | cr1::kSsm.Bit() |
                              cr1::kSsi.Bit();
    Write32(kSpi + kCr1, cr1);
    // 16-bit frames (DS = 1111); FRXTH = 0: RXNE once 16 bits are in the RX FIFO.
    Write32(kSpi + kCr2, cr2::kDs.Value(0b1111));
    Write32(kSpi + kCr1, cr1 | cr1::kSpe.Bit());
    cs_high_since_ = Clock::Now();
    ISR_Start();
    const bool done =
        WaitFor(kSpi + kSr, sr::kRxne.Bit() | sr::kBsy.Bit(), sr::kRxne.Bit(), kMaxPolls);
    (void)ISR_Finish();
    return done;
  }

  // Ends the frame started by the last ISR_Start(): its 16 bits, or kAs5047pNoFrame if
  // it did not complete. Raises CS.
  std::uint16_t ISR_Finish() {
    using namespace spi1;
    const std::uint32_t sr = Read32(kSpi + kSr);
    std::uint16_t frame = kAs5047pNoFrame;
    if (sr::kRxne.IsSet(sr) && !sr::kBsy.IsSet(sr)) {
      // A 16-bit access reads one 16-bit frame (RM0440 §39.4.9 "Data packing").
      frame = Read16(kSpi + kDr);
      // More than one frame means the pipeline slipped: drain it, trust none.
      if (sr::kRxne.IsSet(Read32(kSpi + kSr))) {
        (void)Read16(kSpi + kDr);
        frame = kAs5047pNoFrame;
      }
    }
    Cs::Set();
    cs_high_since_ = Clock::Now();
    return frame;
  }

  // Lowers CS (t_CSn after the last rise) — the first half of ISR_Start(), so the
  // caller can spend t_L on other writes before ISR_Command().
  void ISR_Select() {
    Clock::WaitSince(cs_high_since_, kAs5047pCsCycles);
    Cs::Clear();
    cs_low_since_ = Clock::Now();
  }
  // Sends the read command (t_L after ISR_Select()).
  void ISR_Command() {
    Clock::WaitSince(cs_low_since_, kAs5047pCsCycles);
    Write16(kSpi + spi1::kDr, kAs5047pReadAngle);
  }
  void ISR_Start() {
    ISR_Select();
    ISR_Command();
  }

 private:
  static constexpr std::uint32_t kMaxPolls = 100'000;
  std::uint32_t cs_high_since_ = 0;
  std::uint32_t cs_low_since_ = 0;
};

}  // namespace mjc::stm32g4
