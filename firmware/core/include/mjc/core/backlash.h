// Bowden-cable backlash: the forward model of the paper's eq. (4) (Yun et al.) as a
// play operator, and its inverse for compensation in the position loop.
//
// Forward: the cable-side joint angle θ̃_j follows α(θ_m − c_r) while the motor turns
// positive, α(θ_m − c_l) while it turns negative, and holds in the dead band between:
//   θ̃_j[n] = clamp(θ̃_j[n−1], α(θ_m[n] − c_r), α(θ_m[n] − c_l)),   c_l <= c_r, α > 0.
// What holds the cable side in the dead band is the sheath's friction. The SEA spring
// pulls it towards the joint with K·(θ̃_j − θ_j); once that exceeds the sheath's
// friction τ_f, the cable slides until the spring torque is back to τ_f (on a stiff
// joint after a reversal, e.g. the cable side follows the receding pulley instead of
// staying where it was). With τ_f known (BacklashConfig.cable_friction) the operator
// first lets the cable slide, then applies the pulley's edges:
//   θ̃_j[n] = clamp(clamp(θ̃_j[n−1], θ_j − τ_f/K, θ_j + τ_f/K),
//                  α(θ_m[n] − c_r), α(θ_m[n] − c_l))
// (quasi-static: the sheath's viscous part and the cable's inertia settle within a
// tick). τ_f = 0 means not modelled: the cable holds against any spring torque, eq. (4)
// as the paper has it.
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
  // τ_f, N·m at the joint, [0, kMaxCableFriction]; 0: not modelled (see above).
  Torque cable_friction = Torque{};

  friend constexpr bool operator==(const BacklashConfig&,
                                   const BacklashConfig&) = default;
};

// α and the inverse model's 1/α both live in Scale (Q3.28, below 8), so α is legal in
// (1/8, 8); a real Bowden drive has α near 1.
inline constexpr Scale kMinBacklashAlpha = Scale::FromDouble(0.125);  // exclusive
inline constexpr Scale kMaxBacklashAlpha = Scale::Max();              // exclusive

// A cable slack offset beyond ±0.5 rad (29°) is not a Bowden cable that works.
inline constexpr Angle kMaxBacklashOffset = Angle::FromDouble(0.5);

// A sheath that holds more than 5 N·m at the joint (five times a Maestro joint's torque
// limit) would never let the cable move at all.
inline constexpr Torque kMaxCableFriction = Torque::FromDouble(5.0);

// Stable codes: they travel over CAN with a refused calibration.
enum class BacklashConfigError : std::uint8_t {
  kOk = 0,
  kAlphaOutOfRange = 1,
  kOffsetOutOfRange = 2,
  kLeftAboveRight = 3,
  kFrictionOutOfRange = 4,
};

BacklashConfigError Validate(const BacklashConfig& config);

// The play operator. Config and state belong to the caller; the config must have
// passed Validate().
class BacklashModel {
 public:
  struct State {
    Angle output;  // θ̃_j of the last Reset or Update
    void Clear() { *this = State{}; }
  };

  // Configures for no SEA stiffness (the cable never slides) until Configure().
  BacklashModel(const BacklashConfig* config, State* state);

  // What the config and the SEA stiffness K in use fix, computed once and again
  // whenever either changes: α and the edges' offsets α·c_r and α·c_l (kept here, one
  // load each a tick, not through the config), and the spring deflection τ_f/K at
  // which the cable slides (a division; never for τ_f = 0 or K = 0).
  void Configure(Stiffness sea_stiffness);

  // Starts the operator at the joint's measured angle, clamped into the band that the
  // motor angle allows (the cable side cannot be outside it).
  Angle Reset(Angle motor, Angle joint);

  // One tick after Reset(): θ_m (motor-pulley angle) and θ_j (the joint's measured
  // angle, |θ_j| <= 2π; a decoded one is in [−π, π)) in, θ̃_j out. Inlined into the
  // tick (as a call it cost 1 to 2 Cortex-M4 instructions more).
  [[gnu::always_inline]] Angle Update(Angle motor, Angle joint) {
    // Unchecked: |θ_j| <= 2π and slip_ <= kNoSlip = 64 rad, so θ_j ± slip_ stays
    // inside Angle's ±128 rad.
    const Angle held = Clamp(state_->output, Angle::FromRaw(joint.raw() - slip_.raw()),
                             Angle::FromRaw(joint.raw() + slip_.raw()));
    const Angle scaled = Mul<Angle>(alpha_, motor);
    state_->output = Clamp(held, scaled - alpha_c_right_, scaled - alpha_c_left_);
    return state_->output;
  }

  // The deflection at which the cable slides (kNoSlip when it never does).
  Angle slip() const { return slip_; }

  // "Never slides": a deflection no joint reaches, small enough that θ_j ± it stays in
  // Angle's ±128 rad (the joint's angle is within ±2π).
  static constexpr Angle kNoSlip = Angle::FromDouble(64.0);

  // The band [α(θ_m − c_r), α(θ_m − c_l)] for a motor angle, as αθ_m − αc: one
  // product a tick instead of two (each term rounded once, so an edge is within 1 LSB
  // of the exact value).
  Angle LowerEdge(Angle motor) const {
    return Mul<Angle>(alpha_, motor) - alpha_c_right_;
  }
  Angle UpperEdge(Angle motor) const { return Mul<Angle>(alpha_, motor) - alpha_c_left_; }

 private:
  const BacklashConfig* config_;
  State* state_;
  Scale alpha_;
  Angle alpha_c_right_;  // α·c_r
  Angle alpha_c_left_;   // α·c_l
  Angle slip_ = kNoSlip;
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
