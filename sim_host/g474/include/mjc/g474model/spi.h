// SPI1 of the STM32G474 in master mode (RM0440 chapter "Serial peripheral interface /
// integrated interchip sound (SPI/I2S)"; offsets and reset values from ST's SVD v2.9 —
// whose CR1 bit 11 is named DFF, CRCL on this chip: the frame size is CR2.DS).
//
// Covered: CR1 (CPHA, CPOL, MSTR, BR, SPE, LSBFIRST, SSI, SSM), CR2 (DS with the "not
// used" values forced to 8 bits, FRXTH, RXNEIE/TXEIE/ERRIE), SR (RXNE by the FIFO
// threshold, TXE while the TX FIFO is at most half full, BSY, OVR cleared by reading DR
// then SR, MODF when SSM = 1 and SSI = 0 in master mode — which clears SPE and MSTR —,
// FRLVL/FTLVL), the 32-bit TX and RX FIFOs with data packing by access width (a 16-bit
// access to DR moves two frames of ≤ 8 bits, or one frame of 9..16 bits). A frame
// takes DS bit times at f_PCLK2 / 2^(BR+1) of virtual time; at its end the word
// clocked in from the bus (the world's device) enters the RX FIFO.
//
// Not covered: slave mode, NSS pin management (SSOE/NSSP), CRC, TI mode, bidirectional
// and receive-only modes, DMA, I2S. 32-bit accesses to DR are reported and treated as
// 16-bit.
#pragma once

#include <cstdint>
#include <deque>
#include <functional>

#include "mjc/g474model/common.h"
#include "mjc/g474model/rcc.h"
#include "mjc/g474model/register_table.h"

namespace mjc::g474model {

// One frame on the bus as the SPI clocks it.
struct SpiFrame {
  std::uint16_t mosi = 0;
  unsigned bits = 8;
  bool cpol = false, cpha = false, lsb_first = false;
  double sck_hz = 0;
  Picoseconds start = 0, end = 0;
};

class Spi final : public Peripheral {
 public:
  static constexpr std::uint32_t kSpi1Base = 0x40013000;

  Spi(ViolationLog* log, const Rcc* rcc);
  bool Read(const Access& a, std::uint32_t* value) override;
  bool Write(const Access& a) override;
  void Reset() override;
  void Advance(Picoseconds now) override;
  Picoseconds NextEvent() const override;

  // The bus: called at the end of each frame; returns the MISO word.
  void SetBus(std::function<std::uint16_t(const SpiFrame&)> bus) {
    bus_ = std::move(bus);
  }
  // Called when a frame starts (the chip checks device timing there).
  void SetFrameStartHook(std::function<void(const SpiFrame&)> hook) {
    start_hook_ = std::move(hook);
  }
  bool irq() const;
  unsigned frame_bits() const;
  double sck_hz() const;

 private:
  // The registers without code of their own (register_table.h).
  static RegisterTable<Spi> Registers();
  std::uint32_t Sr() const;
  void StartNext();
  unsigned FrameBytes() const { return frame_bits() > 8 ? 2u : 1u; }

  ViolationLog* log_;
  const Rcc* rcc_;
  Picoseconds now_ = 0;
  std::uint32_t cr1_ = 0, cr2_ = 0x700, crcpr_ = 7, i2scfgr_ = 0, i2spr_ = 2;
  bool ovr_ = false, modf_ = false, ovr_armed_ = false;
  std::deque<std::uint8_t> tx_, rx_;
  bool busy_ = false;
  SpiFrame current_;
  std::function<std::uint16_t(const SpiFrame&)> bus_;
  std::function<void(const SpiFrame&)> start_hook_;
};

}  // namespace mjc::g474model
