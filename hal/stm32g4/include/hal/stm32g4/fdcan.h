// FDCAN1 as the board's hal::CanPort (RM0440 §44, FDCAN): classic CAN and CAN FD with
// bit-rate switch, 1 Mbit/s nominal and 5 Mbit/s data, received by interrupt into a
// queue, sent through the TX FIFO.
//
// Bit timing, from the 85 MHz kernel clock (PLLQ, clock.h), prescalers 1:
//   nominal: 85 tq = 1 (sync) + 67 (NTSEG1) + 17 (NTSEG2) → 1 Mbit/s, sample point 80 %
//            (CiA 601-3's recommendation for 1 Mbit/s), NSJW = NTSEG2 = 17;
//   data:    17 tq = 1 + 12 (DTSEG1) + 4 (DTSEG2)        → 5 Mbit/s, sample point 76.5 %,
//            DSJW = DTSEG2 = 4.
// At 5 Mbit/s the transceiver's loop delay (≈ 100-150 ns) is most of a bit (200 ns), so
// the transmitter checks its own bits at a secondary sample point: transmitter delay
// compensation on (DBTP.TDC), TDCO = DTSEG1 × DBRP = 12 mtq after the measured delay —
// ST's rule for its G4 examples (STM32CubeG4 FDCAN_Com_IT: "TdcOffset default
// recommended value: DataTimeSeg1 * DataPrescaler"), TDCF = 0 (no filter window).
//
// Message RAM (regs/fdcan.h, fixed layout on the G4): standard filters 0..n-1 from the
// configured id/mask list, each "classic" (accept when (id & mask) == (filter & mask)),
// storing to RX FIFO 0; every other frame (and every remote and extended frame) is
// rejected in hardware (RXGFC.ANFS/ANFE = reject, RRFS/RRFE).
//
// Interrupts: line 0 (FDCAN1_IT0, IRQ 21) carries the RX FIFO 0 group (new message,
// message lost); line 1 (FDCAN1_IT1, IRQ 22) the protocol-error group, of which only
// bus-off is enabled. Bus-off: the controller sets CCCR.INIT itself; ISR_Line1 counts
// it and clears INIT at once, after which the controller waits for 129 occurrences of
// 11 recessive bits before taking part in the bus again (the M_CAN core's recovery,
// RM0440 FDCAN_CCCR.INIT, FDCAN "Bus-off" recovery). TakeBusOff() reports the events.
#pragma once

#include <atomic>
#include <cstdint>
#include <span>

#include "hal/can_port.h"
#include "hal/stm32g4/clock.h"
#include "hal/stm32g4/regs/fdcan.h"
#include "mjc/core/spsc_queue.h"
#include "mjc/protocol/can_frame.h"

namespace mjc::stm32g4 {

struct CanBitTiming {
  std::uint32_t prescaler;
  std::uint32_t seg1;  // propagation + phase 1, tq
  std::uint32_t seg2;  // phase 2, tq
  std::uint32_t sjw;   // tq
  constexpr std::uint32_t TqPerBit() const { return 1 + seg1 + seg2; }
  constexpr std::uint32_t BitRate(std::uint32_t clock_hz) const {
    return clock_hz / (prescaler * TqPerBit());
  }
};
inline constexpr CanBitTiming kNominalTiming{1, 67, 17, 17};
inline constexpr CanBitTiming kDataTiming{1, 12, 4, 4};
static_assert(kFdcanKernelHz % (kNominalTiming.prescaler * kNominalTiming.TqPerBit()) ==
              0);
static_assert(kNominalTiming.BitRate(kFdcanKernelHz) == 1'000'000);
static_assert(kFdcanKernelHz % (kDataTiming.prescaler * kDataTiming.TqPerBit()) == 0);
static_assert(kDataTiming.BitRate(kFdcanKernelHz) == 5'000'000);
// Field ranges (RM0440 FDCAN_NBTP, FDCAN_DBTP; each written as value − 1).
static_assert(kNominalTiming.seg1 >= 2 && kNominalTiming.seg1 <= 256);
static_assert(kNominalTiming.seg2 >= 2 && kNominalTiming.seg2 <= 128);
static_assert(kNominalTiming.sjw <= kNominalTiming.seg2);
static_assert(kDataTiming.seg1 >= 1 && kDataTiming.seg1 <= 32);
static_assert(kDataTiming.seg2 >= 1 && kDataTiming.seg2 <= 16);
static_assert(kDataTiming.sjw <= kDataTiming.seg2);
inline constexpr std::uint32_t kTdcOffset = kDataTiming.seg1 * kDataTiming.prescaler;
inline constexpr std::uint32_t kTdcFilter = 0;

// A standard-identifier acceptance filter: frames whose (id & mask) equals (this id &
// mask) are received.
struct CanFilter {
  std::uint16_t id = 0;    // 11 bits
  std::uint16_t mask = 0;  // 11 bits; 0x7FF matches one identifier
};

// Stable codes.
enum class FdcanResult : std::uint8_t {
  kOk = 0,
  kTooManyFilters = 1,  // more than 28 standard filters
  kTimeout = 2,         // the controller did not enter or leave configuration
};

// Bytes of a DLC (ISO 11898-1:2015: 0..8, then 12, 16, 20, 24, 32, 48, 64) and the
// smallest DLC that holds `length` bytes (lengths over 64 are not representable).
constexpr std::uint8_t CanDlcToLength(std::uint32_t dlc, bool fd) {
  constexpr std::uint8_t kFd[16] = {0, 1,  2,  3,  4,  5,  6,  7,
                                    8, 12, 16, 20, 24, 32, 48, 64};
  if (!fd) return static_cast<std::uint8_t>(dlc > 8 ? 8 : dlc);
  return kFd[dlc & 15u];
}
constexpr std::uint32_t CanLengthToDlc(std::uint32_t length) {
  if (length <= 8) return length;
  if (length <= 12) return 9;
  if (length <= 16) return 10;
  if (length <= 20) return 11;
  if (length <= 24) return 12;
  if (length <= 32) return 13;
  if (length <= 48) return 14;
  return 15;
}

// Send() (main loop) writes the TX FIFO's put element and requests it: false when the
// FIFO is full, and also for a frame no controller can send (length over 8 classic or 64
// FD) — the caller must not offer such a frame again. An FD frame goes with bit-rate
// switching; an FD length between the DLC steps is padded with zeros to the next step.
// Receive(), TakeBusOff() and counters() are main-loop calls too.
class Stm32g4Fdcan final : public hal::CanPort {
 public:
  static constexpr std::size_t kRxQueueFrames = 16;

  // Main context, before the FDCAN interrupts run; FDCAN's clocks
  // (EnablePeripheralClocks) and pins must be set. Configures the controller as above,
  // with `filters` (at most 28; an empty list receives nothing), starts it and enables
  // IRQs 21 and 22 at kPriorityCan. On an error the controller is left in configuration
  // (off the bus).
  FdcanResult Init(std::span<const CanFilter> filters);

  // FDCAN1_IT0 (IRQ 21): drains RX FIFO 0 into the queue (a full queue drops and counts).
  void ISR_Line0();
  // FDCAN1_IT1 (IRQ 22): bus-off → counted, recovery started.
  void ISR_Line1();

  // True once every frame given to Send has left the controller: all TX FIFO elements
  // free (TXFQS.TFFL = 3). Any context; for a board about to reset that wants its last
  // answer out first.
  bool TransmitIdle() const;

 private:
  bool DoSend(const protocol::CanFrame& frame) override;
  bool DoReceive(protocol::CanFrame* frame) override;
  std::uint32_t DoTakeBusOff() override;
  hal::CanPortCounters DoCounters() const override;

  lockfree::SpscQueue<protocol::CanFrame, kRxQueueFrames> rx_;
  std::atomic<std::uint32_t> received_{0};
  std::atomic<std::uint32_t> fifo_lost_{0};
  std::atomic<std::uint32_t> sent_{0};
  std::atomic<std::uint32_t> bus_off_{0};
  std::atomic<std::uint32_t> bus_off_taken_{0};
};

}  // namespace mjc::stm32g4
