// The joint board's application: the state machine around the control tick.
//
//   kIdle ──StartTrial──▶ kRunning ──trajectory done / Stop──▶ kIdle
//   kIdle ──StartCalibrationSweep──▶ kCalibrating ──done / Stop──▶ kIdle
//   any ──fault (same tick: bridge off)──▶ kFault ──ClearFaults (cause gone)──▶ kIdle
//
// The bridge is enabled only in kRunning and kCalibrating. Configuration and
// calibration writes are refused unless idle; trials are refused while uncalibrated
// (a calibration sweep is what makes the board calibrated).
//
// Contexts: commands are submitted from the main loop (CAN, host), validated there, and
// handed to the tick through a single-producer single-consumer mailbox; ISR_Tick
// applies them at the start of the next tick, re-checking the state, so nothing races
// with a fault raised in between. Events (window summaries, faults, state changes,
// refusals) go back through another SPSC queue.
#pragma once

#include <atomic>
#include <cstdint>

#include "hal/joint_io.h"
#include "mjc/app/spsc_queue.h"
#include "mjc/core/control_tick.h"

namespace mjc::app {

enum class AppState : std::uint8_t {
  kIdle = 0,
  kCalibrating = 1,
  kRunning = 2,
  kFault = 3
};

// Stable numbers: a command's outcome travels back to the host.
enum class CommandResult : std::uint8_t {
  kAccepted = 0,
  kRefusedNotIdle = 1,       // configuration, calibration and trials need kIdle
  kRefusedUncalibrated = 2,  // no valid backlash calibration yet
  kRefusedInvalid = 3,       // the config failed validation (see detail)
  kRefusedFaultActive = 4,   // ClearFaults while the cause is still present
  kRefusedBusy = 5,          // the mailbox is full: try again next tick
};

struct CommandOutcome {
  CommandResult result = CommandResult::kAccepted;
  std::uint8_t detail = 0;  // the validating module's stable error code, when invalid
};

struct AppEvent {
  enum class Kind : std::uint8_t {
    kWindow = 1,
    kFault = 2,
    kStateChanged = 3,
    kCommandRefused = 4,
  };
  Kind kind = Kind::kStateChanged;
  std::uint32_t tick = 0;
  AppState state = AppState::kIdle;
  Fault fault = Fault::kNone;
  CommandOutcome refusal;
  WindowSummary window;
};

class JointApp {
 public:
  // Starts idle and uncalibrated with `config` (which must validate). Its backlash
  // offsets serve only until SetCalibration(): trials are refused before that.
  explicit JointApp(const ControlConfig& config);

  // --- main-loop context -----------------------------------------------------------
  CommandOutcome Configure(const ControlConfig& config);
  CommandOutcome SetCalibration(const BacklashConfig& backlash);
  // A whole calibration: backlash, SEA stiffness 2kr_j² and the joint encoder's zero.
  CommandOutcome SetCalibration(const BacklashConfig& backlash, Stiffness sea_stiffness,
                                std::uint16_t joint_zero_count);
  CommandOutcome StartTrial(const SineConfig& sine);
  CommandOutcome StartCalibrationSweep(const SweepConfig& sweep);
  // Streamed setpoints: the setpoint moves toward the latest target at most max_rate
  // (rad/s), starting from the present setpoint. Needs a calibrated, idle board.
  CommandOutcome StartStream(AngularVelocity max_rate);
  // The latest streamed target (rad); takes effect at the next tick. Lock-free: one
  // 32-bit store, read once a tick.
  void SetStreamTarget(Angle target) {
    stream_target_.store(target.raw(), std::memory_order_relaxed);
  }
  // Set by the CAN side when streamed setpoints stop arriving: the tick's supervisor
  // sees it as a command timeout (controlled stop, latched).
  void SetCommandTimeout(bool timed_out) {
    command_timeout_.store(timed_out, std::memory_order_relaxed);
  }
  CommandOutcome Stop();
  CommandOutcome ClearFaults();

  bool PopEvent(AppEvent* out) { return events_.Pop(out); }
  std::uint32_t dropped_events() const { return events_.dropped(); }

  AppState state() const { return state_; }
  bool calibrated() const { return calibrated_; }
  const ControlTick& control() const { return control_; }
  // The last tick's result (telemetry, actuation); read between ticks.
  const TickResult& last() const { return result_; }

  // --- interrupt context -----------------------------------------------------------
  template <hal::JointIo Io>
  void ISR_Tick(Io& io) {
    ISR_ApplyCommand();
    Sample sample = io.ISR_Read();
    if (command_timeout_.load(std::memory_order_relaxed)) sample.command_timeout = true;
    ISR_FollowStream();
    control_.ISR_Step(sample, &result_);
    ISR_AfterStep();
    // A state left in this tick (trial done, stop) disarms before the write.
    if (!control_.armed()) result_.actuation = Actuation{};
    io.ISR_Write(result_.actuation);
  }

 private:
  enum class CommandKind : std::uint8_t {
    kConfigure,
    kSetCalibration,
    kStartTrial,
    kStartSweep,
    kStartStream,
    kStop,
    kClearFaults,
  };
  struct Command {
    CommandKind kind = CommandKind::kStop;
    ControlConfig config;
    SineConfig sine;
    SweepConfig sweep;
    AngularVelocity stream_rate;
    bool full_calibration = false;
  };

  CommandOutcome Submit(const Command& command);
  CommandOutcome SubmitCalibration(const ControlConfig& calibration, bool full);
  void ISR_ApplyCommand();
  void ISR_FollowStream();
  void ISR_AfterStep();
  void ISR_Enter(AppState next);
  void ISR_Refuse(CommandResult result, std::uint8_t detail = 0);

  ControlTick control_;
  TickResult result_;
  AppState state_ = AppState::kIdle;
  bool calibrated_ = false;
  SpscQueue<Command, 4> commands_;
  SpscQueue<AppEvent, 64> events_;
  std::atomic<std::int32_t> stream_target_{0};
  std::int32_t applied_stream_target_ = 0;
  AngularVelocity stream_rate_;
  std::atomic<bool> command_timeout_{false};
};

}  // namespace mjc::app
