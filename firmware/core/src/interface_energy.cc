#include "mjc/core/interface_energy.h"

namespace mjc {
namespace {

using fixed_detail::BitLength;

std::int64_t Magnitude(std::int64_t v) { return v < 0 ? -v : v; }

}  // namespace

Ratio EtaPercent(std::int64_t loading, std::int64_t unloading, bool* valid) {
  if (loading <= 0) {
    *valid = false;
    return Ratio{};
  }
  *valid = true;
  // 100·(L − |U|)/L in Q16. Scale both down until L < 2^30 (L keeps 29+ significant
  // bits). |L − |U|| is clamped at 400·L, where η is beyond Ratio's ±32,768 % anyway,
  // so the numerator stays below 400 · 2^30 · 100 · 2^16 < 2^62.
  const std::int64_t u = Magnitude(unloading);
  const int k = BitLength(static_cast<std::uint64_t>(loading)) > 30
                    ? BitLength(static_cast<std::uint64_t>(loading)) - 30
                    : 0;
  const std::int64_t l_scaled = loading >> k;
  std::int64_t diff = (loading - u) >> k;
  const std::int64_t limit = 400 * l_scaled;
  diff = diff > limit ? limit : (diff < -limit ? -limit : diff);
  const std::int64_t num = diff * 100 * 65536;
  const std::int64_t q = (num >= 0 ? num + l_scaled / 2 : num - l_scaled / 2) / l_scaled;
  return Ratio::FromRaw(fixed_detail::SaturateTo<std::int32_t>(q));
}

void WindowTracker::Clear() {
  phase_ = Phase::kNone;
  dropped_ = 0;
}

void WindowTracker::Begin(std::uint32_t tick, Motion motion, std::uint16_t repetition) {
  phase_ = Phase::kLoading;
  motion_ = motion;
  repetition_ = repetition;
  start_tick_ = tick;
  peak_tick_ = tick;
  loading_ = unloading_ = positive_ = negative_ = 0;
  peak_power_ = Power{};
  peak_torque_ = Torque{};
  peak_power_magnitude_ = 0;
  peak_torque_magnitude_ = 0;
  fit_sums_.Clear();
}

void WindowTracker::Finish(std::uint32_t tick, WindowSummary* done) const {
  done->motion = motion_;
  done->repetition = repetition_;
  done->start_tick = start_tick_;
  done->peak_tick = peak_tick_;
  done->end_tick = tick;
  done->loading = scale_.ToEnergy(loading_);
  done->unloading = scale_.ToEnergy(unloading_);
  done->net = scale_.ToEnergy(loading_ + unloading_);
  done->positive_work = scale_.ToEnergy(positive_);
  done->negative_work = scale_.ToEnergy(negative_);
  done->eta_percent = EtaPercent(loading_, unloading_, &done->eta_valid);
  done->peak_power = peak_power_;
  done->peak_torque = peak_torque_;
}

}  // namespace mjc
