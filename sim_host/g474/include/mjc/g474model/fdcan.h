// FDCAN1 of the STM32G474 with its message RAM, and FDCAN_CONFIG.CKDIV, from RM0440
// §44 "FD controller area network (FDCAN)" (§44.3 functional description, §44.4
// registers); offsets, fields and reset values from ST's SVD v2.9; the G4's fixed
// message-RAM layout from ST's HAL (stm32g4xx_hal_fdcan.c, SRAMCAN_* constants); the
// controller's behaviour where RM0440 follows Bosch's M_CAN user manual (bus-off
// recovery, CCE/INIT handshake) rests on that manual's text as reproduced in the SVD
// field descriptions and as open G4 drivers (moteus) run it.
//
// Covered:
//  - CCCR: INIT (set at reset, set by the controller at bus-off), CCE (settable only
//    while INIT = 1, cleared with INIT), CSR → CSA, and the protected bits; every
//    protected register (DBTP, TEST, RWD, NBTP, TSCC, TOCC, TDCR, RXGFC, XIDAM, TXBC,
//    CKDIV and CCCR's configuration bits) takes writes only while INIT = CCE = 1 —
//    others are ignored and reported.
//  - Bit timing: the nominal and data bit rates and sample points computed from the
//    kernel clock (RCC CCIPR.FDCANSEL, then CKDIV.PDIV) and NBTP/DBTP, for the test
//    bench to check (1 Mbit/s / 5 Mbit/s); frame durations in virtual time use them
//    (bit stuffing not counted).
//  - Message RAM at 0x4000A400 (FDCAN1's 0x350 bytes): 28 standard filters, 8 extended
//    filters, RX FIFO 0 and 1 (3 × 18 words), TX event FIFO (3 × 2 words), TX FIFO (3 ×
//    18 words).
//  - Reception (the world delivers frames): standard filters (range, dual, classic
//    id/mask; store in FIFO 0/1, reject, set priority) and extended filters (with XIDAM,
//    and range without it), RXGFC.ANFS/ANFE for non-matching frames, RRFS/RRFE, LSS/LSE;
//    RX FIFO fill level / get / put index / full / message lost (blocking or overwrite
//    mode), RXFxA acknowledge; IR.RFxN/RFxF/RFxL; timestamps (TSCC.TSS = 01, counting
//    nominal bit times / (TCP + 1)).
//  - Transmission: TX FIFO (TXBC.TFQM = 0) free level / get / put index / full; TXBAR
//    → request pending (TXBRP) → after the frame's duration on the bus, the frame
//    leaves through the world callback (FDF/BRS honoured only with CCCR.FDOE/BRSE; DLC
//    → length), TXBTO, IR.TC (for buffers with TXBTIE), IR.TFE, the TX event FIFO
//    (EFC); cancellation (TXBCR) of requests not yet on the bus.
//  - IR (write 1 to clear), IE, ILS (the G4's seven groups), ILE → the two interrupt
//    lines.
//  - Errors: ECR/PSR (LEC, EP, EW, BO). InjectBusOff(): TEC 255, PSR.BO/EP/EW, IR.BO,
//    CCCR.INIT set by the controller; once software clears INIT the controller
//    rejoins after 129 × 11 recessive nominal bit times (PSR.LEC = 5 each 11 bits,
//    as M_CAN reports recovery progress), then BO/EP/EW clear, TEC = REC = 0, IR.BO set.
//
// Not covered: TX queue mode (TFQM = 1, reported), the high-priority message status
// beyond HPMS, restricted/monitoring/test modes, the RAM watchdog, timeout counter,
// TDC measurement, real error counting (only the injected bus-off), arbitration
// against other nodes, bit stuffing in frame durations, FDCAN2/3.
#pragma once

#include <array>
#include <cstdint>
#include <functional>

#include "mjc/g474model/common.h"
#include "mjc/g474model/rcc.h"
#include "mjc/g474model/register_table.h"

namespace mjc::g474model {

// A frame on the bus.
struct CanBusFrame {
  std::uint32_t id = 0;  // 11-bit or 29-bit
  bool extended = false;
  bool remote = false;
  bool fd = false;   // FDF
  bool brs = false;  // bit-rate switch
  bool esi = false;
  std::uint8_t dlc = 0;
  std::uint8_t length = 0;  // bytes, from the DLC
  std::array<std::uint8_t, 64> data{};
};

std::uint8_t DlcToLength(std::uint8_t dlc, bool fd);
std::uint8_t LengthToDlc(std::uint8_t length);

class Fdcan final : public Peripheral {
 public:
  static constexpr std::uint32_t kFdcan1Base = 0x40006400;
  static constexpr std::uint32_t kConfigBase = 0x40006500;  // FDCAN_CONFIG (CKDIV)
  static constexpr std::uint32_t kRamBase = 0x4000A400;
  static constexpr std::uint32_t kRamSize = 0x350;

  Fdcan(ViolationLog* log, const Rcc* rcc);
  bool Read(const Access& a, std::uint32_t* value) override;
  bool Write(const Access& a) override;
  void Reset() override;
  void Advance(Picoseconds now) override;
  Picoseconds NextEvent() const override;

  // FDCAN_CONFIG.CKDIV (shared by the three instances).
  bool ReadConfig(const Access& a, std::uint32_t* value);
  bool WriteConfig(const Access& a);
  // The message RAM (offset from 0x4000A400).
  bool ReadRam(const Access& a, std::uint32_t* value);
  bool WriteRam(const Access& a);

  // World side.
  void SetTransmitHook(std::function<void(const CanBusFrame&, Picoseconds)> hook) {
    tx_hook_ = std::move(hook);
  }
  // A frame that ended on the bus now. Returns false when the controller did not take
  // part (INIT, bus-off, not yet synchronised): nobody acknowledged it from this node.
  bool Receive(const CanBusFrame& frame);
  void InjectBusOff();
  // Frame pins routed (the chip tells: FDCAN1_TX/RX on pins in the right AF). Without
  // them nothing leaves or arrives.
  void SetPinsRouted(bool tx, bool rx) {
    tx_routed_ = tx;
    rx_routed_ = rx;
  }

  bool line0() const;
  bool line1() const;
  double kernel_hz() const;
  double nominal_bitrate() const;
  double data_bitrate() const;
  double nominal_sample_point() const;
  double data_sample_point() const;
  bool bus_off() const { return (psr_ & (1u << 7)) != 0; }
  bool initializing() const { return (cccr_ & 1u) != 0; }
  // The controller takes part in bus traffic (not INIT, synchronised, not bus-off).
  bool active() const;

 private:
  // The registers without code of their own (register_table.h).
  static RegisterTable<Fdcan> Registers();
  bool Protected(const char* reg);
  std::uint32_t Word(std::uint32_t byte_offset) const { return ram_[byte_offset / 4]; }
  void SetIr(std::uint32_t bits) { ir_ |= bits; }
  bool StoreInFifo(int fifo, const CanBusFrame& f, int filter_index, bool anmf);
  void TryStartTx();
  Picoseconds FrameDuration(const CanBusFrame& f) const;
  CanBusFrame ReadTxElement(int index) const;
  std::uint32_t Timestamp() const;

  ViolationLog* log_;
  const Rcc* rcc_;
  Picoseconds now_ = 0;
  std::array<std::uint32_t, kRamSize / 4> ram_{};
  std::uint32_t ckdiv_ = 0;
  std::uint32_t dbtp_ = 0, test_ = 0, rwd_ = 0, cccr_ = 0, nbtp_ = 0, tscc_ = 0,
                tocc_ = 0, ecr_ = 0, psr_ = 0, tdcr_ = 0, ir_ = 0, ie_ = 0, ils_ = 0,
                ile_ = 0, rxgfc_ = 0, xidam_ = 0, hpms_ = 0, txbc_ = 0, txbrp_ = 0,
                txbto_ = 0, txbcf_ = 0, txbtie_ = 0, txbcie_ = 0;
  struct Fifo {
    unsigned fill = 0, get = 0, put = 0;
    bool lost = false;
  };
  std::array<Fifo, 2> rx_{};
  Fifo tx_event_{};
  unsigned tx_get_ = 0, tx_put_ = 0, tx_free_ = 3;
  // Synchronisation after INIT is cleared, and bus-off recovery.
  Picoseconds synced_at_ = kNever;
  Picoseconds recovered_at_ = kNever;
  Picoseconds recovery_start_ = 0;
  // The frame on the bus now.
  int tx_current_ = -1;
  Picoseconds tx_end_ = kNever;
  Picoseconds ts_origin_ = 0;
  bool tx_routed_ = true, rx_routed_ = true;
  std::function<void(const CanBusFrame&, Picoseconds)> tx_hook_;
};

}  // namespace mjc::g474model
