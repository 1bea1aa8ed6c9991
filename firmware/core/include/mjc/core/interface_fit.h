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
// Why the tick accumulates instead of handing every sample to the main loop: a queue
// of samples would cost the tick a push of three words per tick (about the same
// instructions as the products here, measured in `./bench` as tick_instructions_cm4),
// plus RAM for every sample the main loop may fall behind by (a flash page erase
// stalls it for ~20 ms: 200 samples, 2.4 KB), and a sample lost to a full queue would
// make the fit inexact. The sums cost 100 bytes and lose nothing.
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

#include "mjc/core/quantities.h"

namespace mjc {

// A signed 96-bit sum of int64 terms: the normal-equation products of a window.
// Written by hand because the Cortex-M4's compiler has no 128-bit integer; three
// 32-bit limbs are what its add-with-carry instructions work on.
class Wide96 {
 public:
  // Adds v. The sum must stay within ±2^95 (the caller's bound).
  void Add(std::int64_t v) {
    const std::uint64_t sum = low_ + static_cast<std::uint64_t>(v);
    high_ += static_cast<std::int32_t>(v >> 63) + (sum < low_ ? 1 : 0);
    low_ = sum;
  }
  // round(value / n) for n ≥ 1; the caller guarantees it fits int64 (a mean of
  // products of int32s: |v/n| ≤ 2^62). Ties away from zero.
  std::int64_t RoundDivide(std::uint32_t n) const;
  std::int32_t high() const { return high_; }
  std::uint64_t low() const { return low_; }

 private:
  std::uint64_t low_ = 0;
  std::int32_t high_ = 0;
};

// The sums of one window's aligned samples: θ (Angle raw, Q24), ω (AngularVelocity
// raw, Q20), τ (Torque raw, Q24).
struct InterfaceFitSums {
  std::uint32_t count = 0;
  std::int64_t theta = 0, omega = 0, tau = 0;
  Wide96 theta_theta, theta_omega, omega_omega, theta_tau, omega_tau, tau_tau;

  // One aligned sample (tick context).
  void Add(Angle theta_j, AngularVelocity omega_j, Torque torque) {
    const std::int64_t t = theta_j.raw(), w = omega_j.raw(), q = torque.raw();
    ++count;
    theta += t;
    omega += w;
    tau += q;
    theta_theta.Add(t * t);
    theta_omega.Add(t * w);
    omega_omega.Add(w * w);
    theta_tau.Add(t * q);
    omega_tau.Add(w * q);
    tau_tau.Add(q * q);
  }
  void Clear() { *this = InterfaceFitSums{}; }
};

// Why a window's fit has no values. Stable numbers (they travel over CAN).
enum class InterfaceFitStatus : std::uint8_t {
  kOk = 0,
  kTooFewSamples = 1,  // fewer than kMinInterfaceFitSamples
  kNoMotion = 2,       // θ_j or θ̇_j constant over the window
  kCollinear = 3,      // θ_j and θ̇_j too correlated (ρ² > 3/4) to tell k_i from b_i
  kOutOfRange = 4,     // k_i, b_i or τ_0 beyond their formats (±128)
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
