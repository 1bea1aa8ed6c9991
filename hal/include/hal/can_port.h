// The board's CAN controller as the main loop sees it: frames in and out, and the
// controller's own troubles (bus-off). A slow device behind a small virtual interface
// (called from the main loop, never from the control tick). The STM32G4 driver receives
// by interrupt into a queue and transmits through the controller's FIFO; the simulated
// board's port is a SocketCAN socket or an in-process bus.
#pragma once

#include <cstdint>

#include "mjc/protocol/can_frame.h"

namespace mjc::hal {

struct CanPortCounters {
  std::uint32_t received = 0;     // frames handed to Receive's caller
  std::uint32_t rx_overflow = 0;  // frames lost on the way in (FIFO or queue full)
  std::uint32_t sent = 0;         // frames the controller took for transmission
  std::uint32_t bus_off = 0;      // bus-off events, each already being recovered from
  std::uint8_t tx_errors = 0;     // the controller's transmit error counter now
  std::uint8_t rx_errors = 0;     // its receive error counter now
  // The controller's protocol status now (CAN error states, ISO 11898-1).
  bool error_warning = false;  // a counter has reached 96
  bool error_passive = false;  // a counter has reached 128
  bool bus_off_now = false;    // the controller is off the bus (recovering)
  // The last error seen on the bus since the previous counters() call: 0 none, 1 stuff,
  // 2 form, 3 acknowledge, 4 bit 1, 5 bit 0, 6 CRC, 7 no change (ISO 11898-1 / M_CAN
  // LEC coding); a port without this knowledge reports 7.
  std::uint8_t last_error = 7;
};

class CanPort {
 public:
  virtual ~CanPort() = default;

  // Queues `frame` for transmission; false when the controller has no room now (the
  // caller keeps the frame and offers it again on a later poll).
  bool Send(const protocol::CanFrame& frame) { return DoSend(frame); }
  // The next received frame, oldest first; false when there is none.
  bool Receive(protocol::CanFrame* frame) { return DoReceive(frame); }
  // Bus-off events since the last call. The port has already started the controller's
  // recovery; the caller stops the motor (it cannot hear a stop meanwhile).
  std::uint32_t TakeBusOff() { return DoTakeBusOff(); }
  CanPortCounters counters() const { return DoCounters(); }

 private:
  virtual bool DoSend(const protocol::CanFrame& frame) = 0;
  virtual bool DoReceive(protocol::CanFrame* frame) = 0;
  virtual std::uint32_t DoTakeBusOff() = 0;
  virtual CanPortCounters DoCounters() const = 0;
};

}  // namespace mjc::hal
