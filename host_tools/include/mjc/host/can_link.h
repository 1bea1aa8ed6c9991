// The host's CAN links. The tools program against CanLink; SocketCanLink talks to a
// Linux CAN interface (real adapters, vcan, vxcan) through raw CAN FD sockets, and
// InProcessBus connects links inside one process for unit tests. IsoTpLink moves
// multi-frame payloads (calibration records) through the kernel's CAN_ISOTP.
//
// Errors never throw: Open returns nullptr, Send returns false and Receive a result
// that says whether it timed out or failed, each with a reason in `why` naming the
// interface and the system's message.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "mjc/protocol/can_frame.h"

namespace mjc::host {

struct ReceivedFrame {
  protocol::CanFrame frame;
  // Kernel receive time (SO_TIMESTAMP): CLOCK_REALTIME microseconds since the epoch,
  // exactly as the kernel reports it (a candump log prints it digit for digit).
  std::int64_t timestamp_us = 0;
  // The same in seconds, for arithmetic only: a double of today's Unix time resolves
  // ~0.2 µs, so it does not convert back to the exact microsecond.
  double timestamp_s = 0;
  // CAN FD flags as received (CANFD_BRS, CANFD_ESI, CANFD_FDF); 0 for a classical frame.
  std::uint8_t flags = 0;
};

enum class ReceiveStatus : std::uint8_t {
  kFrame = 0,    // a frame arrived
  kTimeout = 1,  // none within the timeout
  kError = 2,    // the socket failed (the reason is in `why`)
  // The interface went down (ENETDOWN, once, as the kernel reports it; the reason is in
  // `why`). The socket stays bound: nothing arrives until the interface is up again,
  // and then frames do. A board rides through it; a tool takes it as the link failing.
  kDown = 3,
};

// What Receive returns: a frame, or why there is none. Tests true only for a frame; *
// and -> reach the frame (a default one unless status is kFrame).
struct ReceiveResult {
  ReceiveStatus status = ReceiveStatus::kTimeout;
  ReceivedFrame received;

  explicit operator bool() const { return status == ReceiveStatus::kFrame; }
  // The link failed or went down: for a tool, the end of its exchange with the board.
  bool failed() const {
    return status == ReceiveStatus::kError || status == ReceiveStatus::kDown;
  }
  const ReceivedFrame& operator*() const { return received; }
  const ReceivedFrame* operator->() const { return &received; }
};

struct LinkStats {
  std::uint64_t sent = 0;
  std::uint64_t received = 0;
  std::uint64_t error_frames = 0;  // CAN error frames seen (controller, bus errors)
  std::uint64_t bus_off = 0;       // of those, bus-off reports
  std::uint64_t tx_retries = 0;    // waits for room after ENOBUFS / EAGAIN
  std::uint64_t tx_failed = 0;     // sends given up on
  std::uint64_t rx_dropped = 0;    // frames the kernel dropped for this socket
                                   // (receive buffer full; SO_RXQ_OVFL)
  std::uint64_t went_down = 0;     // times the interface went down (see CanLink::down)
};

struct IdFilter {
  std::uint32_t id = 0;
  std::uint32_t mask = 0;  // a frame passes when (frame.id & mask) == (id & mask)
};

class CanLink {
 public:
  virtual ~CanLink() = default;

  // Queues one frame for transmission. Waits up to 100 ms when the interface's queue is
  // full; false with the reason when it stays full or the interface is down.
  bool Send(const protocol::CanFrame& frame, std::string* why) {
    return DoSend(frame, why);
  }

  // The next data frame that passes the filters, waiting up to timeout_ms (0: only what
  // is already there). On kError *why (when given) says what failed; the link is then
  // unusable and the caller should stop.
  ReceiveResult Receive(int timeout_ms, std::string* why = nullptr) {
    return DoReceive(timeout_ms, why);
  }

  // Only frames matching one of the filters are received (empty: everything).
  bool SetFilters(std::span<const IdFilter> filters, std::string* why) {
    return DoSetFilters(filters, why);
  }

  const LinkStats& stats() const { return stats_; }

  // The interface is down: a send or a receive met ENETDOWN, and no frame has gone or
  // come since. The kernel reports an interface going down once per socket, to whichever
  // call comes first (a write consumes it as well as a read), so both directions feed
  // this one state; a board that sends often would otherwise never see it on receive.
  bool down() const { return down_; }

  // Where the frames go, for messages: the interface's name ("vcan0").
  virtual std::string Name() const { return "the in-process bus"; }

 protected:
  LinkStats stats_;

  // For the implementations: the interface went down (counted once per outage), or a
  // frame went or came, so it is up.
  void NoteDown() {
    if (!down_) ++stats_.went_down;
    down_ = true;
  }
  void NoteUp() { down_ = false; }

 private:
  bool down_ = false;
  virtual bool DoSend(const protocol::CanFrame& frame, std::string* why) = 0;
  virtual ReceiveResult DoReceive(int timeout_ms, std::string* why) = 0;
  virtual bool DoSetFilters(std::span<const IdFilter> filters, std::string* why) = 0;
};

class SocketCanLink final : public CanLink {
 public:
  // Opens a raw socket on `interface` with CAN FD frames, error frames, kernel
  // timestamps and non-blocking I/O. nullptr with the reason when the interface does
  // not exist, the kernel has no CAN support, or permissions are missing.
  static std::unique_ptr<SocketCanLink> Open(const std::string& interface,
                                             std::string* why);
  ~SocketCanLink() override;
  std::string Name() const override { return interface_; }
  SocketCanLink(const SocketCanLink&) = delete;
  SocketCanLink& operator=(const SocketCanLink&) = delete;

 private:
  SocketCanLink(int fd, std::string interface)
      : fd_(fd), interface_(std::move(interface)) {}
  bool DoSend(const protocol::CanFrame& frame, std::string* why) override;
  ReceiveResult DoReceive(int timeout_ms, std::string* why) override;
  bool DoSetFilters(std::span<const IdFilter> filters, std::string* why) override;
  // NoteDown, remembering when (CLOCK_REALTIME µs, as SO_TIMESTAMP).
  void NoteDownNow();

  int fd_;
  std::string interface_;
  std::int64_t down_noted_us_ = 0;
};

// Links that deliver each sent frame to every other link of the same bus, in order.
class InProcessBus : public std::enable_shared_from_this<InProcessBus> {
 public:
  static std::shared_ptr<InProcessBus> Create() {
    return std::shared_ptr<InProcessBus>(new InProcessBus);
  }
  std::unique_ptr<CanLink> Connect();

 private:
  InProcessBus() = default;
  friend class InProcessLink;
  std::mutex mutex_;
  std::condition_variable arrived_;
  std::vector<class InProcessLink*> links_;
};

// ISO 15765-2 transport through the kernel (CAN_ISOTP): payloads up to 4095 bytes
// between `tx_id` (what this side sends on) and `rx_id` (what it listens to).
class IsoTpLink {
 public:
  static std::unique_ptr<IsoTpLink> Open(const std::string& interface,
                                         std::uint32_t tx_id, std::uint32_t rx_id,
                                         std::string* why);
  ~IsoTpLink();
  IsoTpLink(const IsoTpLink&) = delete;
  IsoTpLink& operator=(const IsoTpLink&) = delete;

  bool Send(std::span<const std::uint8_t> payload, std::string* why);
  // The next whole payload, waiting up to timeout_ms (0: only what is there). nullopt
  // with the reason in *why when none came; *failed (when given) then tells a socket
  // error or a transfer of ours the peer never answered with flow control (true) from
  // a plain timeout (false).
  std::optional<std::vector<std::uint8_t>> Receive(int timeout_ms, std::string* why,
                                                   bool* failed = nullptr);

 private:
  explicit IsoTpLink(int fd, std::string interface)
      : fd_(fd), interface_(std::move(interface)) {}
  int fd_;
  std::string interface_;
};

}  // namespace mjc::host
