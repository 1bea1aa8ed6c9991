#include "mjc/host/bus_scan.h"

#include <algorithm>

#include "mjc/boot/bootloader.h"
#include "mjc/protocol/codec.h"

namespace mjc::host {

using protocol::BoardInfo;
using protocol::BootStatus;
using protocol::CanFrame;
using protocol::DecodeError;
using protocol::Function;
using protocol::FunctionOf;
using protocol::Heartbeat;
using protocol::kBoardTickHz;
using protocol::kMaxNode;
using protocol::kMinNode;
using protocol::NodeOf;
using protocol::SentByBoard;

void BusScan::Handle(const CanFrame& f) {
  const int node = NodeOf(f.id);
  const std::uint8_t function = FunctionOf(f.id);
  if (node < kMinNode || node > kMaxNode || !SentByBoard(function)) return;
  ScannedNode& n = nodes_[node];
  ++n.frames;
  if (function == static_cast<std::uint8_t>(Function::kBoardInfo)) {
    BoardInfo info;
    if (Decode(f, &info) != DecodeError::kOk) return;
    n.identity.OnInfo(info);
    ++n.infos[info.instance];
  } else if (function == static_cast<std::uint8_t>(Function::kHeartbeat)) {
    Heartbeat h;
    if (Decode(f, &h) != DecodeError::kOk) return;
    n.identity.OnHeartbeat(h.tick);
    n.heartbeat = h;
    n.bootloader_clock = false;
  } else if (function == static_cast<std::uint8_t>(Function::kBootStatus)) {
    // The bootloader's clock, in ms, told apart and compared like a heartbeat's ticks.
    BootStatus s;
    if (Decode(f, &s) != DecodeError::kOk) return;
    n.identity.OnHeartbeat(s.tick_ms * (kBoardTickHz / 1000u));
    n.boot_status = s;
    n.bootloader_clock = true;
  } else if (function == static_cast<std::uint8_t>(Function::kChipInfo)) {
    protocol::ChipInfo c;
    if (Decode(f, &c) == DecodeError::kOk) n.chip = c;
    return;
  } else {
    return;
  }
  constexpr auto kTicks = static_cast<std::uint32_t>(kBoardInfoPeriod.count() * 11 / 10 *
                                                     kBoardTickHz / 1000);
  constexpr auto kBootTicks =
      boot::Bootloader::kInfoPeriodMs * 11 / 10 * (kBoardTickHz / 1000u);
  int most_infos = 0;
  for (const auto& [instance, count] : n.infos) most_infos = std::max(most_infos, count);
  n.shown = n.shown || most_infos >= 3 || n.identity.heartbeats() >= 30 ||
            n.identity.elapsed_ticks() >= (n.bootloader_clock ? kBootTicks : kTicks);
  n.judged = !n.identity.ambiguous() || n.identity.proven() ||
             n.identity.infos_since_sign() >= 5;
}

bool BusScan::Complete() const {
  if (nodes_.empty()) return false;
  for (const auto& [node, n] : nodes_) {
    if (!n.shown || !n.judged) return false;
  }
  constexpr auto kGiven =
      static_cast<std::uint32_t>(BusScan::kExpectedWithin.count() * kBoardTickHz / 1000);
  for (const int node : expected_) {
    if (nodes_.count(node) != 0) continue;
    for (const auto& [heard, n] : nodes_) {
      if (n.identity.elapsed_ticks() < kGiven) return false;
    }
  }
  return true;
}

ScanEnd ScanBus(CanLink& link, BusScan* scan, std::chrono::milliseconds silence,
                const std::atomic<bool>* interrupt, std::string* why) {
  link.SetFilters({}, why);
  auto heard = std::chrono::steady_clock::now();
  for (;;) {
    if (scan->Complete()) return ScanEnd::kComplete;
    if (interrupt != nullptr && *interrupt) return ScanEnd::kInterrupted;
    const ReceiveResult r = link.Receive(20, why);
    if (r.failed()) return ScanEnd::kLinkFailed;
    const auto now = std::chrono::steady_clock::now();
    if (r) {
      heard = now;
      scan->Handle(r->frame);
    } else if (now - heard > silence) {
      return ScanEnd::kSilent;
    }
  }
}

}  // namespace mjc::host
