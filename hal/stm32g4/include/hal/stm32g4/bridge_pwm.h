// TIM1 driving a full H-bridge for the brushed DC motor (RM0440 §28, advanced-control
// timer): two legs, leg A on CH1/CH1N and leg B on CH2/CH2N, each a complementary pair
// with dead time, centre-aligned.
//
// Frequency. PWM at 20 kHz, the control tick every second period (10 kHz). Both legs
// switch, in phase opposition (leg A high for (1+d)/2 of the period, leg B for (1−d)/2):
// the motor sees pulses of ±V at twice the PWM frequency, so its current ripple — what
// makes a motor sing — is at 40 kHz, well above the audible band, while each transistor
// switches at 20 kHz. At 170 MHz, centre-aligned (the counter runs 0 → ARR → 0):
// ARR = 170 MHz / (2 × 20 kHz) = 4250 counts, 12 bits of duty resolution.
//
// The tick. In centre-aligned mode the repetition counter counts both the overflow and
// the underflow (RM0440 §28.3.3, "Repetition counter"): REP = 3 gives one update event
// every 4 half-periods = 2 PWM periods = 100 µs, and with it the update interrupt
// TIM1_UP_TIM16 (IRQ 25) that runs the tick. The compare registers are preloaded
// (OCxPE; ARR too, ARPE): a duty written in a tick takes effect at the next update, so
// the PWM never sees half-written pairs, at one tick of latency.
//
// Dead time. Between one transistor of a leg turning off and the other turning on both
// must be off, or the leg shorts the supply. With a gate driver and MOSFETs of the
// class this board uses (turn-off delay plus fall time ≈ 100-150 ns), 250 ns leaves
// margin: ≥ 250 ns, DTG encoded per RM0440 §28.6.20 (TIMx_BDTR.DTG) from tDTS = 1/170 MHz
// (CKD = 0): 43 × 5.88 ns = 252.9 ns. It costs 2 × 253 ns / 50 µs ≈ 1 % of voltage
// near zero duty.
//
// Stopping. A disabled bridge has its enable line low (the gate driver off) *and* both
// low sides on: CCR1 = CCR2 = 0 holds OCxREF low, so CHx is off and CHxN on (after the
// dead time). Shorting the motor through the low sides brakes it (its back-EMF drives a
// current that opposes the motion) instead of letting it freewheel, and it stays so
// even if the enable line were stuck high. The same levels are the idle states
// (CR2.OISx = 0, OISxN = 1, BDTR.OSSI = 1) that the outputs take when MOE is cleared —
// what EmergencyStop() and a fault handler do, in one store, whatever the counter does.
//
// The low side's minimum on-time. With CCRx = ARR, OCxREF would be low for a single
// count (5.9 ns) at the top of each period, far shorter than the dead time, so the low
// side would never turn on (RM0440 §28.3.16: the complementary output's active phase
// starts one dead time after the reference's edge, and a pulse shorter than the dead
// time gives none). A gate driver whose high side is supplied by a bootstrap capacitor
// recharges that capacitor only while its own leg's low side conducts: at a sustained
// full duty it would sag into its under-voltage lock-out and the high side would drop.
// So each leg's compare value stays within [N, ARR − N]: OCxREF is low for at least 2N
// counts around the top of the count, and the low side conducts 2N counts less one dead
// time. N follows from the board's minimum on-time (JointIoBlocks, a property of the
// gate driver it carries) by CompareMargin() below; it costs 2N/ARR of the largest mean
// voltage (the board's figure is in its pin table's comment).
#pragma once

#include <cstdint>

#include "hal/stm32g4/clock.h"
#include "hal/stm32g4/mmio.h"
#include "hal/stm32g4/regs/tim1.h"
#include "mjc/core/quantities.h"

namespace mjc::stm32g4 {

inline constexpr std::uint32_t kPwmHz = 20'000;
inline constexpr std::uint32_t kTickHz = 10'000;
inline constexpr std::uint32_t kPwmArr = kTimerClockHz / (2 * kPwmHz);
static_assert(kTimerClockHz % (2 * kPwmHz) == 0 && kPwmArr == 4250);
static_assert(kPwmHz % kTickHz == 0);
inline constexpr std::uint32_t kPwmRepetition = 2 * (kPwmHz / kTickHz) - 1;
static_assert(kPwmRepetition == 3);
// Core cycles per tick (the tick's budget; the core clock equals the timer clock).
inline constexpr std::uint32_t kTickCycles = kSysclkHz / kTickHz;

// BDTR.DTG for at least `ns` nanoseconds of dead time at tDTS = 1/clock_hz (RM0440
// TIMx_BDTR: DTG[7:5] = 0xx: DT = DTG[7:0] × tDTS; 10x: (64 + DTG[5:0]) × 2 tDTS;
// 110: (32 + DTG[4:0]) × 8 tDTS; 111: (32 + DTG[4:0]) × 16 tDTS).
consteval std::uint32_t DeadTimeCode(std::uint32_t ns, std::uint32_t clock_hz) {
  const std::uint64_t t = (std::uint64_t{ns} * clock_hz + 999'999'999u) / 1'000'000'000u;
  if (t <= 127) return static_cast<std::uint32_t>(t);
  if (t <= 2 * 127) return 0x80u | static_cast<std::uint32_t>((t + 1) / 2 - 64);
  if (t <= 8 * 63) return 0xC0u | static_cast<std::uint32_t>((t + 7) / 8 - 32);
  return 0xE0u | static_cast<std::uint32_t>((t + 15) / 16 - 32);
}
// The dead time a DTG code gives, in ns × 1000 (for the assertion below and the tests).
consteval std::uint64_t DeadTimePs(std::uint32_t code, std::uint32_t clock_hz) {
  std::uint64_t ticks = 0;
  if ((code & 0x80u) == 0) {
    ticks = code;
  } else if ((code & 0xC0u) == 0x80u) {
    ticks = (64u + (code & 0x3Fu)) * 2u;
  } else if ((code & 0xE0u) == 0xC0u) {
    ticks = (32u + (code & 0x1Fu)) * 8u;
  } else {
    ticks = (32u + (code & 0x1Fu)) * 16u;
  }
  return ticks * 1'000'000'000'000ull / clock_hz;
}
inline constexpr std::uint32_t kDeadTimeNs = 250;
inline constexpr std::uint32_t kDeadTimeCode = DeadTimeCode(kDeadTimeNs, kTimerClockHz);
static_assert(kDeadTimeCode == 43);
static_assert(DeadTimePs(kDeadTimeCode, kTimerClockHz) >= kDeadTimeNs * 1000ull);

// The compare margin N (counts, see the header comment) that keeps a leg's low side on
// for at least `min_on_ns` every period: OCxREF low for 2N counts of 1/f, less one dead
// time, ≥ min_on_ns, i.e. N = ⌈(min_on + dead time) × f / 2⌉.
consteval std::uint32_t CompareMargin(std::uint32_t min_on_ns) {
  const std::uint64_t ps =
      std::uint64_t{min_on_ns} * 1000u + DeadTimePs(kDeadTimeCode, kTimerClockHz);
  constexpr std::uint64_t kTwoSecondsPs = 2'000'000'000'000ull;
  return static_cast<std::uint32_t>((ps * kTimerClockHz + kTwoSecondsPs - 1) /
                                    kTwoSecondsPs);
}

// Compare values of the two legs for a duty.
struct BridgeCompare {
  std::uint16_t leg_a = 0;  // CCR1
  std::uint16_t leg_b = 0;  // CCR2
};

// d ∈ [−1, 1) (Q15, raw r ∈ [−32768, 32767]): leg A high for (1 + d)/2 of the period,
// leg B for (1 − d)/2, so the motor's mean voltage is d × V. CCR1 = round(ARR × (32768
// + r) / 65536) clamped to [margin, ARR − margin], CCR2 = ARR − CCR1: the pair always
// sums to ARR (both legs stay within the margin), d = 0 gives 2125/2125 (no mean
// voltage), the extremes ARR − margin / margin: each low side conducts its minimum
// on-time even at a full command. Every raw value is legal.
constexpr BridgeCompare CompareForDuty(Duty duty, std::uint32_t margin) {
  const auto offset = static_cast<std::uint32_t>(std::int32_t{duty.raw()} + 32768);
  std::uint32_t a = (kPwmArr * offset + 32768u) >> 16;
  a = a < margin ? margin : a;
  a = a > kPwmArr - margin ? kPwmArr - margin : a;
  return {static_cast<std::uint16_t>(a), static_cast<std::uint16_t>(kPwmArr - a)};
}

// kMargin: CompareMargin() of the board's gate driver (at most a quarter period).
template <Address kTim, std::uint32_t kMargin>
class Stm32g4BridgePwm {
  static_assert(kMargin <= kPwmArr / 4, "a margin beyond a quarter period");

 public:
  // Configures TIM1 (its clock and the output pins' alternate functions must be set;
  // the bridge's enable line must be low) and starts it with both low sides on and the
  // update interrupt enabled in TIM1 (the NVIC line is the caller's).
  static void Init() {
    using namespace tim1;
    // RM0440 §28.3.16 "Complementary outputs and dead-time insertion" and §28.3.11
    // "PWM mode": counter stopped while configuring.
    Write32(kTim + kCr1, 0);
    Write32(kTim + kPsc, psc::kPsc.Value(0));
    Write32(kTim + kArr, arr::kArr.Value(kPwmArr));
    Write32(kTim + kRcr, rcr::kRep.Value(kPwmRepetition));
    // PWM mode 1 (OCxM = 0110: OCxREF high while CNT < CCRx), preloaded, outputs.
    Write32(kTim + kCcmr1, ccmr1::kCc1s.Value(0) | ccmr1::kOc1m.Value(0b110) |
                               ccmr1::kOc1pe.Bit() | ccmr1::kCc2s.Value(0) |
                               ccmr1::kOc2m.Value(0b110) | ccmr1::kOc2pe.Bit());
    Write32(kTim + kCcr1, ccr1::kCcr1.Value(0));
    Write32(kTim + kCcr2, ccr2::kCcr2.Value(0));
    // Idle levels with MOE = 0: high sides off, low sides on.
    Write32(kTim + kCr2, cr2::kOis1n.Bit() | cr2::kOis2n.Bit());
    // Dead time, off-state forced (OSSI/OSSR: outputs stay driven at their idle/inactive
    // levels instead of released when disabled), LOCK level 1 (DTG, OISx and the break
    // settings can no longer change until reset), MOE still 0.
    Write32(kTim + kBdtr, bdtr::kDtg.Value(kDeadTimeCode) | bdtr::kOssi.Bit() |
                              bdtr::kOssr.Bit() | bdtr::kLock.Value(1));
    // Both channels and their complements, active high.
    Write32(kTim + kCcer, ccer::kCc1e.Bit() | ccer::kCc1ne.Bit() | ccer::kCc2e.Bit() |
                              ccer::kCc2ne.Bit());
    // Centre-aligned mode 1, ARR preloaded, tDTS = tCK_INT; URS: only the counter's
    // overflow/underflow (not UG) raises the update interrupt.
    const std::uint32_t cr1 = cr1::kCms.Value(1) | cr1::kArpe.Bit() | cr1::kUrs.Bit();
    Write32(kTim + kCr1, cr1);
    // UG loads ARR, CCRx and the repetition counter from their preloads.
    Write32(kTim + kEgr, egr::kUg.Bit());
    Write32(kTim + kSr, 0);
    Write32(kTim + kDier, dier::kUie.Bit());
    // Main output enable: from here the outputs follow OCxREF (both low sides on).
    Write32(kTim + kBdtr, Read32(kTim + kBdtr) | bdtr::kMoe.Bit());
    Write32(kTim + kCr1, cr1 | cr1::kCen.Bit());
  }

  // The tick's duty, from the next update on.
  static void ISR_SetDuty(Duty duty) {
    const BridgeCompare c = CompareForDuty(duty, kMargin);
    Write32(kTim + tim1::kCcr1, c.leg_a);
    Write32(kTim + tim1::kCcr2, c.leg_b);
  }
  // Both low sides on from the next update on (see the header comment).
  static void ISR_Brake() {
    Write32(kTim + tim1::kCcr1, 0);
    Write32(kTim + tim1::kCcr2, 0);
  }
  // Clears the update flag; true if it was set (the tick's interrupt entry). rc_w0 bits:
  // writing 0 clears, writing 1 leaves the others untouched (RM0440 TIMx_SR).
  static bool ISR_TakeUpdate() {
    const bool set = tim1::sr::kUif.IsSet(Read32(kTim + tim1::kSr));
    Write32(kTim + tim1::kSr, ~tim1::sr::kUif.Bit());
    return set;
  }
  // MOE off: every output to its idle level (low sides on) at once. Any context; the
  // bridge stays so until Init() runs again.
  static void EmergencyStop() {
    Write32(kTim + tim1::kBdtr, Read32(kTim + tim1::kBdtr) & ~tim1::bdtr::kMoe.Bit());
  }
};

}  // namespace mjc::stm32g4
