#pragma once

// One joint board seen from the host over a CanLink: commands with their answers,
// trial configuration, and what the board reports (heartbeat, telemetry, window
// summaries reassembled from their five frames, faults). Used by mjc trial and monitor.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "mjc/host/can_link.h"
#include "mjc/protocol/codec.h"

namespace mjc::host {

// A window summary as the host reassembles it, in physical units.
struct BoardWindow {
  Motion motion = Motion::kFlexion;
  std::uint16_t repetition = 0;
  bool eta_valid = false;
  double eta_percent = 0;
  double loading_J = 0, unloading_J = 0, positive_J = 0, negative_J = 0;
  double peak_power_W = 0, peak_torque_Nm = 0;
  std::uint32_t start_tick = 0, peak_tick = 0, end_tick = 0;
  double net_J() const { return loading_J + unloading_J; }
};

struct BoardStatus {
  bool heard = false;
  protocol::BoardState state = protocol::BoardState::kIdle;
  bool calibrated = false;
  bool bridge_enabled = false;
  Fault fault = Fault::kNone;
  std::uint32_t tick = 0;
  double motor_rad = 0, joint_rad = 0, torque_Nm = 0, power_W = 0, energy_J = 0;
};

class BoardClient {
 public:
  // `link` must outlive the client; it is filtered to this node's frames.
  BoardClient(CanLink* link, std::uint8_t node);

  // Sends a command and waits for its CommandResult: nullopt when the board does not
  // answer within timeout_ms (then *why names the node).
  std::optional<protocol::CommandOutcomeCode> Command(protocol::CommandCode code,
                                                      int timeout_ms, std::string* why);
  bool SendTrialConfig(const protocol::TrialConfig& config, std::string* why);

  // Reads a parameter: nullopt when the board does not answer, or answers with a status
  // other than kOk (then *why says which).
  std::optional<std::int32_t> ReadParam(protocol::ParamId id, int timeout_ms,
                                        std::string* why);

  // Handles what arrives within timeout_ms; true if anything did.
  bool Poll(int timeout_ms);

  // Windows completed since the last call.
  std::vector<BoardWindow> TakeWindows();
  const BoardStatus& status() const { return status_; }
  std::uint64_t malformed() const { return malformed_; }

 private:
  void Handle(const protocol::CanFrame& frame);

  CanLink* link_;
  std::uint8_t node_;
  std::uint8_t sequence_ = 0;
  BoardStatus status_;
  BoardWindow partial_;
  std::vector<BoardWindow> windows_;
  std::optional<protocol::CommandResult> last_result_;
  std::optional<protocol::ParamValue> last_param_;
  std::uint64_t malformed_ = 0;
};

}  // namespace mjc::host
