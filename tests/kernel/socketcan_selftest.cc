// The host's SocketCAN links against Debian's real CAN stack (run inside the VM by
// scripts/kernel-vm, with vcan0 at CAN FD MTU): classic and FD frames, filters,
// kernel timestamps, a protocol frame through the codec, a burst with the ENOBUFS
// back-off where every frame must arrive in order, and an ISO-TP transfer. Prints one
// line per check, "vcan_frames_per_s: N frames/s" and "isotp_600B_ms: N ms" figures, and
// the closing "N passed, N failed".
#include <chrono>
#include <cstdio>
#include <ctime>
#include <string>
#include <thread>
#include <vector>

#include "mjc/host/can_link.h"
#include "mjc/protocol/codec.h"
#include "self_check.h"

namespace {

using namespace mjc;
using namespace mjc::host;

kernel_test::SelfCheck check;

protocol::CanFrame Frame(std::uint32_t id, std::uint8_t length, std::uint8_t seed,
                         bool fd) {
  protocol::CanFrame f;
  f.id = id;
  f.length = length;
  f.fd = fd;
  for (std::uint8_t i = 0; i < length; ++i)
    f.data[i] = static_cast<std::uint8_t>(seed + i);
  return f;
}

bool Same(const protocol::CanFrame& a, const protocol::CanFrame& b) {
  if (a.id != b.id || a.length != b.length || a.fd != b.fd) return false;
  for (std::uint8_t i = 0; i < a.length; ++i) {
    if (a.data[i] != b.data[i]) return false;
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string ifname = argc > 1 ? argv[1] : "vcan0";
  std::string why;
  auto tx = SocketCanLink::Open(ifname, &why);
  auto rx = SocketCanLink::Open(ifname, &why);
  if (!tx || !rx) {
    std::printf("FAIL open %s: %s\n0 passed, 1 failed\n", ifname.c_str(), why.c_str());
    return 1;
  }

  // Every wait for a frame is capped, not timed: the cap only ends a wait for a frame
  // that will not come, however slow the machine.
  constexpr int kCapMs = 60000;

  // Classic frame, with its kernel timestamp.
  const auto classic = Frame(0x123, 8, 0x10, false);
  check(tx->Send(classic, &why), "send classic: " + why);
  auto got = rx->Receive(kCapMs, &why);
  check(got && Same(got->frame, classic), "classic frame arrives exactly");
  const double now = static_cast<double>(std::time(nullptr));
  check(got && got->timestamp_s > now - 5 && got->timestamp_s < now + 5,
        "kernel timestamp (SO_TIMESTAMP) is the receive time");

  // A 64-byte CAN FD frame.
  const auto fd = Frame(0x124, 64, 0x80, true);
  check(tx->Send(fd, &why), "send FD: " + why);
  got = rx->Receive(kCapMs, &why);
  check(got && Same(got->frame, fd), "64-byte CAN FD frame arrives exactly");

  // Filters: node 3 only.
  const IdFilter node3{0x003, 0x00F};
  check(rx->SetFilters({&node3, 1}, &why), "set filter: " + why);
  tx->Send(Frame(protocol::MakeId(0x30, 2), 1, 1, false), &why);
  tx->Send(Frame(protocol::MakeId(0x30, 3), 1, 2, false), &why);
  got = rx->Receive(kCapMs, &why);
  const bool only3 = got && protocol::NodeOf(got->frame.id) == 3 && !rx->Receive(50);
  check(only3, "filter passes node 3 and drops node 2");
  rx->SetFilters({}, &why);

  // A protocol frame through the codec and the kernel.
  protocol::Heartbeat hb;
  hb.state = protocol::BoardState::kRunning;
  hb.tick = 424242;
  tx->Send(protocol::Encode(hb, 5), &why);
  got = rx->Receive(kCapMs, &why);
  protocol::Heartbeat back;
  check(got && protocol::Decode(got->frame, &back) == protocol::DecodeError::kOk &&
            back.tick == 424242 && back.state == protocol::BoardState::kRunning,
        "heartbeat encoded, sent, received and decoded");

  // Burst: every frame in order, the sender backing off on ENOBUFS.
  constexpr int kBurst = 20000;
  int received = 0, out_of_order = 0;
  std::thread reader([&] {
    std::string rwhy;
    while (received < kBurst) {
      auto f = rx->Receive(kCapMs, &rwhy);
      if (!f) break;
      const int seq = f->frame.data[0] | (f->frame.data[1] << 8);
      if (seq != received % 65536) ++out_of_order;
      ++received;
    }
  });
  const auto start = std::chrono::steady_clock::now();
  int send_failures = 0;
  for (int i = 0; i < kBurst; ++i) {
    protocol::CanFrame f = Frame(0x200, 8, 0, false);
    f.data[0] = static_cast<std::uint8_t>(i & 0xFF);
    f.data[1] = static_cast<std::uint8_t>((i >> 8) & 0xFF);
    if (!tx->Send(f, &why)) ++send_failures;
  }
  reader.join();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  // Every frame accounted for: received in order, or counted as dropped by the kernel.
  // With the 4 MB receive buffer none is dropped.
  const auto dropped = static_cast<int>(rx->stats().rx_dropped);
  check(send_failures == 0 && received + dropped == kBurst && out_of_order == 0 &&
            dropped == 0,
        "burst of " + std::to_string(kBurst) + " frames: " + std::to_string(received) +
            " received in order, " + std::to_string(dropped) + " dropped, " +
            std::to_string(send_failures) + " send failures, " +
            std::to_string(tx->stats().tx_retries) + " ENOBUFS back-offs");
  std::printf("vcan_frames_per_s: %.0f frames/s\n", received / seconds);

  // ISO-TP: 600 bytes between two ids.
  auto a = IsoTpLink::Open(ifname, 0x3E1, 0x3F1, &why);
  auto b = IsoTpLink::Open(ifname, 0x3F1, 0x3E1, &why);
  check(a && b, "ISO-TP sockets: " + why);
  if (a && b) {
    std::vector<std::uint8_t> payload(600);
    for (std::size_t i = 0; i < payload.size(); ++i)
      payload[i] = static_cast<std::uint8_t>(i * 7);
    const auto t0 = std::chrono::steady_clock::now();
    std::thread sender([&] { a->Send(payload, &why); });
    const auto data = b->Receive(kCapMs, &why);
    sender.join();
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
            .count();
    check(data && *data == payload, "ISO-TP moves 600 bytes intact");
    std::printf("isotp_600B_ms: %.1f ms\n", ms);
  }

  // A missing interface is refused with its name.
  auto none = SocketCanLink::Open("nosuchcan9", &why);
  check(!none && why.find("nosuchcan9") != std::string::npos,
        "missing interface: " + why);

  return check.Finish();
}
