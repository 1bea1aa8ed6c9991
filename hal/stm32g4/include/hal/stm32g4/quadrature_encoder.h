// TIM3 counting the motor's quadrature encoder in x4 mode (RM0440 §29.3, "Encoder
// interface mode" of the general-purpose timers): every edge of A and B counts, up or
// down by the phase order. The count is 16 bits and wraps; the core extends it across
// wraps (mjc/core/encoder.h), which needs fewer than 32768 counts between two ticks
// (3.3e8 counts/s at 10 kHz: far beyond any motor here).
//
// Input filter (TIMx_CCMR1.ICxF): an edge counts only after N equal samples at
// f_SAMPLING. ICxF = 0110: f_SAMPLING = f_DTS / 4 = 42.5 MHz, N = 6 → a level must hold
// 141 ns. That rejects ringing and short spikes on the encoder cable while passing edges
// 1 µs apart (1 M counts/s: a 1000-line encoder at 15,000 rpm).
#pragma once

#include <cstdint>

#include "hal/stm32g4/mmio.h"
#include "hal/stm32g4/regs/tim3.h"

namespace mjc::stm32g4 {

inline constexpr std::uint32_t kEncoderFilter = 0b0110;
// SMS = 0011: encoder mode 3, counting on both TI1 and TI2 edges (x4).
inline constexpr std::uint32_t kEncoderModeX4 = 0b0011;

template <Address kTim = tim3::kBase>
class Stm32g4QuadratureEncoder {
 public:
  // The timer's clock and the A/B pins' alternate functions must be set.
  static void Init() {
    using namespace tim3;
    Write32(kTim + kCr1, cr1::kCkd.Value(0));  // counter stopped, tDTS = tCK_INT
    // SMS[3:0] = 0011 across two fields (SMS[2:0] at bits 2:0, SMS[3] at bit 16).
    Write32(kTim + kSmcr, smcr::kSms.Value(kEncoderModeX4 & 0b111) |
                              smcr::kSms3.Value(kEncoderModeX4 >> 3));
    // CCxS = 01: IC1 on TI1, IC2 on TI2; filtered; no prescaler.
    Write32(kTim + kCcmr1, ccmr1::kCc1s.Value(0b01) | ccmr1::kIc1f.Value(kEncoderFilter) |
                               ccmr1::kCc2s.Value(0b01) |
                               ccmr1::kIc2f.Value(kEncoderFilter));
    // Both inputs non-inverted (CCxP = CCxNP = 0): counting direction is the phase order.
    Write32(kTim + kCcer, 0);
    Write32(kTim + kPsc, psc::kPsc.Value(0));
    Write32(kTim + kArr, arr::kArr.Value(0xFFFF));  // the full 16-bit range
    Write32(kTim + kEgr, egr::kUg.Bit());           // load PSC/ARR, count from 0
    Write32(kTim + kCr1, cr1::kCen.Bit());
  }

  // The 16-bit count now.
  static std::uint16_t ISR_Count() {
    return static_cast<std::uint16_t>(tim3::cnt::kCnt.Get(Read32(kTim + tim3::kCnt)));
  }
};

}  // namespace mjc::stm32g4
