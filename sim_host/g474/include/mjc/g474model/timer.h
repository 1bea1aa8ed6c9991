// TIM1 (advanced-control) and TIM3 (general-purpose, 16-bit) of the STM32G474, from
// RM0440 chapters "Advanced-control timers (TIM1/TIM8/TIM20)" and "General-purpose
// timers (TIM2/TIM3/TIM4/TIM5)" (offsets, fields and reset values from ST's SVD v2.9;
// the TIM1-only registers RCR, BDTR, CCR5/6, CCMR3, DTR2 are reserved on TIM3).
//
// Covered:
//  - Time base: counter clocked by the APB timer clock (RCC: ×2 when the APB prescaler
//    is not 1) through PSC; ARR with ARPE preload; edge-aligned up/down (DIR) and
//    centre-aligned modes 1..3 (CMS: 0..ARR−1 up, overflow, ARR..1 down, underflow);
//    the repetition counter (TIM1): an update event every RCR+1 overflows/underflows;
//    UDIS, URS, UG (re-initialises counter and prescaler, loads the preloaded PSC, ARR,
//    RCR and CCRx); SR.UIF (rc_w0) and DIER.UIE → the interrupt line.
//  - Outputs: OCxM frozen/forced/PWM mode 1/2 (OCxM[3] included), CCRx with OCxPE
//    preload; CCxE/CCxP and, on TIM1, CCxNE/CCxNP, BDTR.MOE/OSSI/OSSR, CR2.OISx idle
//    levels and the dead time (BDTR.DTG with its four encodings and CR1.CKD), following
//    the manual's "Output control bits for complementary OCx and OCxN channels" table.
//    The world reads each output's level now and its duty cycle over a period (PWM
//    duty with dead time subtracted from each edge of a complementary pair).
//  - Encoder interface: SMS = 0001/0010/0011 (x2 on TI1, x2 on TI2, x4) and the G4's
//    x1 modes 1110/1111, counting the edges of TI1FP1/TI2FP2 (CCxP inverts) as the
//    manual's "counting direction versus encoder signals" table gives, wrapping at ARR
//    with an update event. Inputs arrive as pin level changes through the GPIO AF
//    routing: a wrong pin or AF number and the counter does not move.
//
// Not covered (reported where software selects them): input capture, compare flags
// CCxIF and their interrupts, the "on match" output modes' timing (they hold their
// level), one-pulse mode, retriggerable/combined/asymmetric PWM, break inputs, DMA,
// slave modes other than encoder, the clock-plus-direction encoder modes, the index
// (ECR), dithering, UIFREMAP, input filters (ignored: edges are clean).
//
// Debug: the DBGMCU freeze (SetDebugStopped, from VirtualChip's Halt) as the manual's
// "Debug mode" paragraph has it.
#pragma once

#include <array>
#include <cstdint>

#include "mjc/g474model/common.h"
#include "mjc/g474model/gpio.h"
#include "mjc/g474model/rcc.h"
#include "mjc/g474model/register_table.h"

namespace mjc::g474model {

// What an output does over a PWM period: driven or floating, and the fraction of the
// period its pin is high.
struct OutputWave {
  bool driven = false;
  double duty = 0;
};

class Timer final : public Peripheral {
 public:
  enum class Kind { kAdvanced, kGeneral16 };
  static constexpr std::uint32_t kTim1Base = 0x40012C00;
  static constexpr std::uint32_t kTim3Base = 0x40000400;

  Timer(Kind kind, const char* name, ViolationLog* log, const Rcc* rcc);

  bool Read(const Access& a, std::uint32_t* value) override;
  bool Write(const Access& a) override;
  void Reset() override;
  void Advance(Picoseconds now) override;
  Picoseconds NextEvent() const override;

  // Update interrupt line (TIM1_UP_TIM16, IRQ 25; TIM3, IRQ 29).
  bool update_irq() const { return (sr_ & 1u) && (dier_ & 1u); }
  // Input channel 1..4 sees `level` (from the pin the chip routed to it).
  void OnInput(int channel, bool level);
  // Output channel 1..4 (complementary: CHxN).
  OutputWave Wave(int channel, bool complementary) const;
  Drive Level(int channel, bool complementary) const;

  // When the counter's next update event (overflow/underflow with the repetition
  // counter run out) happens at the present configuration, whether or not it raises
  // an interrupt; kNever when the counter is stopped, an encoder or slave, or UDIS
  // masks it. The world steps what the outputs drive at these times.
  Picoseconds NextUpdate() const;
  std::uint32_t counter() const { return cnt_; }
  // The core halted by a debugger with this timer's DBGMCU freeze bit set (RM0440
  // "Debug mode"): the counter stops (encoder edges meanwhile are not counted), and an
  // advanced timer's outputs are disabled as if MOE were cleared — the idle levels
  // OISx/OISxN with OSSI = 1, released (Hi-Z) with OSSI = 0. MOE itself is unchanged,
  // so the outputs come back when the core runs again. The caller advances the model
  // to the present first.
  void SetDebugStopped(bool stopped) { debug_stopped_ = stopped; }
  bool debug_stopped() const { return debug_stopped_; }
  double kernel_hz() const;
  // The counter clock's update period (an update event every … seconds) at the present
  // configuration, for reports.
  double UpdatePeriodSeconds() const;

 private:
  // The registers without code of their own (register_table.h); TIM1's extra ones.
  static RegisterTable<Timer> Registers();
  static RegisterTable<Timer> AdvancedRegisters();
  // CCR1..4 (and TIM1's CCR5/6) at `offset`, or null.
  std::uint32_t* Ccr(std::uint32_t offset);
  unsigned Sms() const { return (smcr_ & 7u) | ((smcr_ >> 13) & 8u); }
  bool EncoderMode() const;
  unsigned Cms() const { return (cr1_ >> 5) & 3u; }
  bool CountingDown() const { return (cr1_ >> 4) & 1u; }
  unsigned OcMode(int ch) const;
  bool RefActiveNow(int ch) const;
  double RefDuty(int ch) const;
  double DeadTimeSeconds() const;
  double PeriodSeconds() const;
  void LoadShadows();
  void CountEvent();  // an overflow or underflow
  void Tick(std::uint64_t n);
  void EncoderStep(int delta);
  std::uint64_t TicksToNextUpdate() const;

  Kind kind_;
  const char* name_;
  ViolationLog* log_;
  const Rcc* rcc_;
  Picoseconds now_ = 0;
  TickCounter clock_;
  std::uint32_t cr1_ = 0, cr2_ = 0, smcr_ = 0, dier_ = 0, sr_ = 0, ccmr1_ = 0, ccmr2_ = 0,
                ccer_ = 0, psc_ = 0, arr_ = 0xFFFF, rcr_ = 0, bdtr_ = 0, ccmr3_ = 0,
                dtr2_ = 0, ecr_ = 0, tisel_ = 0, af1_ = 0, af2_ = 0, dcr_ = 0;
  std::array<std::uint32_t, 6> ccr_{};
  // Shadow (active) registers and counter state.
  std::uint32_t cnt_ = 0, psc_count_ = 0, psc_active_ = 0, arr_active_ = 0xFFFF, rep_ = 0,
                rcr_active_ = 0;
  std::array<std::uint32_t, 4> ccr_active_{};
  bool down_ = false;  // centre-aligned: counting down now
  std::array<bool, 4> input_{};
  bool reported_mode_ = false;
  bool debug_stopped_ = false;
};

}  // namespace mjc::g474model
