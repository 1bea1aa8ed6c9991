#include "mjc/host/describe.h"

namespace mjc::host {

std::string_view FaultName(Fault fault) {
  switch (fault) {
    case Fault::kNone:
      return "none";
    case Fault::kJointParity:
      return "joint encoder parity error";
    case Fault::kJointErrorFlag:
      return "joint encoder error flag";
    case Fault::kJointJump:
      return "joint angle jumped";
    case Fault::kJointStuck:
      return "joint encoder stuck";
    case Fault::kMotorStuck:
      return "motor stalled or its encoder stuck";
    case Fault::kJointAngleLimit:
      return "joint angle limit";
    case Fault::kMotorAngleLimit:
      return "motor angle limit";
    case Fault::kTorqueLimit:
      return "torque limit";
    case Fault::kVelocityLimit:
      return "joint velocity limit";
    case Fault::kTickOverrun:
      return "control tick overrun";
    case Fault::kCommandTimeout:
      return "streamed setpoints stopped";
    case Fault::kHostHeartbeatLost:
      return "host heartbeat lost";
    case Fault::kCanBusOff:
      return "CAN bus-off";
  }
  return "unknown fault";
}

std::string DescribeFault(Fault fault) {
  return std::to_string(static_cast<unsigned>(fault)) + " (" +
         std::string(FaultName(fault)) + ")";
}

std::string_view OutcomeName(protocol::CommandOutcomeCode outcome) {
  using protocol::CommandOutcomeCode;
  switch (outcome) {
    case CommandOutcomeCode::kAccepted:
      return "accepted";
    case CommandOutcomeCode::kRefusedNotIdle:
      return "the board is not idle";
    case CommandOutcomeCode::kRefusedUncalibrated:
      return "the board holds no calibration";
    case CommandOutcomeCode::kRefusedInvalid:
      return "invalid configuration";
    case CommandOutcomeCode::kRefusedFaultActive:
      return "a fault is latched or its cause is still present";
    case CommandOutcomeCode::kRefusedBusy:
      return "an earlier request is still being applied";
  }
  return "unknown outcome";
}

}  // namespace mjc::host
