// The joint board's whole tick with its STM32G474 drivers on the Cortex-M4, for ./bench's
// tick_instructions_g474: what the tick's interrupt runs on the board (TickInterrupt,
// firmware/boards/g474_joint/board.cc) — io.ISR_BeginTick() (TIM1's update flag, the
// cycle count), then JointBoard::ISR_Tick(io): the command mailbox, ISR_Read() (TIM3's
// count, the SPI frame), the control tick, the windows and the telemetry, ISR_Write()
// (chip select, the duty to TIM1, the enable line, the next SPI command). The firmware's
// default configuration, calibrated, mid-trial (a 15° sine at 0.5 Hz). Stm32g4JointIo's
// register blocks are placed in RAM — QEMU's mps2-an386 has no STM32 peripherals; the
// blocks are template arguments, so only the addresses in the loads and stores differ —
// and scripts/cm4-instructions counts each of 100 ticks ("g474_tick").
//
// What registers in RAM cannot do, and what the bench does instead:
//  - A read of SPI1's DR does not clear RXNE, so the driver's check for a slipped
//    pipeline (RXNE still set once the frame is read) always fires: it reads SR and DR
//    once more and reports no frame. BenchIo hands the tick the frame that was in DR
//    instead (a 16-bit load and a store, counted).
//  - The DWT's counter does not count. BenchIo advances it by 2,000 cycles after the
//    sample, as the tick's computation does on the chip, so the CS-high hold (t_CSn)
//    is already spent when ISR_Write lowers CS; the CS-to-clock hold (t_L) then runs its
//    bounded wait to its end (60 passes), where the chip waits 60 cycles (as in
//    joint_io_write).
// Both add a few dozen instructions to the chip's count at most.
#include <cstdint>

#include "bench_cm4.h"
#include "g474_ram_blocks.h"
#include "hal/stm32g4/joint_io.h"
#include "mjc/app/joint_board.h"
#include "mjc/app/joint_config.h"
#include "mjc/core/encoder.h"

namespace {

using namespace mjc;
using namespace mjc::stm32g4;
using bench::Announce;
using bench::kRamBlocks;
using bench::Reg;

// The board's JointIo with the two concessions above.
class BenchIo {
 public:
  void Init() { (void)io_.Init(); }
  void ISR_BeginTick() { io_.ISR_BeginTick(); }
  Sample ISR_Read() {
    Sample s = io_.ISR_Read();
    s.joint_frame =
        *reinterpret_cast<volatile std::uint16_t*>(kRamBlocks.joint_spi + spi1::kDr);
    Reg(kRamBlocks.cycle_counter + dwt::kCyccnt) =
        Reg(kRamBlocks.cycle_counter + dwt::kCyccnt) + 2000;
    return s;
  }
  void ISR_Write(const Actuation& a) { io_.ISR_Write(a); }

 private:
  Stm32g4JointIo<kRamBlocks> io_;
};
static_assert(hal::JointIo<BenchIo>);

BenchIo g_io;
app::JointBoard g_board{app::JointBoardConfig{app::DefaultJointConfig(), {}, 0, 1},
                        nullptr, nullptr};

// The sensors of an ideal joint: the motor exactly at the tick's last setpoint, the
// joint a sixth of the way (tests/bench/core_bench_cm4.cc's), put into TIM3's counter
// and SPI1's data register with a frame waiting.
void Sense(Angle setpoint) {
  Reg(kRamBlocks.encoder_timer + tim3::kCnt) =
      static_cast<std::uint16_t>((setpoint.raw() / 515) & 0xFFFF);
  const std::int32_t joint = setpoint.raw() / 6434 / 6;
  Reg(kRamBlocks.joint_spi + spi1::kDr) =
      EncodeJointFrame(static_cast<std::uint16_t>(joint & 0x3FFF), false);
  Reg(kRamBlocks.joint_spi + spi1::kSr) = spi1::sr::kRxne.Bit();
}

// What TickInterrupt runs.
void Tick() {
  g_io.ISR_BeginTick();
  g_board.ISR_Tick(g_io);
}

// The main loop's side between ticks: the app's events taken (nothing counted).
void MainLoop() {
  app::AppEvent event;
  while (g_board.app().PopEvent(&event)) {
  }
}

void Step() {
  Sense(g_board.app().last().telemetry.setpoint);
  Tick();
  MainLoop();
}

}  // namespace

int main() {
  g_io.Init();
  Calibration cal;
  cal.backlash.c_right = Angle::FromDouble(0.0192);
  cal.backlash.c_left = Angle::FromDouble(-0.0157);
  if (g_board.app().SetCalibration(cal).result != app::CommandOutcomeCode::kAccepted) {
    qemu::SemihostExit(3);
  }
  Step();
  SineConfig sine;
  sine.amplitude = Angle::FromDouble(0.2618);
  sine.frequency = Frequency::FromDouble(0.5);
  sine.repetitions = 5;
  if (g_board.app().StartTrial(sine).result != app::CommandOutcomeCode::kAccepted) {
    qemu::SemihostExit(4);
  }
  // 1,100 ticks in: the joint moving, the velocity window (1,001 ticks) full. (QEMU
  // traces every instruction of the image, so the lead-in is kept short.)
  for (int i = 0; i < 1100; ++i) Step();

  Announce("baseline");
  mjc_bench_begin();
  mjc_bench_end();
  for (int i = 0; i < 100; ++i) {
    Sense(g_board.app().last().telemetry.setpoint);
    Announce("g474_tick");
    mjc_bench_begin();
    Tick();
    mjc_bench_end();
    MainLoop();
  }
  // Measured mid-trial, or not at all.
  if (g_board.app().state() != app::BoardState::kRunning) qemu::SemihostExit(5);
  return 0;
}
