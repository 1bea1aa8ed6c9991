// The start-up report and the clock bring-up: what the start-up code does once the
// memory is initialised, before Run(). Built into the image and the virtual board.
#include "board.h"
#include "hal/stm32g4/clock.h"

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
  g_report.clock = stm32g4::ConfigureClocks();
}

}  // namespace mjc::board
