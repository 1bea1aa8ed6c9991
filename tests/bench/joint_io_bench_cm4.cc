// The tick's hardware I/O on the Cortex-M4: Stm32g4JointIo (TIM1, TIM3, SPI1, the CS and
// enable pins, the DWT counter) instantiated with every register block placed in RAM —
// QEMU's mps2-an386 has no STM32 peripherals — and counted by scripts/cm4-instructions
// like the core's kernels. The blocks are template arguments, so this is the driver the
// board runs, compiled the same way: only the addresses in its loads and stores differ.
//
// The DWT "counter" here is a RAM word that does not count. Between the entries the
// image advances it by a tick's worth, as the tick's computation would, so the CS-high
// hold (t_CSn) is already spent when ISR_Write lowers CS; the CS-to-clock hold (t_L)
// then runs its bounded wait to the end (60 passes), as the chip spends up to 60 cycles
// there. joint_io_write therefore includes that wait.
#include <cstdint>

#include "bench_cm4.h"
#include "g474_ram_blocks.h"
#include "hal/stm32g4/joint_io.h"

namespace {

using namespace mjc;
using namespace mjc::stm32g4;
using bench::Entry;
using bench::kRamBlocks;
using bench::Reg;

using Io = Stm32g4JointIo<kRamBlocks>;

Io g_io;
volatile std::uint16_t g_count = 0;
volatile std::uint16_t g_frame = 0;
Actuation g_run;
Actuation g_stop;

void Baseline() { g_count = 0; }
// The interrupt's entry and the sample: TIM1's flag, the cycle count, TIM3's count, the
// SPI frame, CS high.
void Read() {
  g_io.ISR_BeginTick();
  const Sample s = g_io.ISR_Read();
  g_count = s.motor_count;
  g_frame = s.joint_frame;
}
// The actuation: CS low, duty to CCR1/CCR2, enable, the next SPI command.
void WriteRunning() { g_io.ISR_Write(g_run); }
void WriteStopped() { g_io.ISR_Write(g_stop); }

constexpr Entry kEntries[] = {
    {"baseline", Baseline},
    {"joint_io_read", Read},
    {"joint_io_write", WriteRunning},
    {"joint_io_read_again", Read},
    {"joint_io_write_disabled", WriteStopped},
};

}  // namespace

int main() {
  Reg(kRamBlocks.encoder_timer + tim3::kCnt) = 0x1234;
  Reg(kRamBlocks.joint_spi + spi1::kSr) = spi1::sr::kRxne.Bit();  // a frame is waiting
  g_run.bridge_enabled = true;
  g_run.duty = Duty::FromRaw(12000);
  for (const Entry& e : kEntries) {
    // A tick's computation passes between the sample and the actuation.
    Reg(kRamBlocks.cycle_counter + dwt::kCyccnt) =
        Reg(kRamBlocks.cycle_counter + dwt::kCyccnt) + 1000;
    Reg(kRamBlocks.joint_spi + spi1::kSr) = spi1::sr::kRxne.Bit();
    bench::Measure(e);
  }
  return 0;
}
