// A simulated board's CAN controller on a host link: a SocketCAN interface (mjc sim), or
// the in-process bus of the tests. The port's frames are the link's; the link's bus-off
// error frames stand for the controller's own bus-off (a simulated controller rejoins at
// once, as the board's does after its recovery sequence).
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "hal/can_port.h"
#include "mjc/host/can_link.h"

namespace mjc::sim {

class LinkCanPort final : public hal::CanPort {
 public:
  // `link` must outlive the port.
  explicit LinkCanPort(host::CanLink* link)
      : link_(link), bus_off_seen_(link->stats().bus_off) {}

  // Once the link failed (the interface went away, not only down): why. The port then
  // receives nothing; the owner should stop.
  bool failed() const { return failed_; }
  const std::string& error() const { return error_; }
  // Frames the link could not send (each one lost, as a controller that gives up).
  std::uint32_t send_failures() const { return send_failures_; }
  // The interface is down (the link said so, and no frame has come or gone since): the
  // board rides through, as a real one whose bus is unplugged. Times it went down.
  bool down() const { return link_->down(); }
  std::uint32_t times_down() const {
    return static_cast<std::uint32_t>(link_->stats().went_down);
  }

  // Waits up to timeout_ms for a frame, kept for the next Receive: true when one is
  // there. For a board with nothing to do until a frame comes (the simulated
  // bootloader), which then answers at once instead of at its next pass.
  bool WaitForFrame(int timeout_ms);

 private:
  bool DoSend(const protocol::CanFrame& frame) override;
  bool DoReceive(protocol::CanFrame* frame) override;
  std::uint32_t DoTakeBusOff() override;
  // True for a frame; otherwise notes the link down or failed.
  bool Judge(const host::ReceiveResult& r, const std::string& why);
  hal::CanPortCounters DoCounters() const override;

  host::CanLink* link_;
  std::optional<protocol::CanFrame> waiting_;  // taken by WaitForFrame
  std::uint64_t bus_off_seen_;
  std::uint32_t received_ = 0;
  std::uint32_t send_failures_ = 0;
  bool failed_ = false;
  std::string error_;
};

}  // namespace mjc::sim
