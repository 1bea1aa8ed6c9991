// A board and a host for the bootloader's tests: the bootloader's logic over any
// hal::Flash (the simulated flash, or the G474 FLASH driver on the register model), a
// CAN port that is two queues, the handoff block as plain memory, and a host that
// speaks the update protocol (its own ISO-TP segmentation, written here from ISO
// 15765-2, not the board's receiver).
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <optional>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "hal/can_port.h"
#include "hal/flash.h"
#include "image_file.h"
#include "mjc/boot/bootloader.h"
#include "mjc/boot/handoff.h"
#include "mjc/boot/layout.h"
#include "mjc/protocol/codec.h"

namespace mjc::boot::test {

inline constexpr std::uint8_t kNode = 3;
inline constexpr std::uint16_t kBoardType = 1;
inline constexpr std::uint8_t kHardware = 1;

// Two queues: frames the host put on the bus for the board, frames the board sent.
class QueueCan final : public hal::CanPort {
 public:
  std::deque<protocol::CanFrame> to_board;
  std::deque<protocol::CanFrame> from_board;
  std::size_t tx_room = ~std::size_t{0};  // frames Send accepts before "FIFO full"

 private:
  bool DoSend(const protocol::CanFrame& f) override {
    if (tx_room == 0) return false;
    if (tx_room != ~std::size_t{0}) --tx_room;
    from_board.push_back(f);
    return true;
  }
  bool DoReceive(protocol::CanFrame* f) override {
    if (to_board.empty()) return false;
    *f = to_board.front();
    to_board.pop_front();
    return true;
  }
  std::uint32_t DoTakeBusOff() override { return 0; }
  hal::CanPortCounters DoCounters() const override { return {}; }
};

// Forwards to another flash and records every erase and program (page, offset).
class SpyFlash final : public hal::Flash {
 public:
  explicit SpyFlash(hal::Flash* inner) : inner_(inner) {}
  struct Op {
    bool erase;
    std::uint32_t page;
    std::uint32_t offset;
  };
  std::vector<Op> ops;

 private:
  hal::FlashResult DoErasePage(std::uint32_t page) override {
    ops.push_back({true, page, 0});
    return inner_->ErasePage(page);
  }
  hal::FlashResult DoProgram(std::uint32_t page, std::uint32_t offset,
                             std::uint64_t value) override {
    ops.push_back({false, page, offset});
    return inner_->ProgramDoubleWord(page, offset, value);
  }
  hal::FlashResult DoRead(std::uint32_t page, std::uint32_t offset,
                          std::span<std::uint8_t> out) const override {
    return inner_->Read(page, offset, out);
  }
  std::uint32_t DoPageCount() const override { return inner_->page_count(); }
  hal::Flash* inner_;
};

// A linked image as objcopy writes it, for the G474 layout: a vector table (stack in
// SRAM, reset handler inside), then bytes that depend on `seed`.
std::vector<std::uint8_t> MakeImage(std::size_t bytes, std::uint32_t seed);
// Its file (header in front), built for the test board (type 1, hardware 1..1).
std::vector<std::uint8_t> MakeFile(std::span<const std::uint8_t> image,
                                   std::uint16_t board_type = kBoardType,
                                   std::uint8_t hw_min = kHardware,
                                   std::uint8_t hw_max = kHardware);

// Writes `file` into the application region as a debugger would (erase, program).
void Install(hal::Flash& flash, std::span<const std::uint8_t> file,
             const BootLayout& layout = kG474Layout);
// The region's bytes [0, n).
std::vector<std::uint8_t> RegionBytes(hal::Flash& flash, std::size_t n,
                                      const BootLayout& layout = kG474Layout);

BootloaderConfig TestConfig();

// ISO-TP segmentation (sender side): a single frame up to 7 bytes, else a first frame
// and consecutive frames, each padded to 8 bytes with 0xCC.
std::vector<protocol::CanFrame> IsoTpSegments(std::uint32_t id,
                                              std::span<const std::uint8_t> payload);
std::vector<std::uint8_t> BeginRequest(std::span<const std::uint8_t> file,
                                       std::uint8_t sequence = 0);
std::vector<std::uint8_t> ChunkRequest(std::uint32_t offset,
                                       std::span<const std::uint8_t> data,
                                       std::uint8_t sequence = 0);

// One board: the bootloader on `flash`, with its clock, CAN queues and handoff block.
struct Board {
  Board(hal::Flash* flash, volatile BootHandoff* handoff,
        BootloaderConfig config = TestConfig())
      : boot(config, flash, &can, handoff) {}
  QueueCan can;
  Bootloader boot;
  std::uint32_t now_ms = 0;

  BootAction Start(bool software_reset = false) {
    return boot.Start(now_ms, software_reset);
  }
  // Advances the clock by `ms` and polls once.
  BootAction Step(std::uint32_t ms = 1) {
    now_ms += ms;
    return boot.Poll(now_ms);
  }
  void Send(const protocol::CanFrame& f) { can.to_board.push_back(f); }
  void SendIsoTp(std::span<const std::uint8_t> payload);
  // Frames the board sent of type M, decoded, oldest first (taken from the queue).
  template <class M>
  std::vector<M> Take() {
    std::vector<M> out;
    for (auto it = can.from_board.begin(); it != can.from_board.end();) {
      M m;
      if (protocol::Decode(*it, &m) == protocol::DecodeError::kOk &&
          protocol::NodeOf(it->id) == kNode) {
        out.push_back(m);
        it = can.from_board.erase(it);
      } else {
        ++it;
      }
    }
    return out;
  }
  // The last BootResult the board sent (the others dropped), if any.
  std::optional<protocol::BootResult> LastResult();
};

// The host's side of an update, request by request, as `mjc flash` will do it: each
// request is sent, the board polled (1 ms steps) until it answers; false when a
// request was refused or the board stopped answering (a power cut). Results are kept.
struct HostUpdate {
  std::vector<protocol::BootResult> results;
  bool Run(Board& board, std::span<const std::uint8_t> file,
           std::size_t chunk_bytes = kMaxChunkData);
  // One request; the board's answer (nullopt: none within `patience` polls).
  std::optional<protocol::BootResult> Request(
      Board& board, std::span<const std::uint8_t> iso_tp_payload, int patience = 50);
  std::optional<protocol::BootResult> Command(Board& board, protocol::BootRequest r,
                                              int patience = 50);

 private:
  // The board's answer to what was just sent, kept in `results`; nullopt: none within
  // `patience` polls.
  std::optional<protocol::BootResult> AwaitResult(Board& board, int patience);
};

}  // namespace mjc::boot::test
