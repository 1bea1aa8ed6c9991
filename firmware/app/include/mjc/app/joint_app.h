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
  // Starts idle and uncalibrated with `config` (which must validate; its backlash is
  // the placeholder until a calibration is set).
  explicit JointApp(const ControlConfig& config);

  // --- main-loop context -----------------------------------------------------------
  CommandOutcome Configure(const ControlConfig& config);
  CommandOutcome SetCalibration(const BacklashConfig& backlash);
  CommandOutcome StartTrial(const SineConfig& sine);
  CommandOutcome StartCalibrationSweep(const SweepConfig& sweep);
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
    control_.ISR_Step(io.ISR_Read(), &result_);
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
    kStop,
    kClearFaults,
  };
  struct Command {
    CommandKind kind = CommandKind::kStop;
    ControlConfig config;
    SineConfig sine;
    SweepConfig sweep;
  };

  CommandOutcome Submit(const Command& command);
  void ISR_ApplyCommand();
  void ISR_AfterStep();
  void ISR_Enter(AppState next);
  void ISR_Refuse(CommandResult result, std::uint8_t detail = 0);

  ControlTick control_;
  TickResult result_;
  AppState state_ = AppState::kIdle;
  bool calibrated_ = false;
  SpscQueue<Command, 4> commands_;
  SpscQueue<AppEvent, 64> events_;
};

}  // namespace mjc::app
