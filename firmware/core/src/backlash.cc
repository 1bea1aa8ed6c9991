#include "mjc/core/backlash.h"

namespace mjc {
BacklashConfigError Validate(const BacklashConfig& config) {
  if (config.alpha <= kMinBacklashAlpha || config.alpha >= kMaxBacklashAlpha) {
    return BacklashConfigError::kAlphaOutOfRange;
  }
  if (Abs(config.c_right) > kMaxBacklashOffset ||
      Abs(config.c_left) > kMaxBacklashOffset) {
    return BacklashConfigError::kOffsetOutOfRange;
  }
  if (config.c_left > config.c_right) return BacklashConfigError::kLeftAboveRight;
  if (config.cable_friction < Torque{} || config.cable_friction > kMaxCableFriction) {
    return BacklashConfigError::kFrictionOutOfRange;
  }
  return BacklashConfigError::kOk;
}

BacklashModel::BacklashModel(const BacklashConfig* config, State* state)
    : config_(config), state_(state) {
  Configure(Stiffness{});
}

void BacklashModel::Configure(Stiffness sea_stiffness) {
  alpha_ = config_->alpha;
  alpha_c_right_ = Mul<Angle>(config_->alpha, config_->c_right);
  alpha_c_left_ = Mul<Angle>(config_->alpha, config_->c_left);
  slip_ = kNoSlip;
  if (config_->cable_friction == Torque{} || sea_stiffness <= Stiffness{}) return;
  // τ_f/K in rad, rounded to nearest, through int64: Torque and Stiffness are both
  // Q7.24, so the quotient of the raw values scaled by 2^24 is the Q7.24 angle (both
  // are positive here). Capped at kNoSlip (a slack spring and a strong sheath: the
  // cable never slides in any reachable deflection).
  const std::int64_t k = sea_stiffness.raw();
  const std::int64_t slip =
      ((static_cast<std::int64_t>(config_->cable_friction.raw()) << Angle::kFracBits) +
       k / 2) /
      k;
  if (slip < kNoSlip.raw()) slip_ = Angle::FromRaw(static_cast<std::int32_t>(slip));
}

Angle BacklashModel::Reset(Angle motor, Angle joint) {
  state_->output = Clamp(joint, LowerEdge(motor), UpperEdge(motor));
  return state_->output;
}

InverseBacklash::InverseBacklash(const BacklashConfig* config, State* state)
    : config_(config), state_(state) {
  Configure();
}

void InverseBacklash::Configure() {
  alpha_inverse_ = Divide<Scale>(Scale(1), config_->alpha);
}

Angle InverseBacklash::Command(Angle wanted) {
  const Angle base = Mul<Angle>(alpha_inverse_, wanted);
  if (!state_->initialized) {
    // Unknown direction: centre of the slack.
    state_->last_command =
        base + Angle::FromRaw(config_->c_left.raw() / 2 + config_->c_right.raw() / 2);
    state_->initialized = true;
  } else if (wanted > state_->last_wanted) {
    state_->last_command = base + config_->c_right;
  } else if (wanted < state_->last_wanted) {
    state_->last_command = base + config_->c_left;
  }
  state_->last_wanted = wanted;
  return state_->last_command;
}

}  // namespace mjc
