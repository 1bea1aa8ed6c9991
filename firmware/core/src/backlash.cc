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
  return BacklashConfigError::kOk;
}

Angle BacklashModel::Reset(Angle motor, Angle joint) {
  state_->output = Clamp(joint, LowerEdge(motor), UpperEdge(motor));
  state_->initialized = true;
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
