// The attachment's own mechanics per motion window: a least-squares fit of
//   τ = k_i·θ_j + b_i·θ̇_j + τ_0
// to the tick's aligned samples (τ the SEA torque, θ_j the joint angle and θ̇_j its
// least-squares slope, all referring to the instant delay_ticks() old).
//
// Split by context. The tick adds each aligned sample to the window's normal-equation
// sums (InterfaceFitSums::Add: six 32×32→64 products into 96-bit sums, three 64-bit
// sums, a count), exactly: no rounding, so the sums are the same on the host and the
// Cortex-M4 and independent of when the main loop looks. The main loop solves the
// system once per window (SolveInterfaceFit), with Eigen fixed-size integer matrices.
//
// Why the tick accumulates instead of handing every sample to the main loop. Measured
// with `./bench` (tick_instructions_cm4, mean of 100 ticks mid-trial): the tick went
// from 982 to 1,097 Cortex-M4 instructions (+115, 0.7 % of the 17,000 cycles a tick
// has at 170 MHz). A queue of samples would cost the tick less (a push of three words,
// ~20 instructions) but not the core: the main loop would still do these products for
// every sample, plus the pops. It would also need RAM for every sample the main loop
// can fall behind by (a flash page erase stalls it for up to ~40 ms: 400 samples,
// 4.8 KB), and a sample lost to a full queue would make the fit inexact. The sums
// cost 128 bytes (and a queue of four completed windows' to the main loop, 544 bytes:
// JointApp::PopWindowFit), lose nothing, and leave the main loop one solve per window.
//
// Overflow bound (the longest window): a window's ticks are counted in a uint32, so
// n < 2^32. Every regressor is a raw int32 (|x| ≤ 2^31), so |Σx| < 2^31·2^32 = 2^63
// fits int64, and every product |x·y| ≤ 2^62, so |Σx·y| < 2^62·2^32 = 2^94 fits the
// 96-bit signed sum (Wide96, |v| < 2^95) whatever the trajectory and the tick rate.
//
// The solve (exact identity, not an approximation): eliminating τ_0 from the 3×3
// normal equations leaves the 2×2 system of the centred moments
//   [C_θθ C_θω; C_θω C_ωω]·[k b]ᵀ = [C_θτ C_ωτ]ᵀ,   τ_0 = τ̄ − k·θ̄ − b·ω̄,
// and the residual variance is C_ττ − k·C_θτ − b·C_ωτ. The centred moments are formed
// in int64 to within 2 raw² units (Centred in interface_fit.cc), each regressor is
// scaled by a power of two so its variance has 29–30 bits, and the 2×2 system is
// solved by its adjugate in int64 (every product < 2^61). The residual goes through
// the scaled solution in Q26, which puts a floor under the reported RMS of about
// 2.5e-4 of the torque's standard deviation over the window (a fit that good reads
// no lower). Errors against a double-precision solve of the same samples:
// tests/unit/core/interface_fit_test.cc.
#pragma once

#include <cstdint>

#include "mjc/core/fixed.h"
#include "mjc/core/quantities.h"

namespace mjc {

// A signed 96-bit sum of up to 2^32 − 1 products of two int32s: the normal-equation
// sums of a window. Written by hand because the Cortex-M4's compiler has no 128-bit
// integer. Held as value = top·2^64 + sum, sum an int64 that each product (|v| ≤ 2^62)
// is added to with wrap-around, and top the count of its signed overflows: +1 when the
// true sum passed INT64_MAX, −1 when it passed INT64_MIN. On the M4 that is SMULL, an
// ADDS/ADCS pair whose V flag is the overflow, and a branch taken only on an overflow
// (at most once in 2^63/|v| products in one direction: rare for a joint's angles and
// torques, every other tick for full-scale ones): the tick's six products cost 24
// instructions fewer than as two 64-bit sums of the product's words
// (tick_instructions_cm4). |value| < 2^94, so top
// stays within ±2^30.
class Wide96 {
 public:
  // Adds a·b.
  void AddProduct(std::int32_t a, std::int32_t b) {
    const std::int64_t v = fixed_detail::WideProduct(a, b);
    if (AddOverflows(v)) top_ += v < 0 ? -1 : 1;
  }
  // round(value / n) for n ≥ 1; the caller guarantees it fits int64 (a mean of
  // products of int32s: |v/n| ≤ 2^62). Ties away from zero.
  std::int64_t RoundDivide(std::uint32_t n) const;
  // The value's top 32 bits (signed) and low 64 bits.
  std::int32_t high() const { return top_ + (sum_ < 0 ? -1 : 0); }
  std::uint64_t low() const { return static_cast<std::uint64_t>(sum_); }

 private:
  // sum_ += v with wrap-around; true when the true sum left int64's range.
  bool AddOverflows(std::int64_t v) {
#if defined(__arm__)
    // The V flag of the high words' ADCS read by the branch itself: from
    // __builtin_add_overflow GCC made it a register first (three instructions more).
    bool overflow = false;
    asm("adds %Q[sum], %Q[sum], %Q[v]\n\tadcs %R[sum], %R[sum], %R[v]"
        : [sum] "+r"(sum_), "=@ccvs"(overflow)
        : [v] "r"(v));
    return overflow;
#else
    return __builtin_add_overflow(sum_, v, &sum_);
#endif
  }

  std::int64_t sum_ = 0;
  std::int32_t top_ = 0;
};

// The sums of one window's aligned samples: θ (Angle raw, Q24), ω (AngularVelocity
// raw, Q20), τ (Torque raw, Q24).
struct InterfaceFitSums {
  std::uint32_t count = 0;
  std::int64_t theta = 0, omega = 0, tau = 0;
  Wide96 theta_theta, theta_omega, omega_omega, theta_tau, omega_tau, tau_tau;

  // One aligned sample (tick context). Out of line on purpose: a straight-line
  // function keeps each sum's load, add and store together, where inlined into the
  // window tracker's branches GCC spilled all of them to the stack (the tick grew by 172
  // instructions, not 112; tick_instructions_cm4).
  void Add(Angle theta_j, AngularVelocity omega_j, Torque torque);
  void Clear() { *this = InterfaceFitSums{}; }
};

// Why a window's fit has no values. Stable numbers (they travel over CAN).
enum class InterfaceFitStatus : std::uint8_t {
  kOk = 0,
  kTooFewSamples = 1,  // fewer than kMinInterfaceFitSamples
  kNoMotion = 2,       // θ_j or θ̇_j constant over the window
  kCollinear = 3,      // θ_j and θ̇_j too correlated (ρ² > 3/4) to tell k_i from b_i
  kOutOfRange = 4,     // k_i, b_i or τ_0 beyond their formats (±128)
  kNotDelivered = 5,   // the window's sums did not reach the main loop
};

// A fit needs at least this many samples: a tenth of a second at 10 kHz, far less than
// any window of a trial (half a cycle).
inline constexpr std::uint32_t kMinInterfaceFitSamples = 1000;

struct InterfaceFit {
  InterfaceFitStatus status = InterfaceFitStatus::kTooFewSamples;
  Stiffness stiffness;  // k_i, N·m/rad
  Damping damping;      // b_i, N·m·s/rad
  Torque offset;        // τ_0, N·m
  Torque residual_rms;  // √(mean (τ − fit)²), N·m, saturating at 128
  bool valid() const { return status == InterfaceFitStatus::kOk; }
};

// Solves the window's least squares (main-loop context: a few hundred instructions
// and four 64-bit divisions). Every field is zero unless status is kOk.
InterfaceFit SolveInterfaceFit(const InterfaceFitSums& sums);

}  // namespace mjc
