// The joint board's image: brings the chip up, initialises every driver, and serves the
// 10 kHz tick and the main loop.
//
// The application's composition root (firmware/app: the object that owns the JointApp,
// the CAN node and the calibration store) plugs in at the two places marked
// "composition root" below; it is handed the drivers through their interfaces only:
// hal::JointIo (g_joint_io, the tick), hal::CanPort (g_can) and hal::Flash (the
// calibration pages of g_flash). Until then the tick samples the sensors and holds the
// bridge disabled, and the main loop keeps the watchdog and the CAN port serviced.
#include <atomic>
#include <cstdint>

#include "board.h"
#include "hal/stm32g4/clock.h"
#include "hal/stm32g4/gpio.h"
#include "hal/stm32g4/nvic.h"
#include "hal/stm32g4/regs/irq.h"
#include "hal/stm32g4/watchdog.h"
#include "mjc/boot/handoff.h"

extern "C" {
// The calibration pages' place in flash (linker/stm32g474.ld).
extern const std::uint8_t __calibration_start[];
// Shared with the bootloader across resets (linker/stm32g474.ld, HANDOFF).
extern mjc::boot::BootHandoff __boot_handoff;
void TickInterrupt();
void CanLine0Interrupt();
void CanLine1Interrupt();
}

namespace mjc::board {
namespace {

// The tick's hot state in CCM SRAM (zero wait states, no bus contention with DMA).
__attribute__((section(".ccm_bss.joint_io"))) JointIo g_joint_io;
stm32g4::Stm32g4Fdcan g_can;
std::atomic<std::uint32_t> g_ticks{0};

std::uint32_t CalibrationPage() {
  const auto address =
      static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(__calibration_start));
  return (address - stm32g4::Stm32g4Flash::PageAddress(0)) /
         static_cast<std::uint32_t>(hal::Flash::kPageSize);
}

// ---- composition root: the tick ---------------------------------------------------
// Replaced by the application's `app.ISR_Tick(io)`. Until then: read the sample (so the
// joint encoder's pipeline and the overrun measurement run) and keep the bridge off.
template <hal::JointIo Io>
void Tick(Io& io) {
  (void)io.ISR_Read();
  io.ISR_Write(Actuation{});
}
// ---- end composition root ----------------------------------------------------------

}  // namespace
}  // namespace mjc::board

void TickInterrupt() {
  using namespace mjc::board;
  g_joint_io.ISR_BeginTick();
  Tick(g_joint_io);
  g_ticks.store(g_ticks.load(std::memory_order_relaxed) + 1, std::memory_order_release);
}
void CanLine0Interrupt() { mjc::board::g_can.ISR_Line0(); }
void CanLine1Interrupt() { mjc::board::g_can.ISR_Line1(); }

int main() {
  using namespace mjc;
  using namespace mjc::board;
  const StartupReport& startup = Startup();
  const stm32g4::ResetCause reset_cause = stm32g4::TakeResetCause();

  // Pins and peripheral clocks (the bridge's enable line is an output driven low before
  // anything else can drive the gates).
  stm32g4::EnablePeripheralClocks();
  for (const stm32g4::PinConfig& pin : kPins) stm32g4::ConfigurePin(pin);

  // The watchdog from here on: everything below must keep making progress.
  (void)stm32g4::StartWatchdog();

  static stm32g4::Stm32g4Flash flash(CalibrationPage(), 2);
  const bool flash_ok = flash.Init();
  const bool joint_ok = g_joint_io.Init();
  const stm32g4::FdcanResult can_result = g_can.Init(NodeFilters(kNodeId));

  // ---- composition root: construction ----------------------------------------------
  // The application is built here from: g_joint_io (hal::JointIo), g_can (hal::CanPort),
  // flash with pages CalibrationPage() and CalibrationPage() + 1 (hal::Flash, for the
  // CalibrationStore), and the boot facts for its first report: startup.clock,
  // startup.crashed / crash_exception, reset_cause, flash_ok, joint_ok, can_result.
  // The motor may run only if startup.clock == ClockResult::kOk.
  (void)startup;
  (void)reset_cause;
  (void)flash_ok;
  (void)joint_ok;
  (void)can_result;
  // ---- end composition root ----------------------------------------------------------

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
    // 2 s (20,000 ticks) with the watchdog refreshed: until then a reset counts as a
    // failed start, and after three the bootloader stays (firmware/bootloader).
    if (!confirmed && tick >= 20'000u) {
      boot::ConfirmHealthyBoot(__boot_handoff);
      confirmed = true;
    }
    // ---- composition root: the main loop's work ------------------------------------
    // Replaced by the application's poll (CAN node, events, calibration saves). Until
    // then the CAN port's queue is emptied and bus-off events taken.
    protocol::CanFrame frame;
    while (g_can.Receive(&frame)) {
    }
    (void)g_can.TakeBusOff();
    // ---- end composition root ------------------------------------------------------
    // Alive: the LED toggles every 5,000 ticks (1 Hz blink).
    stm32g4::WritePin(kStatusLed, (tick / 5000u) % 2u != 0);
    stm32g4::WaitForInterrupt();
  }
}
