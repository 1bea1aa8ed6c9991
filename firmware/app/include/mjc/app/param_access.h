// The parameters of the protocol's list (protocol/params.h) bound to the board's fields:
// the CAN node's own settings, the control configuration, and what the board holds. The
// list says who may write what and within which raw range; this says where each lives.
// A compile-time check (param_access.cc) makes sure every id of the list is bound.
#pragma once

#include <cstdint>

#include "mjc/core/control_tick.h"
#include "mjc/protocol/params.h"

namespace mjc::app {

struct CanNodeConfig;

// Where the parameters live.
struct ParamFields {
  CanNodeConfig* node;     // kNode (and the build id)
  ControlConfig* control;  // kControl, and the calibration in force
  bool* calibrated;        // kCalibrated
};

// The raw value of `id` (a fixed-point field's raw integer); false for an id no field
// is bound to (none of the list's).
bool ReadParam(protocol::ParamId id, const ParamFields& fields, std::int32_t* raw);

// Sets `id`'s field to `raw`; the caller has checked the list's access and range. False
// for a read-only field.
bool WriteParam(protocol::ParamId id, std::int32_t raw, const ParamFields& fields);

// The joint's limits the board holds (docs: protocol/params.h, kJointLimit): torque_max
// within joint_torque_limit, and a joint limit never loosened. True, with the limit in
// *bound, when writing `raw` to `id` would go beyond one; false for any other id.
bool BeyondJointLimit(protocol::ParamId id, std::int32_t raw, const ParamFields& fields,
                      std::int32_t* bound);

// The control configuration's torque_max brought within joint_torque_limit (after the
// limit was tightened).
void KeepWithinJointLimits(const ParamFields& fields);

}  // namespace mjc::app
