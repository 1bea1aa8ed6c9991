// The control tick's hardware on the STM32G474 (hal::JointIo): the motor's quadrature
// count (TIM3), the joint encoder's SPI frame (AS5047P on SPI1), the H-bridge (TIM1 and
// its enable line), and the tick's own duration on the DWT cycle counter.
//
// Every register address is a compile-time constant (the blocks are a template
// argument), so a tick's I/O is a handful of loads and stores to constant addresses, and
// the same driver runs against blocks placed in RAM (an instruction-count image on
// QEMU's mps2-an386, which has no STM32 peripherals) at the same cost.
//
// The interrupt (TIM1_UP_TIM16, IRQ 25, at 10 kHz) runs, in order:
//   io.ISR_BeginTick();   // clears TIM1's update flag, notes the cycle count
//   app.ISR_Tick(io);     // ISR_Read(), the tick, ISR_Write()
// A tick whose ISR_Write() comes more than one tick period (17,000 cycles) after its
// ISR_BeginTick() overran: the next ISR_Read() reports Sample::tick_overrun (fault 300).
#pragma once

#include <atomic>
#include <cstdint>

#include "hal/joint_io.h"
#include "hal/stm32g4/as5047p.h"
#include "hal/stm32g4/bridge_pwm.h"
#include "hal/stm32g4/gpio.h"
#include "hal/stm32g4/poll.h"
#include "hal/stm32g4/quadrature_encoder.h"
#include "hal/stm32g4/regs/spi.h"
#include "hal/stm32g4/regs/tim1.h"
#include "hal/stm32g4/regs/tim3.h"

namespace mjc::stm32g4 {

struct JointIoBlocks {
  Address bridge_timer = tim1::kBase;
  Address encoder_timer = tim3::kBase;
  Address joint_spi = spi1::kBase;
  PortPin joint_cs;                    // the AS5047P's chip select (output, idle high)
  PortPin bridge_enable;               // the H-bridge's enable line (output, idle low)
  Address cycle_counter = dwt::kBase;  // the DWT block (tick duration, SPI hold times)
  // The gate driver's minimum low-side on-time per PWM period, in ns (bridge_pwm.h: a
  // bootstrap-supplied high side recharges only then). A property of the board's gate
  // driver; every board states it (0 is refused below).
  std::uint32_t bridge_low_side_min_ns = 0;
};

template <JointIoBlocks kBlocks>
class Stm32g4JointIo {
  static_assert(kBlocks.bridge_low_side_min_ns > 0,
                "the board's gate driver needs its minimum low-side on-time");

 public:
  using Pwm = Stm32g4BridgePwm<kBlocks.bridge_timer,
                               CompareMargin(kBlocks.bridge_low_side_min_ns)>;
  using Encoder = Stm32g4QuadratureEncoder<kBlocks.encoder_timer>;
  using JointEncoder =
      As5047p<kBlocks.joint_spi, kBlocks.joint_cs, kBlocks.cycle_counter>;
  using Enable = OutputPin<kBlocks.bridge_enable>;
  using Clock = CycleCounter<kBlocks.cycle_counter>;

  // After clocks and pins (and on the chip: the DWT's counter is started here): the
  // bridge disabled (enable low, both low sides on), the
  // encoder counting, the joint encoder's pipeline primed, then TIM1 started with its
  // update interrupt (its NVIC line is the caller's: EnableIrq(irq::kTim1Update, ...)).
  // False if the joint encoder's primer frame did not complete (the ticks will then
  // report its frames as parity faults).
  bool Init() {
    Enable::Clear();
    EnableCycleCounter();
    Encoder::Init();
    const bool joint_ok = joint_.Init();
    Pwm::Init();
    joint_.ISR_Start();  // the first tick's frame
    return joint_ok;
  }

  // The first thing the tick's interrupt does.
  void ISR_BeginTick() {
    start_ = Clock::Now();
    (void)Pwm::ISR_TakeUpdate();
  }

  Sample ISR_Read() {
    Sample s;
    s.motor_count = Encoder::ISR_Count();
    s.joint_frame = joint_.ISR_Finish();
    s.tick_overrun = overrun_pending_;
    overrun_pending_ = false;
    return s;
  }

  void ISR_Write(const Actuation& actuation) {
    joint_.ISR_Select();
    if (actuation.bridge_enabled) {
      Pwm::ISR_SetDuty(actuation.duty);
      Enable::Set();
    } else {
      Enable::Clear();
      Pwm::ISR_Brake();
    }
    joint_.ISR_Command();
    const std::uint32_t cycles = Clock::Now() - start_;
    last_tick_cycles_.store(cycles, std::memory_order_relaxed);
    if (cycles > max_tick_cycles_.load(std::memory_order_relaxed)) {
      max_tick_cycles_.store(cycles, std::memory_order_relaxed);
    }
    if (cycles > kTickCycles) {
      overrun_pending_ = true;
      overruns_.store(overruns_.load(std::memory_order_relaxed) + 1,
                      std::memory_order_relaxed);
    }
  }

  // Any context (a fault handler): enable line low and every output at its idle level
  // (low sides on), without the counter's help.
  static void EmergencyStop() {
    Enable::Clear();
    Pwm::EmergencyStop();
  }

  // Tick durations in core cycles (from ISR_BeginTick to the end of ISR_Write), for
  // telemetry and benchmarks; read from the main loop (32-bit loads, not torn).
  std::uint32_t last_tick_cycles() const {
    return last_tick_cycles_.load(std::memory_order_relaxed);
  }
  std::uint32_t max_tick_cycles() const {
    return max_tick_cycles_.load(std::memory_order_relaxed);
  }
  std::uint32_t overruns() const { return overruns_.load(std::memory_order_relaxed); }

 private:
  JointEncoder joint_;
  std::uint32_t start_ = 0;
  std::atomic<std::uint32_t> last_tick_cycles_{0};
  std::atomic<std::uint32_t> max_tick_cycles_{0};
  std::atomic<std::uint32_t> overruns_{0};
  bool overrun_pending_ = false;
};

}  // namespace mjc::stm32g4
