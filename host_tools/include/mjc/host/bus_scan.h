// Every board on a bus, heard without asking (mjc list, mjc flash): their heartbeats,
// bootloaders' BootStatus and BoardInfo frames, per node id, with two boards answering
// for one id told apart (BoardIdentity).
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>

#include "mjc/host/board_client.h"
#include "mjc/host/can_link.h"
#include "mjc/protocol/messages.h"

namespace mjc::host {

struct ScannedNode {
  BoardIdentity identity;
  std::optional<protocol::Heartbeat> heartbeat;  // the last one
  // The last BootStatus: the node runs its bootloader when its last BoardInfo says so
  // (in_bootloader()).
  std::optional<protocol::BootStatus> boot_status;
  // The last ChipInfo (a bootloader's: option bytes, clock, reset flags).
  std::optional<protocol::ChipInfo> chip;
  // Its clock was last read from a BootStatus (a bootloader's), not a heartbeat.
  bool bootloader_clock = false;
  std::map<std::uint16_t, int> infos;  // BoardInfo frames heard, by instance
  std::uint64_t frames = 0;            // frames the node sent
  // It has shown every board behind its id: its clock advanced 1.1 BoardInfo periods
  // since first heard (each board answering for it sent a BoardInfo meanwhile: 110 ms
  // of an application's time, 1.1 s of a bootloader's, which sends one a second and its
  // clock in its BootStatus), or one of its instances sent three BoardInfo frames (two
  // periods of its time, for a board without heartbeats, or two boards whose clocks
  // interleave), or 30 heartbeats or BootStatus frames (three seconds at 10 Hz: a board
  // whose clock does not move). Two boards told apart at once are no exception: the scan
  // goes on while the other nodes' boards may not have spoken yet.
  bool shown = false;
  // A sign of a second board (one BoardInfo of another instance) has been judged: proven
  // by both instances heard twice, or left a sign once five more BoardInfo frames came
  // (a second board would have sent its second meanwhile).
  bool judged = true;

  bool in_bootloader() const {
    return identity.info() && identity.info()->image == protocol::ImageKind::kBootloader;
  }
};

class BusScan {
 public:
  // Nodes the caller expects (a hand's joints). Without it the scan may end once the
  // boards heard first have shown themselves, before a slower one spoke; with it, it
  // goes on until each expected node is heard, or until every node heard has talked for
  // kExpectedWithin of its own time (at 10 heartbeats a second, ten chances for an
  // expected board to speak: one that has not is missing). Board time, so a slow or
  // starved machine does not declare a board missing.
  void Expect(std::set<int> nodes) { expected_ = std::move(nodes); }
  static constexpr std::chrono::milliseconds kExpectedWithin{1000};

  // Takes one frame off the bus; a host's frames and other ids are ignored.
  void Handle(const protocol::CanFrame& frame);
  // True once a node was heard, every node heard has shown itself, and every expected
  // node was heard or given its time (Expect).
  bool Complete() const;
  const std::map<int, ScannedNode>& nodes() const { return nodes_; }

 private:
  std::map<int, ScannedNode> nodes_;
  std::set<int> expected_;
};

enum class ScanEnd : std::uint8_t {
  kComplete = 0,     // every node heard has shown itself
  kSilent = 1,       // nothing at all was heard for the silence cap
  kLinkFailed = 2,   // *why says what
  kInterrupted = 3,  // *interrupt was raised
};

// Listens on `link` (its filters are cleared) until the scan is complete, the bus has
// been silent for `silence` (a bus without a board: the only wall-clock bound, and it
// ends nothing a board is doing), the link fails or *interrupt turns true.
ScanEnd ScanBus(CanLink& link, BusScan* scan, std::chrono::milliseconds silence,
                const std::atomic<bool>* interrupt, std::string* why);

}  // namespace mjc::host
