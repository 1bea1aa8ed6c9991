// The joint board: brings up the pins, the watchdog and every driver, builds the
// firmware's composition root (app::JointBoard: the application, its CAN node and its
// calibration store) on them, and serves the 10 kHz tick and the main loop. The board is
// handed the drivers through their interfaces only: hal::JointIo (g_joint_io, the
// tick), hal::CanPort (g_can), hal::Flash (the calibration pages; reads anywhere) and
// hal::BootEntry (the way into the bootloader on a host's BootHold).
//
// Who the board is comes from flash, not from this build: its node id from the identity
// record commissioning wrote (RunOptions::node without one), so that every update keeps
// it; the build it reports from the image header the bootloader checked before it handed
// over (the same commit the build compiled in, by construction of the packed file; the
// build's own without a header, as on the virtual board, which no bootloader precedes).
//
// Built into the image and, unchanged, into the virtual board (board.h: the two
// entries).
#include "board.h"

#include <atomic>
#include <cstdint>
#include <new>

#include "hal/stm32g4/clock.h"
#include "hal/stm32g4/debug.h"
#include "hal/stm32g4/gpio.h"
#include "hal/stm32g4/nvic.h"
#include "hal/stm32g4/regs/irq.h"
#include "hal/stm32g4/unique_id.h"
#include "hal/stm32g4/watchdog.h"
#include "interrupts.h"
#include "mjc/app/joint_board.h"
#include "mjc/app/joint_config.h"
#include "mjc/boot/handoff.h"
#include "mjc/boot/identity_store.h"
#include "mjc/boot/image_check.h"
#include "mjc/boot/layout.h"
#include "mjc/build_id.h"

namespace mjc::board {
namespace {

// The tick's hot state in CCM SRAM (zero wait states, no bus contention with DMA).
__attribute__((section(".ccm_bss.joint_io"))) JointIo g_joint_io;
stm32g4::Stm32g4Fdcan g_can;
std::atomic<std::uint32_t> g_ticks{0};

// The calibration pages' driver, built in Run() (its pages come from the memory map).
alignas(stm32g4::Stm32g4Flash) std::uint8_t
    g_flash_storage[sizeof(stm32g4::Stm32g4Flash)];

std::uint32_t CalibrationPage() {
  return (CalibrationAddress() - stm32g4::Stm32g4Flash::PageAddress(0)) /
         static_cast<std::uint32_t>(hal::Flash::kPageSize);
}

// The application's board, built in Run() once the drivers are up (placement in CCM
// SRAM: the tick's hot state, zero wait states), then served by the tick's interrupt.
alignas(app::JointBoard) __attribute__((section(".ccm_bss.board"))) std::uint8_t
    g_board_storage[sizeof(app::JointBoard)];
app::JointBoard* g_board = nullptr;
BootFacts g_boot;

// A host's BootHold accepted at rest (app::CanNode): into the bootloader, which stays
// (StayReason kRequested) and takes the new image.
class Stm32g4BootEntry final : public hal::BootEntry {
  // The hold's answer and what was queued before it leave first: the controller's three
  // TX elements take under 0.5 ms at 1 Mbit/s. Bounded, since the answer is a courtesy
  // (the host watches for the bootloader's own frames) and a bus that does not take it
  // must not keep the board: 1 ms of the cycle counter, well inside the watchdog's
  // 100 ms.
  static constexpr std::uint32_t kDrainCycles = stm32g4::kSysclkHz / 1000u;

  void DoEnterBootloader() override {
    StopBridge();
    stm32g4::DisableInterrupts();
    const std::uint32_t since = stm32g4::CycleCount();
    while (!g_can.TransmitIdle() && stm32g4::CycleCount() - since < kDrainCycles) {
    }
    boot::RequestBootloader(Handoff());
    stm32g4::RequestSystemReset();
    // The reset comes within a few cycles on the chip; the virtual chip takes the one
    // it recorded at its next event, which WFI reaches.
    for (;;) stm32g4::WaitForInterrupt();
  }
};
Stm32g4BootEntry g_boot_entry;

protocol::ResetCause WireResetCause(stm32g4::ResetCause cause) {
  switch (cause) {
    case stm32g4::ResetCause::kPowerOn:
      return protocol::ResetCause::kPowerOn;
    case stm32g4::ResetCause::kPin:
      return protocol::ResetCause::kPin;
    case stm32g4::ResetCause::kSoftware:
      return protocol::ResetCause::kSoftware;
    case stm32g4::ResetCause::kIndependentWatchdog:
    case stm32g4::ResetCause::kWindowWatchdog:
      return protocol::ResetCause::kWatchdog;
    case stm32g4::ResetCause::kLowPower:
    case stm32g4::ResetCause::kOptionByteLoader:
      return protocol::ResetCause::kOther;
    case stm32g4::ResetCause::kUnknown:
      break;
  }
  return protocol::ResetCause::kUnknown;
}

}  // namespace

const app::JointBoard* Instance() { return g_board; }
const BootFacts& LastBoot() { return g_boot; }
std::uint32_t LastTickCycles() { return g_joint_io.last_tick_cycles(); }

}  // namespace mjc::board

void TickInterrupt() {
  using namespace mjc::board;
  g_joint_io.ISR_BeginTick();
  g_board->ISR_Tick(g_joint_io);
  g_ticks.store(g_ticks.load(std::memory_order_relaxed) + 1, std::memory_order_release);
}
void CanLine0Interrupt() { mjc::board::g_can.ISR_Line0(); }
void CanLine1Interrupt() { mjc::board::g_can.ISR_Line1(); }

namespace mjc::board {

void Run(const RunOptions& options) {
  // The board's RAM state, rebuilt (board.h: on the chip already zero, on the host left
  // over from before a reset). No interrupt runs yet: the NVIC is at its reset state.
  g_board = nullptr;
  g_boot = BootFacts{};
  new (&g_joint_io) JointIo();
  new (&g_can) stm32g4::Stm32g4Fdcan();
  g_ticks.store(0, std::memory_order_relaxed);

  const StartupReport& startup = Startup();
  const stm32g4::ResetCause reset_cause = stm32g4::TakeResetCause();

  // Pins and peripheral clocks (the bridge's enable line is an output driven low before
  // anything else can drive the gates).
  stm32g4::EnablePeripheralClocks();
  for (const stm32g4::PinConfig& pin : kPins) stm32g4::ConfigurePin(pin);

  // A debugger's halt stops the watchdog and takes TIM1's outputs to their idle levels
  // (hal/stm32g4/debug.h), before either runs.
  stm32g4::FreezeOnDebugHalt();
  // The watchdog from here on: everything below must keep making progress.
  (void)stm32g4::StartWatchdog();

  auto* flash = new (g_flash_storage) stm32g4::Stm32g4Flash(CalibrationPage(), 2);
  const bool flash_ok = flash->Init();
  const boot::IdentityStore identity_store(flash, boot::kG474Layout.identity_page_a,
                                           boot::kG474Layout.identity_page_b);
  const auto identity = flash_ok ? identity_store.Load() : std::nullopt;
  const std::uint8_t node = identity ? identity->identity.node : options.node;
  boot::AppRegion region(flash, boot::kG474Layout);
  const auto header = flash_ok ? boot::ReadInstalledHeader(region) : std::nullopt;
  const bool joint_ok = g_joint_io.Init();
  const stm32g4::FdcanResult can_result = g_can.Init(NodeFilters(node));

  // The board. Its first report (BoardInfo) says which build runs and why it started;
  // the rest of the boot facts keep it from running the motor: a clock not from the
  // crystal (HSI16's PLL after a crystal that did not start, or worse), a joint encoder
  // or CAN controller that did not come up.
  app::JointBoardConfig config{
      app::DefaultJointConfig(), {}, CalibrationPage(), CalibrationPage() + 1};
  config.can.node = node;
  // FDCAN runs CAN FD with bit-rate switching (stm32g4/fdcan.h); on HSI16 (no crystal)
  // the 5 Mbit/s data phase is beyond HSI16's accuracy (hal/README.md, "Clock"), so
  // the board then sends classical frames only.
  config.can.fd = startup.clock == stm32g4::ClockResult::kOk;
  if (options.host_timeout_ms) config.can.host_timeout_ms = *options.host_timeout_ms;
  config.can.identity.build = header ? header->commit : build::kCommit;
  config.can.identity.dirty = header ? header->dirty : build::kDirty;
  config.can.identity.reset_cause = WireResetCause(reset_cause);
  config.can.identity.instance = stm32g4::UniqueId16();
  // An identity page the flash could not read (an ECC error a cut save left; the other
  // page's record, or the default node, was taken): named in every BoardInfo.
  const std::uint8_t bad_identity = identity_store.unreadable_pages();
  config.can.identity.flash_unreadable = static_cast<std::uint8_t>(
      ((bad_identity & 1u) ? protocol::flash_unreadable::kIdentityA : 0u) |
      ((bad_identity & 2u) ? protocol::flash_unreadable::kIdentityB : 0u));
  g_board = new (g_board_storage)
      app::JointBoard(config, &g_can, flash_ok ? flash : nullptr, &g_boot_entry);
  if (const auto restored = g_board->Boot()) {
    g_boot.calibration_restored = true;
    g_boot.calibration_sequence = restored->sequence;
  }
  const bool may_drive = startup.clock == stm32g4::ClockResult::kOk && joint_ok &&
                         can_result == stm32g4::FdcanResult::kOk;
  if (!may_drive) g_board->HoldFault(Fault::kBoardStartup);
  (void)startup.crashed;

  // The tick starts last: TIM1 is already counting, its interrupt is enabled now.
  stm32g4::EnableIrq(stm32g4::irq::kTim1Update, stm32g4::kPriorityTick);
  stm32g4::EnableInterrupts();

  std::uint32_t last_tick = g_ticks.load(std::memory_order_acquire);
  bool confirmed = false;
  for (;;) {
    // The watchdog is refreshed only while the tick also runs.
    const std::uint32_t tick = g_ticks.load(std::memory_order_acquire);
    if (tick != last_tick) {
      stm32g4::RefreshWatchdog();
      last_tick = tick;
    }
    // A healthy start, told to the bootloader once the tick and this loop have run for
    // 2 s with the watchdog refreshed: until then a reset counts as a failed start, and
    // after three the bootloader stays (firmware/bootloader).
    if (!confirmed && tick >= kHealthyBootTicks) {
      boot::ConfirmHealthyBoot(Handoff());
      confirmed = true;
    }
    g_board->Poll();
    // Alive: the LED toggles every 5,000 ticks (1 Hz blink).
    stm32g4::WritePin(kStatusLed, (tick / 5000u) % 2u != 0);
    stm32g4::WaitForInterrupt();
  }
}

}  // namespace mjc::board
