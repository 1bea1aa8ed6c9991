// Bowden-cable backlash: the forward model of the paper's eq. (4) (Yun et al.) as a
// play operator, and its inverse for compensation in the position loop.
//
// Forward: the cable-side joint angle θ̃_j follows α(θ_m − c_r) while the motor turns
// positive, α(θ_m − c_l) while it turns negative, and holds in the dead band between:
//   θ̃_j[n] = clamp(θ̃_j[n−1], α(θ_m[n] − c_r), α(θ_m[n] − c_l)),   c_l <= c_r, α > 0.
// Inverse: the motor angle that puts the cable side at a wanted θ̃_j, taking up the
// slack on the side the wanted motion is heading: θ_m = θ̃_j/α + c_r when θ̃_j rises,
// θ̃_j/α + c_l when it falls, unchanged while it holds.
#pragma once

#include <cstdint>

#include "mjc/core/quantities.h"

namespace mjc {

struct BacklashConfig {
  Scale alpha = Scale::FromDouble(1.0);  // r_m / r_j, legal (1/8, 8)
  Angle c_right = Angle{};  // c_r, rad, [-kMaxBacklashOffset, kMaxBacklashOffset]
  Angle c_left = Angle{};   // c_l, rad, [-kMaxBacklashOffset, c_r]
};

// α and the inverse model's 1/α both live in Scale (Q3.28, below 8), so α is legal in
// (1/8, 8); a real Bowden drive has α near 1.
inline constexpr Scale kMinBacklashAlpha = Scale::FromDouble(0.125);  // exclusive
inline constexpr Scale kMaxBacklashAlpha = Scale::Max();              // exclusive

// A cable slack offset beyond ±0.5 rad (29°) is not a Bowden cable that works.
inline constexpr Angle kMaxBacklashOffset = Angle::FromDouble(0.5);

// Stable codes: they travel over CAN with a refused calibration.
enum class BacklashConfigError : std::uint8_t {
  kOk = 0,
  kAlphaOutOfRange = 1,
  kOffsetOutOfRange = 2,
  kLeftAboveRight = 3,
};

BacklashConfigError Validate(const BacklashConfig& config);

// The play operator. Config and state belong to the caller; the config must have
// passed Validate().
class BacklashModel {
 public:
  struct State {
    Angle output;  // θ̃_j of the last update
    bool initialized = false;
    void Clear() { *this = State{}; }
  };

  BacklashModel(const BacklashConfig* config, State* state)
      : config_(config), state_(state) {}

  // Starts the operator at the joint's measured angle, clamped into the band that the
  // motor angle allows (the cable side cannot be outside it).
  Angle Reset(Angle motor, Angle joint);

  // One tick: θ_m (motor-pulley angle) in, θ̃_j out. Resets on the first call. Inlined
  // into the tick (as a call it cost 1 to 2 Cortex-M4 instructions more).
  [[gnu::always_inline]] Angle Update(Angle motor) {
    if (!state_->initialized) {
      // No joint reading to start from: the middle of the band.
      const Angle lo = LowerEdge(motor);
      const Angle hi = UpperEdge(motor);
      return Reset(motor, Angle::FromRaw(lo.raw() + (hi - lo).raw() / 2));
    }
    state_->output = Clamp(state_->output, LowerEdge(motor), UpperEdge(motor));
    return state_->output;
  }

  // The band [α(θ_m − c_r), α(θ_m − c_l)] for a motor angle. Inline: each tick's Update
  // computes both, and as calls they cost it 12 instructions more on Cortex-M4.
  Angle LowerEdge(Angle motor) const {
    return Mul<Angle>(config_->alpha, motor - config_->c_right);
  }
  Angle UpperEdge(Angle motor) const {
    return Mul<Angle>(config_->alpha, motor - config_->c_left);
  }

 private:
  const BacklashConfig* config_;
  State* state_;
};

// The inverse model for backlash compensation. alpha_inverse = 1/α is computed once
// from the config (a division), never per tick.
class InverseBacklash {
 public:
  struct State {
    Angle last_wanted;
    Angle last_command;
    bool initialized = false;
    void Clear() { *this = State{}; }
  };

  InverseBacklash(const BacklashConfig* config, State* state);

  // Recomputes 1/α after the config changed.
  void Configure();

  // The motor-pulley angle for a wanted cable-side joint angle θ̃_j.
  Angle Command(Angle wanted);

 private:
  const BacklashConfig* config_;
  State* state_;
  Scale alpha_inverse_;
};

}  // namespace mjc
