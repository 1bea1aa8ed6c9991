// The bootloader's whole run on the joint board (G474Bootloader: what the image's main()
// runs) against the chip's register models, with the real drivers: FDCAN1 on a bus the
// test plays the host on (frames at their time on the bus), the FLASH model, the
// watchdog, the clock tree. An update from the first frame to the reset into the new
// image, the hold window, the node id from the identity pages, and the state it hands
// over in. Every rule of the reference manual the drivers break is a failure.
#include "mjc/boot/g474_bootloader.h"

#include <gtest/gtest.h>

#include <deque>
#include <functional>
#include <optional>
#include <vector>

#include "boot_rig.h"
#include "hal/stm32g4/clock.h"
#include "hal/stm32g4/flash.h"
#include "hal/stm32g4/nvic.h"
#include "mjc/boot/identity_store.h"
#include "mjc/g474model/virtual_chip.h"
#include "mjc/protocol/codec.h"

namespace {

using namespace mjc;
using namespace mjc::boot;
using g474model::CanBusFrame;
using g474model::Picoseconds;
using g474model::VirtualChip;
using protocol::BootError;
using protocol::BootRequest;
using protocol::BootState;
using protocol::StayReason;

constexpr Picoseconds kMs = 1'000'000'000;
// A classical frame of 8 bytes at 1 Mbit/s with stuffing: about 130 µs on the bus.
constexpr Picoseconds kFrameTime = 130'000'000;

g474model::ChipConfig Board() {
  g474model::ChipConfig c;
  c.rcc.hse_hz = stm32g4::kHseHz;
  return c;
}

protocol::CanFrame FromBus(const CanBusFrame& f) {
  protocol::CanFrame c;
  c.id = f.id;
  c.length = f.length;
  c.fd = f.fd;
  c.data = f.data;
  return c;
}
CanBusFrame ToBus(const protocol::CanFrame& f) {
  CanBusFrame b;
  b.id = f.id;
  b.dlc = f.length;
  b.length = f.length;
  b.data = f.data;
  return b;
}

// The chip, bound, with the test as the rest of the bus.
class Rig {
 public:
  Rig() : chip_(Board()) {
    stm32g4::BindRegisterSpace(&chip_);
    chip_.fdcan1().SetTransmitHook([this](const CanBusFrame& f, Picoseconds at) {
      sent.push_back({FromBus(f), at});
      if (on_frame) on_frame(FromBus(f), at);
    });
  }
  ~Rig() { stm32g4::BindRegisterSpace(nullptr); }
  VirtualChip& chip() { return chip_; }

  // Puts `frame` on the bus at `at` (delivered if the controller listens by then).
  void Deliver(Picoseconds at, const protocol::CanFrame& frame) {
    chip_.Schedule(at, [this, frame] { (void)chip_.DeliverCanFrame(ToBus(frame)); });
  }

  // One run of the bootloader from reset: its exit, or nullopt when it was still
  // serving the bus at `until` (or the chip reset).
  std::optional<g474::Exit> Run(Picoseconds until) {
    chip_.SetTimeLimit(until);
    std::optional<g474::Exit> exit;
    try {
      bootloader_.emplace(&handoff);
      exit = bootloader_->Run();
    } catch (const g474model::TimeLimitReached&) {
    } catch (const g474model::ChipReset& reset) {
      resets.push_back(reset.cause);
    }
    chip_.SetTimeLimit(g474model::kNever);  // the test reads registers afterwards
    return exit;
  }

  // Frames the board sent of type M (from node `node`), with their times.
  template <class M>
  std::vector<std::pair<M, Picoseconds>> Sent(std::uint8_t node = 1) const {
    std::vector<std::pair<M, Picoseconds>> out;
    for (const auto& [f, at] : sent) {
      M m;
      if (protocol::NodeOf(f.id) == node &&
          protocol::Decode(f, &m) == protocol::DecodeError::kOk) {
        out.push_back({m, at});
      }
    }
    return out;
  }

  BootHandoff handoff{};
  std::vector<std::pair<protocol::CanFrame, Picoseconds>> sent;
  std::function<void(const protocol::CanFrame&, Picoseconds)> on_frame;
  std::vector<g474model::ResetCause> resets;

 private:
  VirtualChip chip_;
  std::optional<g474::G474Bootloader> bootloader_;
};

std::string Violations(VirtualChip& chip) { return chip.violations().ToString(); }

TEST(G474Bootloader, WithoutAnImageItStaysAndReportsOnTheBus) {
  Rig rig;
  EXPECT_FALSE(rig.Run(250 * kMs));
  EXPECT_TRUE(rig.resets.empty()) << "the watchdog is refreshed";
  const auto info = rig.Sent<protocol::BoardInfo>();
  ASSERT_EQ(info.size(), 1u);
  EXPECT_EQ(info[0].first.image, protocol::ImageKind::kBootloader);
  EXPECT_EQ(info[0].first.reset_cause, protocol::ResetCause::kPowerOn);
  const auto status = rig.Sent<protocol::BootStatus>();
  ASSERT_GE(status.size(), 3u);
  for (const auto& [s, at] : status) {
    EXPECT_EQ(s.state, BootState::kReady);
    EXPECT_EQ(s.reason, StayReason::kNoValidImage);
    EXPECT_EQ(s.error, BootError::kNoImage);
  }
  // Every 100 ms of the board's clock (the crystal's: the virtual time).
  const Picoseconds period = status[2].second - status[1].second;
  EXPECT_NEAR(static_cast<double>(period) / kMs, 100.0, 0.1);
  EXPECT_EQ(rig.chip().fdcan1().nominal_bitrate(), 1e6);
  EXPECT_EQ(rig.chip().gpio('B').Level(10), false) << "the bridge's enable";
  EXPECT_EQ(boot::g474::PeekResetFlags().cause, protocol::ResetCause::kUnknown)
      << "staying, it cleared this reset's flags";
  EXPECT_TRUE(rig.chip().violations().empty()) << Violations(rig.chip());
}

TEST(G474Bootloader, AValidImageStartsAfterTheHoldWindowInTheResetState) {
  Rig rig;
  const auto file = test::MakeFile(test::MakeImage(3000, 41));
  auto& memory = rig.chip().flash().mutable_contents();
  std::copy(file.begin(), file.end(), memory.begin() + 8 * 2048);
  const auto exit = rig.Run(1000 * kMs);
  ASSERT_TRUE(exit);
  EXPECT_EQ(exit->action, BootAction::kBoot);
  EXPECT_EQ(exit->vector_table, 0x08004200u);
  const auto status = rig.Sent<protocol::BootStatus>();
  ASSERT_EQ(status.size(), 2u);  // at the window's start and 100 ms into it
  EXPECT_EQ(status[0].first.state, BootState::kHoldWindow);
  const double window_ms = static_cast<double>(rig.chip().now() - status[0].second) / kMs;
  EXPECT_NEAR(window_ms, 200.0, 0.5);
  EXPECT_EQ(boot::g474::PeekResetFlags().cause, protocol::ResetCause::kPowerOn)
      << "starting the application, it left the flags to it";
  g474::ReleasePeripherals();
  EXPECT_EQ(rig.chip().rcc().sysclk_hz(), 16e6);
  EXPECT_TRUE(rig.chip().violations().empty()) << Violations(rig.chip());
}

TEST(G474Bootloader, HoldFramesCatchItInTheWindow) {
  Rig rig;
  const auto file = test::MakeFile(test::MakeImage(3000, 42));
  auto& memory = rig.chip().flash().mutable_contents();
  std::copy(file.begin(), file.end(), memory.begin() + 8 * 2048);
  // The host sends a hold every 10 ms from before the reset on: those before the
  // controller listens are lost, a later one is taken.
  for (int i = 0; i < 40; ++i) {
    rig.Deliver(i * 10 * kMs, protocol::Encode(protocol::BootHold{}, 1));
  }
  EXPECT_FALSE(rig.Run(400 * kMs));
  const auto status = rig.Sent<protocol::BootStatus>();
  ASSERT_FALSE(status.empty());
  EXPECT_EQ(status.back().first.state, BootState::kReady);
  EXPECT_EQ(status.back().first.reason, StayReason::kHoldFrame);
  const auto results = rig.Sent<protocol::BootResult>();
  ASSERT_FALSE(results.empty());
  EXPECT_EQ(results[0].first.request, BootRequest::kHold);
  EXPECT_TRUE(rig.chip().violations().empty()) << Violations(rig.chip());
}

TEST(G474Bootloader, AnswersWithTheNodeIdOfItsIdentityRecord) {
  Rig rig;
  {
    stm32g4::Stm32g4Flash identity_pages(252, 2);
    ASSERT_TRUE(identity_pages.Init());
    ASSERT_EQ(IdentityStore(&identity_pages, 252, 253)
                  .Save({.node = 5, .hardware_revision = 1}),
              IdentityResult::kOk);
  }
  const auto file = test::MakeFile(test::MakeImage(3000, 43));
  auto& memory = rig.chip().flash().mutable_contents();
  std::copy(file.begin(), file.end(), memory.begin() + 8 * 2048);
  for (int i = 0; i < 40; ++i) {
    rig.Deliver(i * 10 * kMs, protocol::Encode(protocol::BootHold{}, 1));  // not node 5
  }
  const auto exit = rig.Run(1000 * kMs);
  ASSERT_TRUE(exit) << "holds for another node do not count";
  EXPECT_TRUE(rig.Sent<protocol::BoardInfo>(1).empty());
  EXPECT_EQ(rig.Sent<protocol::BoardInfo>(5).size(), 1u);
  EXPECT_TRUE(rig.chip().violations().empty()) << Violations(rig.chip());
}

// The host's side of an update on the bus, driven by the board's frames: each request
// after the previous answer, each ISO-TP transfer paced by the board's flow control.
class BusHost {
 public:
  BusHost(Rig* rig, std::vector<std::uint8_t> file) : rig_(rig), file_(std::move(file)) {
    rig_->on_frame = [this](const protocol::CanFrame& f, Picoseconds at) {
      OnFrame(f, at);
    };
  }
  bool booted() const { return boot_answered_; }
  std::vector<protocol::BootResult> results;

 private:
  void OnFrame(const protocol::CanFrame& f, Picoseconds at) {
    const std::uint8_t function = protocol::FunctionOf(f.id);
    if (function == 0x3D && (f.data[0] & 0xF0) == 0x30 && !pending_.empty()) {
      // Clear to send: the consecutive frames, back to back.
      Picoseconds t = at + kFrameTime;
      for (const auto& cf : pending_) {
        rig_->Deliver(t, cf);
        t += kFrameTime;
      }
      pending_.clear();
      return;
    }
    protocol::BootStatus status;
    if (!started_ && protocol::Decode(f, &status) == protocol::DecodeError::kOk) {
      started_ = true;
      Send(at, test::BeginRequest(file_));
      return;
    }
    protocol::BootResult r;
    if (protocol::Decode(f, &r) != protocol::DecodeError::kOk) return;
    results.push_back(r);
    if (r.error != BootError::kNone) return;  // the test looks at it
    const auto image = std::span<const std::uint8_t>(file_).subspan(kHeaderArea);
    if ((r.request == BootRequest::kBegin || r.request == BootRequest::kChunk) &&
        r.next_offset < image.size()) {
      const std::size_t n =
          std::min<std::size_t>(kMaxChunkData, image.size() - r.next_offset);
      Send(at, test::ChunkRequest(r.next_offset, image.subspan(r.next_offset, n)));
    } else if (r.request == BootRequest::kBegin || r.request == BootRequest::kChunk) {
      Command(at, BootRequest::kCommit);
    } else if (r.request == BootRequest::kCommit) {
      Command(at, BootRequest::kBoot);
    } else if (r.request == BootRequest::kBoot) {
      boot_answered_ = true;
    }
  }
  void Send(Picoseconds at, const std::vector<std::uint8_t>& payload) {
    auto frames = test::IsoTpSegments(protocol::MakeId(0x3C, 1), payload);
    rig_->Deliver(at + kFrameTime, frames.front());
    pending_.assign(frames.begin() + 1, frames.end());
  }
  void Command(Picoseconds at, BootRequest request) {
    protocol::BootCommand c;
    c.request = request;
    rig_->Deliver(at + kFrameTime, protocol::Encode(c, 1));
  }

  Rig* rig_;
  std::vector<std::uint8_t> file_;
  std::deque<protocol::CanFrame> pending_;
  bool started_ = false;
  bool boot_answered_ = false;
};

TEST(G474Bootloader, AnUpdateOverTheBusThenTheResetStartsTheNewImage) {
  Rig rig;
  const auto file = test::MakeFile(test::MakeImage(2500, 44));  // two pages
  BusHost host(&rig, file);
  const auto exit = rig.Run(2000 * kMs);
  ASSERT_TRUE(exit) << "results: " << host.results.size();
  EXPECT_EQ(exit->action, BootAction::kReset);
  EXPECT_TRUE(host.booted());
  for (const auto& r : host.results) EXPECT_EQ(r.error, BootError::kNone);
  const auto& memory = rig.chip().flash().contents();
  EXPECT_TRUE(std::equal(file.begin(), file.end(), memory.begin() + 8 * 2048));
  // The reset the Boot asked for, then the new image starts after the window.
  rig.on_frame = nullptr;
  try {
    stm32g4::RequestSystemReset();
    FAIL() << "no reset";
  } catch (const g474model::ChipReset& reset) {
    EXPECT_EQ(reset.cause, g474model::ResetCause::kSoftware);
  }
  rig.sent.clear();
  const auto again = rig.Run(rig.chip().now() + 1000 * kMs);
  ASSERT_TRUE(again);
  EXPECT_EQ(again->action, BootAction::kBoot);
  const auto info = rig.Sent<protocol::BoardInfo>();
  ASSERT_EQ(info.size(), 1u);
  EXPECT_EQ(info[0].first.reset_cause, protocol::ResetCause::kSoftware);
  ImageHeader header;
  ASSERT_EQ(CheckImageFile(file, &header), ImageCheck::kValid);
  EXPECT_EQ(BootAttempts(rig.handoff, header.image_crc), 1u) << "this start counted";
  EXPECT_TRUE(rig.chip().violations().empty()) << Violations(rig.chip());
}

// The chip as the bootloader found it, with every BoardInfo: FLASH_OPTR as the model's
// factory value (RM0440 FLASH_OPTR reset value 0xFFEFF8AA: nSWBOOT0 = 1, so the chip
// samples its BOOT0 pin), the power-on's flags (RCC_CSR's top byte: BORRSTF bit 27,
// PINRSTF bit 26 → bits 3 and 2), and the crystal's PLL.
TEST(G474Bootloader, ReportsItsOptionBytesClockAndResetFlags) {
  Rig rig;
  EXPECT_FALSE(rig.Run(250 * kMs));
  const auto chip = rig.Sent<protocol::ChipInfo>();
  ASSERT_EQ(chip.size(), 1u);
  EXPECT_EQ(chip[0].first.option_bytes, 0xFFEFF8AAu);
  EXPECT_TRUE(protocol::BootsFromPin(chip[0].first.option_bytes));
  EXPECT_EQ(chip[0].first.reset_flags, (1u << 3) | (1u << 2));
  EXPECT_EQ(chip[0].first.clock, protocol::ClockSource::kHsePll);
  EXPECT_EQ(chip[0].first.clock_fault, protocol::ClockFault::kNone);
  EXPECT_TRUE(chip[0].first.hse_ready);
  EXPECT_TRUE(rig.chip().violations().empty()) << Violations(rig.chip());
}

// A crystal that never starts: the bootloader does not hand over to a valid image, runs
// its PLL from HSI16 to the same 170 MHz, serves the bus at 1 Mbit/s and says why.
TEST(G474Bootloader, WithADeadCrystalItStaysOnHsiAndSaysWhy) {
  Rig rig;
  rig.chip().rcc().SetHseStartup(g474model::kNever);
  const auto file = test::MakeFile(test::MakeImage(3000, 44));
  auto& memory = rig.chip().flash().mutable_contents();
  std::copy(file.begin(), file.end(), memory.begin() + 8 * 2048);
  EXPECT_FALSE(rig.Run(1100 * kMs)) << "no hand-over";
  EXPECT_TRUE(rig.resets.empty()) << "the watchdog is refreshed";
  EXPECT_EQ(rig.chip().rcc().sysclk_hz(), 170e6);
  EXPECT_EQ(rig.chip().rcc().fdcan_kernel_hz(), 85e6);
  EXPECT_EQ(rig.chip().fdcan1().nominal_bitrate(), 1e6);
  const auto status = rig.Sent<protocol::BootStatus>();
  ASSERT_GE(status.size(), 10u);
  for (const auto& [s, at] : status) {
    EXPECT_EQ(s.state, BootState::kReady);
    EXPECT_EQ(s.reason, StayReason::kNoClock);
  }
  // Its clock is HSI16's (exact in the model): 100 ms of virtual time between two.
  const Picoseconds period = status[5].second - status[4].second;
  EXPECT_NEAR(static_cast<double>(period) / kMs, 100.0, 0.1);
  const auto chip = rig.Sent<protocol::ChipInfo>();
  ASSERT_GE(chip.size(), 1u);
  EXPECT_EQ(chip.back().first.clock, protocol::ClockSource::kHsiPll);
  EXPECT_EQ(chip.back().first.clock_fault, protocol::ClockFault::kHseTimeout);
  EXPECT_FALSE(chip.back().first.hse_ready);
  // The first frame within a few ms of the reset: the crystal's wait is bounded.
  ASSERT_FALSE(rig.sent.empty());
  EXPECT_LT(rig.sent.front().second, 10 * kMs);
  EXPECT_TRUE(rig.chip().violations().empty()) << Violations(rig.chip());
}

// A crystal that starts 50 ms after HSEON, far beyond tSU(HSE): the bootloader has given
// up on it after 5 ms and stays on HSI16; its ChipInfo then shows the crystal running.
TEST(G474Bootloader, WithALateCrystalItStaysAndReportsTheCrystalRunningLate) {
  Rig rig;
  rig.chip().rcc().SetHseStartup(50 * kMs);
  const auto file = test::MakeFile(test::MakeImage(3000, 45));
  auto& memory = rig.chip().flash().mutable_contents();
  std::copy(file.begin(), file.end(), memory.begin() + 8 * 2048);
  EXPECT_FALSE(rig.Run(1100 * kMs)) << "no hand-over";
  const auto status = rig.Sent<protocol::BootStatus>();
  ASSERT_FALSE(status.empty());
  EXPECT_EQ(status.back().first.reason, StayReason::kNoClock);
  const auto chip = rig.Sent<protocol::ChipInfo>();
  ASSERT_GE(chip.size(), 2u);  // at its start and 1 s later
  EXPECT_FALSE(chip.front().first.hse_ready) << "at its start, the crystal was not ready";
  EXPECT_TRUE(chip.back().first.hse_ready) << "1 s later it runs";
  EXPECT_EQ(chip.back().first.clock, protocol::ClockSource::kHsiPll);
  EXPECT_TRUE(rig.chip().violations().empty()) << Violations(rig.chip());
}

}  // namespace
