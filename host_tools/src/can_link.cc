#include "mjc/host/can_link.h"

#include <fcntl.h>
#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/isotp.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <net/if_arp.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <string>
#include <thread>

namespace mjc::host {
namespace {

std::string Errno(const std::string& what) { return what + ": " + std::strerror(errno); }

void Say(std::string* why, const std::string& text) {
  if (why != nullptr) *why = text;
}

// poll() for one event on fd, up to timeout_ms; false on timeout, with *error set on
// failure.
bool WaitFor(int fd, short events, int timeout_ms, bool* error) {
  pollfd p{fd, events, 0};
  for (;;) {
    const int n = ::poll(&p, 1, timeout_ms);
    if (n < 0 && errno == EINTR) continue;
    *error = n < 0;
    return n > 0;
  }
}

// What `interface` is when it is not CAN, from its ARPHRD type in sysfs ("a loopback
// device", "an Ethernet device", "a network device of type 772"); empty when it is CAN
// (ARPHRD_CAN, 280) or its type cannot be read.
std::string InterfaceKind(const std::string& interface) {
  std::FILE* f = std::fopen(("/sys/class/net/" + interface + "/type").c_str(), "r");
  if (f == nullptr) return "";
  int type = -1;
  const bool read = std::fscanf(f, "%d", &type) == 1;
  std::fclose(f);
  if (!read || type == ARPHRD_CAN) return "";
  switch (type) {
    case ARPHRD_LOOPBACK:
      return "a loopback device";
    case ARPHRD_ETHER:
      return "an Ethernet device";
    default:
      return "a network device of type " + std::to_string(type);
  }
}

int OpenSocket(int type, int protocol, const std::string& interface, std::string* why,
               unsigned* index) {
  if (interface.empty() || interface.size() >= IFNAMSIZ) {
    Say(why, "'" + interface + "' is not an interface name");
    return -1;
  }
  // An interface of another kind (lo, eth0) would be refused by bind() with "No such
  // device", which reads as if it were missing: its type says what it is.
  if (const std::string kind = InterfaceKind(interface); !kind.empty()) {
    Say(why, "'" + interface + "' is not a CAN interface (it is " + kind +
                 "): give a CAN one, e.g. can0 or vcan0 (ip -br link show type can; "
                 "ip -br link show type vcan)");
    return -1;
  }
  const int fd = ::socket(PF_CAN, type | SOCK_NONBLOCK | SOCK_CLOEXEC, protocol);
  if (fd < 0) {
    Say(why, Errno("cannot open a CAN socket (does this kernel have CAN support?)"));
    return -1;
  }
  *index = ::if_nametoindex(interface.c_str());
  if (*index == 0) {
    Say(why, Errno("no CAN interface '" + interface + "'"));
    ::close(fd);
    return -1;
  }
  return fd;
}

// Gives up on a socket being set up: says what failed, with errno, closes it, and
// returns the null link Open returns.
std::nullptr_t CloseFailed(int fd, const std::string& what, std::string* why) {
  Say(why, Errno(what));
  ::close(fd);
  return nullptr;
}

}  // namespace

// --- SocketCAN raw ------------------------------------------------------------------

std::unique_ptr<SocketCanLink> SocketCanLink::Open(const std::string& interface,
                                                   std::string* why) {
  unsigned index = 0;
  const int fd = OpenSocket(SOCK_RAW, CAN_RAW, interface, why, &index);
  if (fd < 0) return nullptr;
  const int on = 1;
  const can_err_mask_t errors = CAN_ERR_MASK;
  if (::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &on, sizeof on) < 0 ||
      ::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &errors, sizeof errors) < 0 ||
      ::setsockopt(fd, SOL_SOCKET, SO_TIMESTAMP, &on, sizeof on) < 0 ||
      ::setsockopt(fd, SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof on) < 0) {
    return CloseFailed(fd, "cannot set up the socket on '" + interface + "'", why);
  }
  // The smallest send buffer the kernel allows (it rounds 0 up to a few frames): a
  // socket that has that much queued gets EAGAIN and poll() reports POLLOUT when the
  // driver frees room, before the interface's own queue (txqueuelen, 10 on CAN) can
  // fill and drop frames with ENOBUFS, which poll() cannot wait for (see DoSend).
  const int send_buffer = 0;
  if (::setsockopt(fd, SOL_SOCKET, SO_SNDBUF, &send_buffer, sizeof send_buffer) < 0) {
    return CloseFailed(fd, "cannot set the send buffer on '" + interface + "'", why);
  }
  // Eight boards at full rate are ~9,000 frames/s: 4 MB holds seconds of them while
  // the tool is busy (the kernel default, ~200 KB, holds about 0.2 s). Without
  // CAP_NET_ADMIN SO_RCVBUFFORCE fails and SO_RCVBUF is capped at rmem_max; either way
  // every frame the kernel still drops is counted (SO_RXQ_OVFL).
  const int buffer = 4 << 20;
  if (::setsockopt(fd, SOL_SOCKET, SO_RCVBUFFORCE, &buffer, sizeof buffer) < 0) {
    ::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &buffer, sizeof buffer);
  }
  sockaddr_can address{};
  address.can_family = AF_CAN;
  address.can_ifindex = static_cast<int>(index);
  if (::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) < 0) {
    return CloseFailed(fd, "cannot bind to '" + interface + "'", why);
  }
  return std::unique_ptr<SocketCanLink>(new SocketCanLink(fd, interface));
}

SocketCanLink::~SocketCanLink() { ::close(fd_); }

void SocketCanLink::NoteDownNow() {
  NoteDown();
  // The same clock as SO_TIMESTAMP.
  down_noted_us_ = std::chrono::duration_cast<std::chrono::microseconds>(
                       std::chrono::system_clock::now().time_since_epoch())
                       .count();
}

bool SocketCanLink::DoSend(const protocol::CanFrame& frame, std::string* why) {
  canfd_frame raw{};
  raw.can_id = frame.id & CAN_SFF_MASK;
  raw.len = frame.length;
  std::memcpy(raw.data, frame.data.data(),
              std::min<std::size_t>(frame.length, CANFD_MAX_DLEN));
  const std::size_t size = frame.fd ? CANFD_MTU : CAN_MTU;
  if (frame.fd) raw.flags = CANFD_BRS;
  // A full transmit queue drains in frame times: wait for room, up to kPatience, rather
  // than dropping the frame or spinning. Two queues can be full. This socket's send
  // buffer (EAGAIN) is what poll() watches: POLLOUT returns once the driver has sent
  // frames and freed them, and Open keeps that buffer small so it fills first. The
  // interface's queue (ENOBUFS: the frame was dropped on the way in, so the buffer
  // stays free and POLLOUT is already set) also fills when other sockets keep it busy;
  // then the wait is a pause of about one frame time (an 8-byte classical frame at
  // 1 Mbit/s takes 135 µs with worst-case stuffing).
  constexpr auto kPatience = std::chrono::milliseconds(100);
  constexpr auto kFrameTime = std::chrono::microseconds(135);
  const auto deadline = std::chrono::steady_clock::now() + kPatience;
  for (;;) {
    const ssize_t n = ::write(fd_, &raw, size);
    if (n == static_cast<ssize_t>(size)) {
      ++stats_.sent;
      NoteUp();
      return true;
    }
    if (n < 0 && errno == ENETDOWN) {
      Say(why, Errno("cannot send on '" + interface_ + "'"));
      NoteDownNow();
      ++stats_.tx_failed;
      return false;
    }
    if (n >= 0 || (errno != ENOBUFS && errno != EAGAIN)) break;
    const bool queue_full = errno == ENOBUFS;
    const auto left = std::chrono::ceil<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) {
      ++stats_.tx_failed;
      Say(why, "'" + interface_ + "': transmit queue stayed full (" +
                   (queue_full ? "ENOBUFS" : "EAGAIN") + ") for 100 ms");
      return false;
    }
    ++stats_.tx_retries;
    bool error = false;
    if (!WaitFor(fd_, POLLOUT, static_cast<int>(left.count()), &error) && error) break;
    if (queue_full) std::this_thread::sleep_for(kFrameTime);
  }
  ++stats_.tx_failed;
  Say(why, Errno("cannot send on '" + interface_ + "'"));
  return false;
}

ReceiveResult SocketCanLink::DoReceive(int timeout_ms, std::string* why) {
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  for (;;) {
    canfd_frame raw{};
    iovec io{&raw, sizeof raw};
    alignas(cmsghdr) char
        control[CMSG_SPACE(sizeof(timeval)) + CMSG_SPACE(sizeof(std::uint32_t))];
    msghdr message{};
    message.msg_iov = &io;
    message.msg_iovlen = 1;
    message.msg_control = control;
    message.msg_controllen = sizeof control;
    const ssize_t n = ::recvmsg(fd_, &message, 0);
    if (n < 0) {
      if (errno == ENETDOWN) {
        NoteDownNow();
        Say(why, "'" + interface_ + "' went down");
        return {ReceiveStatus::kDown, {}};
      }
      if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) {
        Say(why, Errno("cannot receive on '" + interface_ + "'"));
        return {ReceiveStatus::kError, {}};
      }
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
                            deadline - std::chrono::steady_clock::now())
                            .count();
      if (left <= 0) return {ReceiveStatus::kTimeout, {}};
      bool error = false;
      if (!WaitFor(fd_, POLLIN, static_cast<int>(left), &error) && error) {
        Say(why, Errno("poll on '" + interface_ + "'"));
        return {ReceiveStatus::kError, {}};
      }
      continue;
    }
    if (raw.can_id & CAN_ERR_FLAG) {
      ++stats_.error_frames;
      if (raw.can_id & CAN_ERR_BUSOFF) ++stats_.bus_off;
      continue;
    }
    if (raw.can_id & (CAN_EFF_FLAG | CAN_RTR_FLAG)) continue;  // not our protocol's
    ReceiveResult out{ReceiveStatus::kFrame, {}};
    ReceivedFrame& r = out.received;
    r.frame.id = raw.can_id & CAN_SFF_MASK;
    r.frame.length = raw.len;
    r.frame.fd = n == static_cast<ssize_t>(CANFD_MTU);
    if (r.frame.fd) r.flags = raw.flags;
    std::memcpy(r.frame.data.data(), raw.data, std::min<std::size_t>(raw.len, 64));
    for (cmsghdr* c = CMSG_FIRSTHDR(&message); c != nullptr;
         c = CMSG_NXTHDR(&message, c)) {
      if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_TIMESTAMP) {
        timeval tv{};
        std::memcpy(&tv, CMSG_DATA(c), sizeof tv);
        r.timestamp_us = std::int64_t{tv.tv_sec} * 1000000 + tv.tv_usec;
        r.timestamp_s = static_cast<double>(r.timestamp_us) * 1e-6;
      } else if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_RXQ_OVFL) {
        std::uint32_t dropped = 0;  // the socket's cumulative drop count
        std::memcpy(&dropped, CMSG_DATA(c), sizeof dropped);
        stats_.rx_dropped = dropped;
      }
    }
    ++stats_.received;
    // A frame received before the interface went down can still sit in the socket's
    // queue after the outage was noted: only a later one says it is up again.
    if (r.timestamp_us > down_noted_us_) NoteUp();
    return out;
  }
}

bool SocketCanLink::DoSetFilters(std::span<const IdFilter> filters, std::string* why) {
  std::vector<can_filter> raw;
  for (const IdFilter& f : filters)
    raw.push_back({f.id, f.mask | CAN_EFF_FLAG | CAN_RTR_FLAG});
  // On SocketCAN an empty filter list receives nothing; ours means everything: the
  // kernel's own default, one filter with a zero mask.
  if (raw.empty()) raw.push_back({0, 0});
  const auto size = static_cast<socklen_t>(raw.size() * sizeof(can_filter));
  if (::setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_FILTER, raw.data(), size) < 0) {
    Say(why, Errno("'" + interface_ + "': CAN_RAW_FILTER"));
    return false;
  }
  return true;
}

// --- in-process bus -----------------------------------------------------------------

class InProcessLink final : public CanLink {
 public:
  explicit InProcessLink(std::shared_ptr<InProcessBus> bus) : bus_(std::move(bus)) {
    std::lock_guard lock(bus_->mutex_);
    bus_->links_.push_back(this);
  }
  ~InProcessLink() override {
    std::lock_guard lock(bus_->mutex_);
    std::erase(bus_->links_, this);
  }

 private:
  bool Passes(const protocol::CanFrame& f) const {
    if (filters_.empty()) return true;
    return std::any_of(filters_.begin(), filters_.end(), [&](const IdFilter& x) {
      return (f.id & x.mask) == (x.id & x.mask);
    });
  }
  bool DoSend(const protocol::CanFrame& frame, std::string*) override {
    std::lock_guard lock(bus_->mutex_);
    ReceivedFrame sent;
    sent.frame = frame;
    sent.timestamp_us = std::chrono::duration_cast<std::chrono::microseconds>(
                            std::chrono::system_clock::now().time_since_epoch())
                            .count();
    sent.timestamp_s = static_cast<double>(sent.timestamp_us) * 1e-6;
    for (InProcessLink* other : bus_->links_) {
      if (other != this && other->Passes(frame)) other->queue_.push_back(sent);
    }
    ++stats_.sent;
    bus_->arrived_.notify_all();
    return true;
  }
  ReceiveResult DoReceive(int timeout_ms, std::string*) override {
    std::unique_lock lock(bus_->mutex_);
    if (timeout_ms > 0) {  // a zero timeout only looks: no timed wait, no syscall
      bus_->arrived_.wait_for(lock, std::chrono::milliseconds(timeout_ms),
                              [this] { return !queue_.empty(); });
    }
    if (queue_.empty()) return {ReceiveStatus::kTimeout, {}};
    ReceiveResult out{ReceiveStatus::kFrame, queue_.front()};
    queue_.pop_front();
    ++stats_.received;
    return out;
  }
  bool DoSetFilters(std::span<const IdFilter> filters, std::string*) override {
    std::lock_guard lock(bus_->mutex_);
    filters_.assign(filters.begin(), filters.end());
    return true;
  }

  std::shared_ptr<InProcessBus> bus_;
  std::deque<ReceivedFrame> queue_;
  std::vector<IdFilter> filters_;
};

std::unique_ptr<CanLink> InProcessBus::Connect() {
  return std::make_unique<InProcessLink>(shared_from_this());
}

// --- ISO-TP -------------------------------------------------------------------------

std::unique_ptr<IsoTpLink> IsoTpLink::Open(const std::string& interface,
                                           std::uint32_t tx_id, std::uint32_t rx_id,
                                           std::string* why) {
  unsigned index = 0;
  const int fd = OpenSocket(SOCK_DGRAM, CAN_ISOTP, interface, why, &index);
  if (fd < 0) return nullptr;
  // Each Send returns its own transfer's outcome. Otherwise the kernel reports a
  // transfer that failed (no flow control within its fixed 1 s: ECOMM) on the next call
  // on the socket, whichever that is, and the next transfer is then never tried.
  // CAN_ISOTP_WAIT_TX_DONE makes the write wait for the transfer's last frame, and a
  // blocking socket lets it (Receive polls before it reads). The kernel takes ISO-TP
  // options only before the bind.
  can_isotp_options options{};
  socklen_t size = sizeof options;
  if (::getsockopt(fd, SOL_CAN_ISOTP, CAN_ISOTP_OPTS, &options, &size) < 0) {
    return CloseFailed(fd, "cannot read the ISO-TP options on '" + interface + "'", why);
  }
  options.flags |= CAN_ISOTP_WAIT_TX_DONE;
  const int flags = ::fcntl(fd, F_GETFL);
  if (::setsockopt(fd, SOL_CAN_ISOTP, CAN_ISOTP_OPTS, &options, sizeof options) < 0 ||
      flags < 0 || ::fcntl(fd, F_SETFL, flags & ~O_NONBLOCK) < 0) {
    return CloseFailed(fd, "cannot set up ISO-TP on '" + interface + "'", why);
  }
  sockaddr_can address{};
  address.can_family = AF_CAN;
  address.can_ifindex = static_cast<int>(index);
  address.can_addr.tp.tx_id = tx_id & CAN_SFF_MASK;
  address.can_addr.tp.rx_id = rx_id & CAN_SFF_MASK;
  if (::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) < 0) {
    return CloseFailed(
        fd, "cannot bind ISO-TP on '" + interface + "' (is can-isotp loaded?)", why);
  }
  return std::unique_ptr<IsoTpLink>(new IsoTpLink(fd, interface));
}

IsoTpLink::~IsoTpLink() { ::close(fd_); }

bool IsoTpLink::Send(std::span<const std::uint8_t> payload, std::string* why) {
  if (payload.empty() || payload.size() > 4095) {
    Say(why, "ISO-TP payloads are 1..4095 bytes, not " + std::to_string(payload.size()));
    return false;
  }
  bool error = false;
  for (int attempt = 0; attempt < 100; ++attempt) {
    const ssize_t n = ::write(fd_, payload.data(), payload.size());
    if (n == static_cast<ssize_t>(payload.size())) return true;
    if (n < 0 && (errno == EAGAIN || errno == EBUSY)) {
      WaitFor(fd_, POLLOUT, 10, &error);
      continue;
    }
    // ECOMM: this transfer's first frame got no flow control within the kernel's 1 s.
    Say(why, errno == ECOMM ? "no ISO-TP flow control from the peer on '" + interface_ +
                                  "' within the kernel's 1 s"
                            : Errno("ISO-TP send on '" + interface_ + "'"));
    return false;
  }
  Say(why, "ISO-TP send on '" + interface_ + "': the previous transfer did not finish");
  return false;
}

std::optional<std::vector<std::uint8_t>> IsoTpLink::Receive(int timeout_ms,
                                                            std::string* why,
                                                            bool* failed) {
  bool error = false;
  if (failed != nullptr) *failed = true;
  if (!WaitFor(fd_, POLLIN, timeout_ms, &error)) {
    if (failed != nullptr) *failed = error;
    Say(why, error ? Errno("ISO-TP poll on '" + interface_ + "'")
                   : "no ISO-TP reply on '" + interface_ + "' within " +
                         std::to_string(timeout_ms) + " ms");
    return std::nullopt;
  }
  std::vector<std::uint8_t> buffer(4096);
  const ssize_t n = ::read(fd_, buffer.data(), buffer.size());
  if (n < 0) {
    // ECOMM: our last transfer failed because the peer sent no flow control in time.
    Say(why, errno == ECOMM ? "no ISO-TP flow control from the peer on '" + interface_ +
                                  "' (absent or silent)"
                            : Errno("ISO-TP receive on '" + interface_ + "'"));
    return std::nullopt;
  }
  buffer.resize(static_cast<std::size_t>(n));
  if (failed != nullptr) *failed = false;
  return buffer;
}

}  // namespace mjc::host
