// The virtual joint board boots as on the chip: the image's own start-up, drivers and
// application (firmware/boards/g474_joint) against the STM32G474 register models, bound
// to the plant, on an in-process CAN bus. One simulated second: no rule of the manual
// broken (the models' violations); SYSCLK at 170 MHz from the PLL in Range 1 boost with
// 4 flash wait states (asked of the RCC, PWR and FLASH models); the tick's interrupt at
// 10 kHz; FDCAN at 1 Mbit/s nominal and 5 Mbit/s data; the BoardInfo frame with this
// build's commit, the power-on reset and the instance folded from the chip's unique ID.
// The start is confirmed to the bootloader (the handoff block) after 2 s of ticks, not
// before.
#include "mjc/g474board/virtual_board.h"

#include <gtest/gtest.h>

#include <vector>

#include "board.h"
#include "mjc/boot/handoff.h"
#include "mjc/build_id.h"
#include "mjc/plant/params.h"
#include "mjc/protocol/codec.h"

namespace {

using namespace mjc;
using namespace mjc::protocol;

constexpr std::array<std::uint32_t, 3> kUniqueId = {0x0031002Au, 0x4D4B5012u,
                                                    0x20313739u};

g474board::VirtualBoardConfig Config(const plant::PlantParams& params) {
  g474board::VirtualBoardConfig config;
  config.plant = params;
  config.node = 1;
  config.unique_id = kUniqueId;
  config.speed = 0;      // as fast as the machine runs it: no wall time in any verdict
  config.log = nullptr;  // quiet; the violations are checked below
  return config;
}

std::string Violations(const g474board::VirtualBoard& board) {
  std::string s;
  for (const auto& v : board.violations()) s += v.source + ": " + v.what + "\n";
  return s;
}

// Every frame the host link holds now.
std::vector<CanFrame> Drain(host::CanLink& link) {
  std::vector<CanFrame> frames;
  while (const auto r = link.Receive(0)) frames.push_back(r->frame);
  return frames;
}

TEST(VirtualBoard, BootsAsOnTheChip) {
  auto bus = host::InProcessBus::Create();
  auto board_link = bus->Connect();
  auto host_link = bus->Connect();
  g474board::VirtualBoard board(Config(plant::LoadPlantParams("default")),
                                board_link.get());

  board.RunUntil(0.5);
  ASSERT_NE(board.firmware(), nullptr) << "the firmware did not build its board";
  const std::uint32_t tick_half = board.firmware()->app().last().telemetry.tick;
  board.RunUntil(1.0);
  const std::uint32_t tick_one = board.firmware()->app().last().telemetry.tick;
  EXPECT_TRUE(board.violations().empty()) << Violations(board);

  g474model::VirtualChip& chip = board.chip();
  EXPECT_EQ(chip.rcc().sysclk_hz(), 170e6);
  EXPECT_EQ(chip.rcc().hclk_hz(), 170e6);
  EXPECT_TRUE(chip.pwr().boost());
  EXPECT_EQ(chip.flash().latency(), 4u);
  // The tick: TIM1's update every 100 µs, and the firmware's tick counter advanced by
  // exactly that rate over the second half of the second.
  EXPECT_NEAR(chip.tim1().UpdatePeriodSeconds(), 100e-6, 1e-12);
  EXPECT_EQ(tick_one - tick_half, 5000u);
  EXPECT_EQ(chip.fdcan1().nominal_bitrate(), 1e6);
  EXPECT_EQ(chip.fdcan1().data_bitrate(), 5e6);

  // Who the board says it is.
  std::uint32_t folded = kUniqueId[0] ^ kUniqueId[1] ^ kUniqueId[2];
  const auto instance = static_cast<std::uint16_t>(folded ^ (folded >> 16));
  int infos = 0;
  for (const CanFrame& f : Drain(*host_link)) {
    BoardInfo info;
    if (FunctionOf(f.id) != static_cast<std::uint8_t>(Function::kBoardInfo)) continue;
    ASSERT_EQ(Decode(f, &info), DecodeError::kOk);
    ++infos;
    EXPECT_EQ(NodeOf(f.id), 1);
    EXPECT_EQ(info.build, build::kCommit);
    EXPECT_EQ(info.dirty, build::kDirty);
    EXPECT_EQ(info.image, ImageKind::kApplication);
    EXPECT_EQ(info.reset_cause, ResetCause::kPowerOn);
    EXPECT_EQ(info.instance, instance);
  }
  EXPECT_GE(infos, 1);
  board.Stop();
  EXPECT_TRUE(board.violations().empty()) << Violations(board);
  EXPECT_EQ(board.Summary().resets, 0);
}

TEST(VirtualBoard, ConfirmsAHealthyStartAfterTwoSeconds) {
  // Two unconfirmed starts of this image so far, as the bootloader counts them.
  constexpr std::uint32_t kImageCrc = 0x5EED1234u;
  boot::SetBootAttempts(board::Handoff(), kImageCrc, 2);
  g474board::VirtualBoard board(Config(plant::LoadPlantParams("default")), nullptr);

  board.RunUntil(1.9);
  EXPECT_EQ(boot::BootAttempts(board::Handoff(), kImageCrc), 2u);
  board.RunUntil(2.1);
  EXPECT_EQ(boot::BootAttempts(board::Handoff(), kImageCrc), 0u);
  EXPECT_EQ(board::Handoff().attempts_magic, boot::kAttemptsMagic);
  board.Stop();
  EXPECT_TRUE(board.violations().empty()) << Violations(board);
}

}  // namespace
