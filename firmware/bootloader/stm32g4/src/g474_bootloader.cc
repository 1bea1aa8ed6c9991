#include "mjc/boot/g474_bootloader.h"

#include <array>

#include "hal/stm32g4/clock.h"
#include "hal/stm32g4/mmio.h"
#include "hal/stm32g4/watchdog.h"
#include "mjc/boot/identity_store.h"
#include "mjc/boot/layout.h"
#include "mjc/build_id.h"
#include "mjc/protocol/can_frame.h"

namespace mjc::boot::g474 {
namespace {

using protocol::Function;

constexpr auto kBoardType = static_cast<std::uint16_t>(BoardType::kG474Joint);

void Service() { stm32g4::RefreshWatchdog(); }

// The wire's numbers are the driver's.
static_assert(static_cast<int>(protocol::ClockSource::kHsi16) ==
                  static_cast<int>(stm32g4::ClockSource::kHsi16) &&
              static_cast<int>(protocol::ClockSource::kHsePll) ==
                  static_cast<int>(stm32g4::ClockSource::kHsePll) &&
              static_cast<int>(protocol::ClockSource::kHsiPll) ==
                  static_cast<int>(stm32g4::ClockSource::kHsiPll) &&
              static_cast<int>(protocol::ClockSource::kOther) ==
                  static_cast<int>(stm32g4::ClockSource::kOther));
static_assert(static_cast<int>(protocol::ClockFault::kHseTimeout) ==
                  static_cast<int>(stm32g4::ClockResult::kHseTimeout) &&
              static_cast<int>(protocol::ClockFault::kSwitchTimeout) ==
                  static_cast<int>(stm32g4::ClockResult::kSwitchTimeout) &&
              static_cast<int>(protocol::ClockFault::kNone) ==
                  static_cast<int>(stm32g4::ClockResult::kOk));

// What this run found at its start, for ChipInfo (the rest is read when it is sent).
struct ChipAtStart {
  std::uint8_t reset_flags = 0;
  protocol::ClockFault clock_fault = protocol::ClockFault::kNone;
};
ChipAtStart g_chip_at_start;

protocol::ChipInfo ReadChipInfo() {
  protocol::ChipInfo c;
  c.option_bytes = OptionBytes();
  c.reset_flags = g_chip_at_start.reset_flags;
  c.hse_ready = stm32g4::HseReady();
  c.clock = static_cast<protocol::ClockSource>(stm32g4::ActiveClockSource());
  c.clock_fault = g_chip_at_start.clock_fault;
  return c;
}

std::array<stm32g4::CanFilter, 3> BootFilters(std::uint8_t node) {
  const auto id = [node](Function f) {
    return static_cast<std::uint16_t>(
        protocol::MakeId(static_cast<std::uint8_t>(f), node));
  };
  return {{{id(Function::kBootHold), 0x7FF},
           {id(Function::kBootCommand), 0x7FF},
           {id(Function::kBootIsoTpToBoard), 0x7FF}}};
}

}  // namespace

G474Bootloader::G474Bootloader(volatile BootHandoff* handoff)
    : handoff_(handoff), flash_(kG474Layout.app_first_page, kG474Layout.app_pages) {}

Exit G474Bootloader::Run() {
  // No interrupt is ever taken (the start-up code masked them already; the FDCAN driver
  // enables its IRQs in the NVIC, where they only pend).
  stm32g4::DisableInterrupts();
  HoldBridgeOff();
  const ResetFlags reset = PeekResetFlags();
  // The crystal's bring-up waits 5 ms for it (clock.h). Without it the same PLL
  // frequencies come from HSI16, enough to serve the bus and say why the board stays;
  // the application is never started on that clock.
  const stm32g4::ClockResult crystal = stm32g4::ConfigureClocks();
  const bool clock_ok = crystal == stm32g4::ClockResult::kOk ||
                        stm32g4::ConfigureClocksFromHsi() == stm32g4::ClockResult::kOk;
  g_chip_at_start = {reset.flags, static_cast<protocol::ClockFault>(crystal)};
  (void)stm32g4::StartWatchdog();
  (void)flash_.Init();  // a chip of another geometry: every write refused

  const BootLayout& layout = kG474Layout;
  const auto identity =
      IdentityStore(&flash_, layout.identity_page_a, layout.identity_page_b).Load();
  BootloaderConfig config;
  config.layout = layout;
  config.board_type = kBoardType;
  config.node = identity ? identity->identity.node : kDefaultNode;
  config.hardware_revision =
      identity ? identity->identity.hardware_revision : kDefaultHardwareRevision;
  config.build = build::kCommit;
  config.dirty = build::kDirty;
  config.instance = BoardInstance();
  config.reset_cause = reset.cause;
  config.service = Service;
  config.clock_ok = crystal == stm32g4::ClockResult::kOk;
  config.chip_info = ReadChipInfo;
  node_ = config.node;

  bool can_ok = false;
  if (clock_ok) {
    EnableCanPeripherals();
    can_ok = can_.Init(BootFilters(config.node)) == stm32g4::FdcanResult::kOk;
  }
  config.hold_window_ms = can_ok ? Bootloader::kHoldWindowMs : 0;

  Bootloader& boot = boot_.emplace(config, &flash_, can_ok ? &can_ : nullptr, handoff_);
  MsClock clock(clock_ok ? stm32g4::kSysclkHz / 1000 : 16'000);
  BootAction action = boot.Start(clock.Now(), reset.software);
  bool flags_cleared = false;
  while (action == BootAction::kNone) {
    stm32g4::RefreshWatchdog();
    // Staying: the reset flags read above are this run's; the application reads its own
    // reset's, so they are cleared now rather than left to mix with the next reset's.
    if (!flags_cleared && boot.state() != protocol::BootState::kHoldWindow) {
      ClearResetFlags();
      flags_cleared = true;
    }
    if (can_ok) {
      can_.ISR_Line0();  // polled: the RX FIFO into the port's queue
      can_.ISR_Line1();  // bus-off recovery
    }
    action = boot.Poll(clock.Now());
  }
  return {action, boot.boot_address()};
}

}  // namespace mjc::boot::g474
