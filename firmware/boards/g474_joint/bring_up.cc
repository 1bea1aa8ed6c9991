// The start-up report and the clock bring-up: what the start-up code does once the
// memory is initialised, before Run(). Built into the image and the virtual board.
#include "board.h"
#include "hal/stm32g4/clock.h"
#include "hal/stm32g4/watchdog.h"

namespace mjc::board {

// .noinit: the reset neither copies nor zeroes it, so DefaultHandler's record reaches
// the next boot (the host build's survives its virtual chip's resets alike).
__attribute__((section(".noinit.crash"))) CrashRecord g_crash;

namespace {
StartupReport g_report;
}  // namespace

const StartupReport& Startup() { return g_report; }

void BringUp() {
  g_report = StartupReport{};
  g_report.crashed = g_crash.magic == kCrashMagic;
  g_report.crash_exception = g_report.crashed ? g_crash.exception : 0;
  g_crash.magic = 0;
  // The watchdog the bootloader left running (100 ms) is fed through every wait; the
  // crystal's is bounded to 5 ms (clock.h). Without the crystal the same frequencies
  // come from HSI16, so the tick, the bridge's PWM and CAN run as designed: the board
  // answers on the bus, holding Fault::kBoardStartup (board.cc), rather than resetting
  // through the watchdog with nothing said.
  g_report.clock = stm32g4::ConfigureClocks(stm32g4::RefreshWatchdog);
  if (g_report.clock != stm32g4::ClockResult::kOk) {
    g_report.fallback = stm32g4::ConfigureClocksFromHsi(stm32g4::RefreshWatchdog);
  }
}

}  // namespace mjc::board
