#include "mjc/sim/link_can_port.h"

namespace mjc::sim {

bool LinkCanPort::DoSend(const protocol::CanFrame& frame) {
  std::string why;
  if (link_->Send(frame, &why)) return true;
  // The link already waited for room (ENOBUFS): the frame is lost, counted, and the
  // board goes on, as a controller whose frame never gets on the bus.
  ++send_failures_;
  error_ = why;
  return true;
}

bool LinkCanPort::Judge(const host::ReceiveResult& r, const std::string& why) {
  switch (r.status) {
    case host::ReceiveStatus::kFrame:
      return true;
    case host::ReceiveStatus::kTimeout:
      return false;
    case host::ReceiveStatus::kDown:
      // The socket stays bound; frames come again once the interface is up (the link
      // keeps the state).
      error_ = why;
      return false;
    case host::ReceiveStatus::kError:
      break;
  }
  failed_ = true;
  error_ = why;
  return false;
}

bool LinkCanPort::WaitForFrame(int timeout_ms) {
  if (waiting_) return true;
  if (failed_) return false;
  std::string why;
  const host::ReceiveResult r = link_->Receive(timeout_ms, &why);
  if (!Judge(r, why)) return false;
  waiting_ = r->frame;
  return true;
}

bool LinkCanPort::DoReceive(protocol::CanFrame* frame) {
  if (waiting_) {
    *frame = *waiting_;
    waiting_.reset();
    ++received_;
    return true;
  }
  if (failed_) return false;
  std::string why;
  const host::ReceiveResult r = link_->Receive(0, &why);
  if (!Judge(r, why)) return false;
  *frame = r->frame;
  ++received_;
  return true;
}

std::uint32_t LinkCanPort::DoTakeBusOff() {
  const std::uint64_t now = link_->stats().bus_off;
  const auto n = static_cast<std::uint32_t>(now - bus_off_seen_);
  bus_off_seen_ = now;
  return n;
}

hal::CanPortCounters LinkCanPort::DoCounters() const {
  hal::CanPortCounters c;
  c.received = received_;
  c.rx_overflow = static_cast<std::uint32_t>(link_->stats().rx_dropped);
  c.sent = static_cast<std::uint32_t>(link_->stats().sent);
  c.bus_off = static_cast<std::uint32_t>(link_->stats().bus_off);
  return c;
}

}  // namespace mjc::sim
