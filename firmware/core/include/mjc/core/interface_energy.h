// Interface power and energy (paper eqs. 2, 3, 6) and the per-window summaries of
// docs/DESIGN.md §2, step 4.
//
// Energy is integrated exactly: every tick adds the raw Q24 power to an int64 (units of
// 2^-24 W·tick), so the sum is exact whatever the decimation of telemetry, and it
// cannot overflow in 24 h at 10 kHz even at full-scale power (FIXED_POINT.md). Joules
// are computed only when read: E = Σ · 2^-24 / f_tick.
#pragma once

#include <cstdint>

#include "mjc/core/interface_fit.h"
#include "mjc/core/quantities.h"
#include "mjc/core/trajectory.h"

namespace mjc {

// Σ P in raw power units per tick → joules, for one tick rate: E_raw (Q32 J) =
// Σ · 2^8 / f_tick, rounded to nearest (ties away from zero), exact for every int64
// sum. Uses one 64-bit division: for readout (window ends, reports), not per tick.
class EnergyScale {
 public:
  // tick_hz: 256..1,000,000.
  explicit constexpr EnergyScale(std::uint32_t tick_hz) : tick_hz_(tick_hz) {}
  constexpr Energy ToEnergy(std::int64_t power_sum) const {
    const std::int64_t f = tick_hz_;
    const std::int64_t q =
        power_sum / f;  // |q · 2^8| <= 2^63 · 2^8 / f: fits for f >= 256
    const std::int64_t r = power_sum % f;  // same sign as power_sum, |r| < f
    const std::int64_t scaled = r * 256;
    const std::int64_t fraction = (scaled >= 0 ? scaled + f / 2 : scaled - f / 2) / f;
    return Energy::FromRaw(q * 256 + fraction);
  }

 private:
  std::uint32_t tick_hz_;
};

class EnergyAccumulator {
 public:
  void Add(Power p) { sum_ += p.raw(); }
  std::int64_t raw_sum() const { return sum_; }
  void Clear() { sum_ = 0; }

 private:
  std::int64_t sum_ = 0;
};

enum class Motion : std::uint8_t { kFlexion = 1, kExtension = 2 };

// One motion window: a lobe of the commanded sinusoid, split at its commanded peak.
struct WindowSummary {
  Motion motion = Motion::kFlexion;
  std::uint16_t repetition = 0;  // the sine cycle it belongs to, 0-based
  std::uint32_t start_tick = 0;  // first tick of loading
  std::uint32_t peak_tick = 0;   // first tick of unloading
  std::uint32_t end_tick = 0;    // first tick after unloading
  Energy loading;                // ∫P over the loading half (robot → interface: > 0)
  Energy unloading;      // ∫P over the unloading half (interface → robot: < 0)
  Energy net;            // loading + unloading
  Energy positive_work;  // ∫max(P, 0) over the window
  Energy negative_work;  // ∫min(P, 0) over the window
  // η = (1 − |E_unloading| / E_loading) · 100 %, eq. (6); zero when E_loading <= 0
  // (eta_valid false).
  Ratio eta_percent;
  bool eta_valid = false;
  Power peak_power;    // the sample of largest |P|, with its sign
  Torque peak_torque;  // the sample of largest |τ|, with its sign
};

// η in percent from raw energy sums (any common unit), rounded to nearest.
Ratio EtaPercent(std::int64_t loading, std::int64_t unloading, bool* valid);

// Splits power into flexion/extension windows by the trajectory segment of the tick the
// power belongs to (the caller delays the segment by the estimator's delay so both
// refer to the same instant). A window completes when unloading ends; one interrupted
// before (a fault, a stop) is dropped and counted.
class WindowTracker {
 public:
  explicit WindowTracker(std::uint32_t tick_hz) : scale_(tick_hz) {}

  // One tick of aligned samples (power, torque, joint angle and velocity of one
  // instant). Returns true and fills *done, and *done_fit with the window's
  // least-squares sums of τ against θ_j and θ̇_j (interface_fit.h), when a window has
  // just completed.
  bool Update(std::uint32_t tick, Segment segment, std::uint16_t repetition, Power power,
              Torque torque, Angle joint, AngularVelocity velocity, WindowSummary* done,
              InterfaceFitSums* done_fit);

  std::uint32_t dropped_windows() const { return dropped_; }
  void Clear();

 private:
  enum class Phase : std::uint8_t { kNone, kLoading, kUnloading };

  void Begin(std::uint32_t tick, Motion motion, std::uint16_t repetition);
  void Finish(std::uint32_t tick, WindowSummary* done) const;

  EnergyScale scale_;
  Phase phase_ = Phase::kNone;
  Motion motion_ = Motion::kFlexion;
  std::uint16_t repetition_ = 0;
  std::uint32_t start_tick_ = 0;
  std::uint32_t peak_tick_ = 0;
  std::int64_t loading_ = 0;
  std::int64_t unloading_ = 0;
  std::int64_t positive_ = 0;
  std::int64_t negative_ = 0;
  // |raw| as an unsigned, exact for every int32 (no saturation to test).
  static constexpr std::uint32_t Magnitude(std::int32_t raw) {
    return raw < 0 ? 0u - static_cast<std::uint32_t>(raw)
                   : static_cast<std::uint32_t>(raw);
  }

  Power peak_power_;
  Torque peak_torque_;
  // Their magnitudes, kept beside them: each tick compares one magnitude, not two
  // saturating Abs (4 Cortex-M4 instructions a tick, tick_instructions_cm4).
  std::uint32_t peak_power_magnitude_ = 0;
  std::uint32_t peak_torque_magnitude_ = 0;
  InterfaceFitSums fit_sums_;
  std::uint32_t dropped_ = 0;
};

// The paper analyses the middle three of five repetitions: which repetitions to keep.
struct RepetitionRange {
  std::uint16_t first = 0;
  std::uint16_t count = 0;
  constexpr bool Contains(std::uint16_t r) const {
    return r >= first && r - first < count;
  }
};
constexpr RepetitionRange MiddleRepetitions(std::uint16_t total, std::uint16_t keep) {
  if (keep >= total) return {0, total};
  return {static_cast<std::uint16_t>((total - keep) / 2), keep};
}

// Inlined into the tick: as a call with nine arguments (five on the stack) it cost the
// tick 9 Cortex-M4 instructions more (tick_instructions_cm4). Begin and Finish, once a
// window, stay calls.
[[gnu::always_inline]] inline bool WindowTracker::Update(
    std::uint32_t tick, Segment segment, std::uint16_t repetition, Power power,
    Torque torque, Angle joint, AngularVelocity velocity, WindowSummary* done,
    InterfaceFitSums* done_fit) {
  const bool flexion_loading = segment == Segment::kFlexionLoading;
  const bool extension_loading = segment == Segment::kExtensionLoading;
  const bool unloading =
      segment == Segment::kFlexionUnloading || segment == Segment::kExtensionUnloading;
  const Motion motion = (flexion_loading || segment == Segment::kFlexionUnloading)
                            ? Motion::kFlexion
                            : Motion::kExtension;
  bool completed = false;

  // Leaving the current window?
  if (phase_ == Phase::kUnloading && !(unloading && motion == motion_)) {
    Finish(tick, done);
    *done_fit = fit_sums_;
    completed = true;
    phase_ = Phase::kNone;
  } else if (phase_ == Phase::kLoading && !(flexion_loading || extension_loading) &&
             !(unloading && motion == motion_)) {
    ++dropped_;  // loading interrupted before the peak
    phase_ = Phase::kNone;
  }

  if (phase_ == Phase::kNone && (flexion_loading || extension_loading)) {
    Begin(tick, motion, repetition);
  } else if (phase_ == Phase::kLoading && unloading && motion == motion_) {
    phase_ = Phase::kUnloading;
    peak_tick_ = tick;
  }
  // Unloading seen without its loading half (started mid-window) opens no window.

  if (phase_ != Phase::kNone) {
    (phase_ == Phase::kLoading ? loading_ : unloading_) += power.raw();
    (power.raw() > 0 ? positive_ : negative_) += power.raw();
    if (const std::uint32_t m = Magnitude(power.raw()); m > peak_power_magnitude_) {
      peak_power_ = power;
      peak_power_magnitude_ = m;
    }
    if (const std::uint32_t m = Magnitude(torque.raw()); m > peak_torque_magnitude_) {
      peak_torque_ = torque;
      peak_torque_magnitude_ = m;
    }
    fit_sums_.Add(joint, velocity, torque);
  }
  return completed;
}

}  // namespace mjc
