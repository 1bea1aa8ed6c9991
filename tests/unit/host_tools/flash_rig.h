// A host and a simulated board (sim::BootingBoard: its bootloader, then its application)
// on one in-process bus, in one thread and in the board's time: whenever the host waits
// for a frame, the board runs a millisecond at a time, and the host's clock is the
// board's. So every run is the same, whatever the machine, and a wait bounded by
// silence ends after that much of the board's (simulated) time.
//
// The host's ISO-TP (RigTransport) is written here from ISO 15765-2 (a single frame up
// to 7 bytes, else a first frame, the receiver's flow control, consecutive frames
// 1, 2, … 15, 0, …), not taken from the board's receiver. The rig can cut the board's
// power (the object ends, its flash stays) and power it on again, drop frames either
// way, and watch the board's own reports (its BootStatus progress) to choose when.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "hal/sim/sim_flash.h"
#include "mjc/app/joint_config.h"
#include "mjc/host/can_link.h"
#include "mjc/host/firmware_update.h"
#include "mjc/plant/params.h"
#include "mjc/protocol/codec.h"
#include "mjc/sim/booting_board.h"
#include "mjc/sim/link_can_port.h"

namespace mjc::test {

class FlashRig {
 public:
  static constexpr std::uint32_t kBootloaderBuild = 0xB0071234u;

  explicit FlashRig(std::uint8_t default_node = 1)
      : bus_(host::InProcessBus::Create()),
        flash_(sim::kBoardFlashPages),
        default_node_(default_node) {
    host_ = std::make_unique<SteppedLink>(this, bus_->Connect());
  }

  hal::SimFlash& flash() { return flash_; }
  // Null while the power is off.
  sim::BootingBoard* board() { return board_.get(); }

  // Power on (a new board object on the flash as it is: random RAM, reset cause
  // power-on), and off (a power cut: the object ends between two steps).
  void PowerOn(std::uint64_t ram_seed = 1) {
    board_link_ = bus_->Connect();
    port_ = std::make_unique<sim::LinkCanPort>(board_link_.get());
    sim::BootingBoardConfig c;
    c.app = {
        app::DefaultJointConfig(), {}, sim::kCalibrationPageA, sim::kCalibrationPageB};
    c.app.can.node = default_node_;
    c.app.can.host_timeout_ms = 0;  // the rig sends no host heartbeats
    c.bootloader_build = kBootloaderBuild;
    c.instance = 0x5A5A;
    c.ram_seed = ram_seed;
    board_ = std::make_unique<sim::BootingBoard>(plant::LoadPlantParams("default"), c,
                                                 port_.get(), &flash_);
  }
  void PowerOff() {
    board_.reset();
    port_.reset();
    board_link_.reset();
  }

  // One millisecond of board time (and of the host's clock); then the watch.
  void StepMs() {
    if (board_) {
      for (int i = 0; i < 10; ++i) board_->Tick();
      board_->Poll();
    }
    now_ += std::chrono::milliseconds(1);
    if (watch) watch(*this);
  }
  void RunMs(int ms) {
    for (int i = 0; i < ms; ++i) StepMs();
  }

  // The host's side: its raw link (every wait steps the board), its clock, a frame
  // put on the bus.
  host::CanLink* host_link() { return host_.get(); }
  std::chrono::steady_clock::time_point now() const { return now_; }
  host::BoardClient::Clock clock() {
    return [this] { return now_; };
  }
  void SendFromHost(const protocol::CanFrame& f) {
    std::string why;
    host_->Send(f, &why);
  }
  // Frames the host put on the bus, by function code.
  std::uint64_t host_sent(protocol::Function f) const {
    return host_->sent[static_cast<std::uint8_t>(f)];
  }

  // Called after every step: a test's choice of when to act (a power cut at some
  // progress the board reported).
  std::function<void(FlashRig&)> watch;
  // Board → host frames to drop (true: lost), and host → board ISO-TP frames to drop.
  std::function<bool(const protocol::CanFrame&)> drop_to_host;
  std::function<bool(const protocol::CanFrame&)> drop_to_board;

  // The ISO-TP transport of the rig for `node`.
  std::unique_ptr<host::BootTransport> Transport(std::uint8_t node) {
    return std::make_unique<RigTransport>(this, bus_->Connect(), node);
  }

  host::UpdateOptions Options() {
    host::UpdateOptions o;
    o.now = clock();
    return o;
  }

  // An update of `node` with `image`, the host's clock the rig's.
  host::UpdateResult Update(std::uint8_t node, const host::FirmwareImage& image,
                            host::UpdateOptions options) {
    auto transport = Transport(node);
    host::FirmwareUpdate update(host_link(), transport.get(), node, image,
                                std::move(options));
    return update.Run();
  }
  host::UpdateResult Update(std::uint8_t node, const host::FirmwareImage& image) {
    return Update(node, image, Options());
  }

 private:
  // The host's raw link: Receive steps the board while nothing has arrived.
  class SteppedLink final : public host::CanLink {
   public:
    SteppedLink(FlashRig* rig, std::unique_ptr<host::CanLink> inner)
        : rig_(rig), inner_(std::move(inner)) {}
    std::uint64_t sent[128] = {};

   private:
    bool DoSend(const protocol::CanFrame& f, std::string* why) override {
      ++sent[protocol::FunctionOf(f.id)];
      return inner_->Send(f, why);
    }
    host::ReceiveResult DoReceive(int timeout_ms, std::string* why) override {
      for (int waited = 0;; ++waited) {
        for (host::ReceiveResult r = inner_->Receive(0, why); r;
             r = inner_->Receive(0, why)) {
          if (rig_->drop_to_host && rig_->drop_to_host(r->frame)) continue;
          return r;
        }
        if (waited >= timeout_ms) return {host::ReceiveStatus::kTimeout, {}};
        rig_->StepMs();
      }
    }
    bool DoSetFilters(std::span<const host::IdFilter> filters,
                      std::string* why) override {
      return inner_->SetFilters(filters, why);
    }
    FlashRig* rig_;
    std::unique_ptr<host::CanLink> inner_;
  };

  // ISO 15765-2 sender, classical frames, padded to 8 bytes with 0xCC; the flow
  // control awaited for up to 1000 ms of board time (N_Bs, as the Linux kernel's).
  class RigTransport final : public host::BootTransport {
   public:
    RigTransport(FlashRig* rig, std::unique_ptr<host::CanLink> link, std::uint8_t node)
        : rig_(rig),
          link_(std::move(link)),
          tx_id_(protocol::MakeId(
              static_cast<std::uint8_t>(protocol::Function::kBootIsoTpToBoard), node)),
          rx_id_(protocol::MakeId(
              static_cast<std::uint8_t>(protocol::Function::kBootIsoTpFromBoard), node)) {
      const host::IdFilter only{rx_id_, 0x7FF};
      std::string why;
      link_->SetFilters({&only, 1}, &why);
    }

   private:
    bool Put(std::span<const std::uint8_t> bytes) {
      protocol::CanFrame f;
      f.id = tx_id_;
      f.length = 8;
      f.data.fill(0xCC);
      std::copy(bytes.begin(), bytes.end(), f.data.begin());
      if (rig_->drop_to_board && rig_->drop_to_board(f)) return true;
      std::string why;
      return link_->Send(f, &why);
    }
    bool DoSend(std::span<const std::uint8_t> payload, std::string* why) override {
      std::vector<std::uint8_t> b;
      if (payload.size() <= 7) {
        b.push_back(static_cast<std::uint8_t>(payload.size()));
        b.insert(b.end(), payload.begin(), payload.end());
        return Put(b);
      }
      if (payload.size() > 4095) {
        *why = "over 4095 bytes";
        return false;
      }
      // A flow control left from an earlier transfer is not this one's.
      for (host::ReceiveResult r = link_->Receive(0); r; r = link_->Receive(0)) {
      }
      b = {static_cast<std::uint8_t>(0x10 | (payload.size() >> 8)),
           static_cast<std::uint8_t>(payload.size() & 0xFF)};
      b.insert(b.end(), payload.begin(), payload.begin() + 6);
      Put(b);
      std::optional<std::uint8_t> status;
      for (int ms = 0; ms <= 1000 && !status; ++ms) {
        for (host::ReceiveResult r = link_->Receive(0); r; r = link_->Receive(0)) {
          if ((r->frame.data[0] >> 4) == 3) status = r->frame.data[0] & 0x0F;
        }
        if (!status) rig_->StepMs();
      }
      if (!status || *status != 0) {
        *why = status ? "the receiver reported an overflow" : "no flow control";
        return false;
      }
      std::uint8_t sequence = 1;
      for (std::size_t at = 6; at < payload.size(); at += 7) {
        b = {static_cast<std::uint8_t>(0x20 | sequence)};
        const std::size_t n = std::min<std::size_t>(7, payload.size() - at);
        b.insert(b.end(), payload.begin() + static_cast<std::ptrdiff_t>(at),
                 payload.begin() + static_cast<std::ptrdiff_t>(at + n));
        Put(b);
        sequence = static_cast<std::uint8_t>((sequence + 1) & 0x0F);
      }
      return true;
    }
    FlashRig* rig_;
    std::unique_ptr<host::CanLink> link_;
    std::uint32_t tx_id_;
    std::uint32_t rx_id_;
  };

  std::shared_ptr<host::InProcessBus> bus_;
  hal::SimFlash flash_;
  std::uint8_t default_node_;
  std::unique_ptr<host::CanLink> board_link_;
  std::unique_ptr<sim::LinkCanPort> port_;
  std::unique_ptr<sim::BootingBoard> board_;
  std::unique_ptr<SteppedLink> host_;
  std::chrono::steady_clock::time_point now_{};
};

}  // namespace mjc::test
