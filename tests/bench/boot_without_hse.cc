// boot_without_hse_on_can, for ./bench: 1 when a board whose crystal never starts still
// answers on CAN and says why, 0 otherwise. Both images run on the STM32G474 register
// models with RCC's HSE set never to become ready (Rcc::SetHseStartup(kNever)):
//
//  - the bootloader (G474Bootloader, with a valid image installed) must stay, serving
//    the bus with BootStatus.reason = no_clock and a ChipInfo naming the HSI16 PLL;
//  - the application (the virtual board, its watchdog running as the bootloader leaves
//    it) must answer with heartbeats carrying Fault::kBoardStartup and never reset.
//
// One simulated second each. Anything else prints 0 with what was missing.
#include <cstdio>
#include <optional>
#include <string>

#include "boot_rig.h"
#include "hal/stm32g4/mmio.h"
#include "mjc/boot/g474_bootloader.h"
#include "mjc/g474board/virtual_board.h"
#include "mjc/g474model/virtual_chip.h"
#include "mjc/host/can_link.h"
#include "mjc/plant/params.h"
#include "mjc/protocol/codec.h"

namespace {

using namespace mjc;
using g474model::Picoseconds;

constexpr Picoseconds kMs = 1'000'000'000;

std::string BootloaderAnswers() {
  g474model::ChipConfig config;
  config.rcc.hse_hz = 24e6;
  g474model::VirtualChip chip(config);
  chip.rcc().SetHseStartup(g474model::kNever);
  const auto file = boot::test::MakeFile(boot::test::MakeImage(3000, 7));
  std::copy(file.begin(), file.end(), chip.flash().mutable_contents().begin() + 8 * 2048);
  bool stays = false, on_hsi = false;
  chip.fdcan1().SetTransmitHook([&](const g474model::CanBusFrame& f, Picoseconds) {
    protocol::CanFrame c;
    c.id = f.id;
    c.length = f.length;
    c.data = f.data;
    protocol::BootStatus status;
    protocol::ChipInfo info;
    if (protocol::Decode(c, &status) == protocol::DecodeError::kOk) {
      stays = status.reason == protocol::StayReason::kNoClock;
    }
    if (protocol::Decode(c, &info) == protocol::DecodeError::kOk) {
      on_hsi = info.clock == protocol::ClockSource::kHsiPll;
    }
  });
  stm32g4::BindRegisterSpace(&chip);
  boot::BootHandoff handoff{};
  bool handed_over = false;
  chip.SetTimeLimit(1000 * kMs);
  try {
    handed_over =
        boot::g474::G474Bootloader(&handoff).Run().action != boot::BootAction::kNone;
  } catch (const g474model::TimeLimitReached&) {
  } catch (const g474model::ChipReset&) {
    handed_over = true;
  }
  chip.SetTimeLimit(g474model::kNever);
  stm32g4::BindRegisterSpace(nullptr);
  if (handed_over) return "the bootloader left (hand-over or reset)";
  if (!stays) return "no BootStatus with reason no_clock from the bootloader";
  if (!on_hsi) return "no ChipInfo naming the HSI16 PLL from the bootloader";
  if (!chip.violations().empty()) return "bootloader: " + chip.violations().ToString();
  return "";
}

std::string ApplicationAnswers() {
  auto bus = host::InProcessBus::Create();
  auto board_link = bus->Connect();
  auto host_link = bus->Connect();
  g474board::VirtualBoardConfig config;
  config.plant = plant::LoadPlantParams("default");
  config.speed = 0;
  config.log = nullptr;
  g474board::VirtualBoard board(config, board_link.get());
  g474model::VirtualChip& chip = board.chip();
  chip.rcc().SetHseStartup(g474model::kNever);
  // The bootloader's watchdog (100 ms), as it leaves it running.
  constexpr std::uint32_t kIwdg = 0x40003000;
  chip.Write(kIwdg, 0xCCCC, 4);
  chip.Write(kIwdg, 0x5555, 4);
  chip.Write(kIwdg + 0x04, 3, 4);
  chip.Write(kIwdg + 0x08, 99, 4);
  chip.AdvanceTo(chip.now() + kMs);
  chip.Write(kIwdg, 0xAAAA, 4);
  board.RunUntil(1.0);
  int faulted = 0;
  while (const auto r = host_link->Receive(0)) {
    protocol::Heartbeat beat;
    if (protocol::Decode(r->frame, &beat) == protocol::DecodeError::kOk &&
        beat.fault == Fault::kBoardStartup) {
      ++faulted;
    }
  }
  const int resets = board.Summary().resets;
  const std::size_t violations = board.violations().size();
  board.Stop();
  if (resets != 0) return "the application reset " + std::to_string(resets) + " times";
  if (faulted == 0) return "no heartbeat with kBoardStartup from the application";
  if (violations != 0) return "application: model violations";
  return "";
}

}  // namespace

int main() {
  const std::string boot = BootloaderAnswers();
  const std::string app = ApplicationAnswers();
  if (boot.empty() && app.empty()) {
    std::printf(
        "boot_without_hse_on_can: 1 (dead crystal: the bootloader stays on the HSI16 PLL "
        "saying no_clock, the application answers with kBoardStartup and never "
        "resets)\n");
    return 0;
  }
  std::printf("boot_without_hse_on_can: 0 (%s%s%s)\n", boot.c_str(),
              boot.empty() || app.empty() ? "" : "; ", app.c_str());
  return 0;
}
