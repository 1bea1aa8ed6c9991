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
// handed to the tick through a single-producer single-consumer mailbox; ISR_Tick takes
// one at the start of each tick and re-checks the state, so nothing races with a fault
// raised in between. Every command the mailbox took is answered by one kCommandDone
// event carrying the submitter's tag and the tick's verdict. Events (command verdicts,
// window summaries, faults, state changes) go back through another SPSC queue.
#pragma once

#include <atomic>
#include <cstdint>

#include "hal/joint_io.h"
#include "mjc/app/spsc_queue.h"
#include "mjc/app/tick_count.h"
#include "mjc/core/control_tick.h"
#include "mjc/protocol/states.h"

namespace mjc::app {

// The application's state and a command's outcome are the protocol's (they travel as
// they are).
using protocol::BoardState;
using protocol::CommandOutcomeCode;

struct CommandOutcome {
  CommandOutcomeCode result = CommandOutcomeCode::kAccepted;
  std::uint8_t detail = 0;  // the validating module's stable error code, when invalid
};

// The submitter's name for a command, returned unchanged with the tick's verdict (64
// bits: the joint service names a command by its origin, code, sequence and session).
using RequestTag = std::uint64_t;

struct AppEvent {
  enum class Kind : std::uint8_t {
    kWindow = 1,
    kFault = 2,
    kStateChanged = 3,
    kCommandDone = 4,
  };
  Kind kind = Kind::kStateChanged;
  std::uint32_t tick = 0;
  BoardState state = BoardState::kIdle;
  Fault fault = Fault::kNone;
  RequestTag tag = 0;      // kCommandDone: the command's tag
  CommandOutcome outcome;  // kCommandDone: the tick's verdict
  WindowSummary window;
};

class JointApp {
 public:
  // Starts idle and uncalibrated with `config`; an invalid one leaves ControlConfig{}'s
  // defaults in force (check it with ControlTick::Validate first). Its backlash
  // offsets serve only until SetCalibration(): trials are refused before that.
  explicit JointApp(const ControlConfig& config);

  // --- main-loop context -----------------------------------------------------------
  // Each submit validates what it can here and returns the refusal at once; kAccepted
  // means the tick has the command, and its verdict (applied, or refused because the
  // state changed meanwhile) follows as a kCommandDone event with `tag`.
  CommandOutcome Configure(const ControlConfig& config, RequestTag tag = 0);
  // A calibration (backlash, SEA stiffness 2kr_j², joint encoder zero); refusal detail:
  // the CalibrationError.
  CommandOutcome SetCalibration(const Calibration& calibration, RequestTag tag = 0);
  CommandOutcome StartTrial(const SineConfig& sine, RequestTag tag = 0);
  CommandOutcome StartCalibrationSweep(const RampedSineConfig& sweep, RequestTag tag = 0);
  // Streamed setpoints: the setpoint moves toward the latest target at most max_rate
  // (rad/s), starting from the present setpoint. Needs a calibrated, idle board.
  CommandOutcome StartStream(AngularVelocity max_rate, RequestTag tag = 0);
  // The latest streamed target (rad); takes effect at the next tick. Lock-free: one
  // 32-bit store, read once a tick.
  void SetStreamTarget(Angle target) {
    stream_target_.store(target.raw(), std::memory_order_relaxed);
  }
  // The main loop saw the setpoint stream or the host go quiet, or the bus go off
  // (IsExternalFault codes; others are ignored): the next tick latches the fault and
  // stops the motor. Lock-free and never lost: the tick loads the code and, when one
  // is pending, takes it with an atomic exchange. Two raised before one tick latch the
  // later one.
  void RaiseFault(Fault fault) {
    if (IsExternalFault(fault)) {
      raised_fault_.store(static_cast<std::uint16_t>(fault), std::memory_order_release);
    }
  }
  CommandOutcome Stop(RequestTag tag = 0);
  CommandOutcome ClearFaults(RequestTag tag = 0);

  bool PopEvent(AppEvent* out) { return events_.Pop(out); }
  std::uint32_t dropped_events() const { return events_.dropped(); }
  // The least-squares sums of the window that started at `start_tick` (a kWindow
  // event's window.start_tick), for SolveInterfaceFit. They travel in a queue of their
  // own, so the events stay small (128 bytes each otherwise, 8 KB over the event
  // queue); older sums whose events were lost are dropped on the way. False when they
  // are not there (the queue was full when the window ended).
  // `of_trial`, when given, says whether the window was a trial's (not a calibration
  // sweep's).
  bool PopWindowFit(std::uint32_t start_tick, InterfaceFitSums* out,
                    bool* of_trial = nullptr);
  // The attachment's fit of that window (PopWindowFit, SolveInterfaceFit; status
  // kNotDelivered when its sums are not there). A valid fit of a trial's window with
  // k, b ≥ 0 also becomes the velocity estimator's attachment model from the next tick
  // (ControlTick::SetAttachment); a calibration sweep moves the robot without the hand,
  // so its fits describe no attachment. Main-loop context.
  InterfaceFit SolveWindowFit(std::uint32_t start_tick);
  std::uint32_t dropped_attachment_updates() const { return attachments_.dropped(); }
  std::uint32_t dropped_window_fits() const { return window_fits_.dropped(); }

  // The configuration in force, as the main loop sees it: a consistent copy of the
  // tick's, taken again only when the tick has applied a new one (a configuration or a
  // calibration). Main-loop context.
  const ControlConfig& config() const;

  // The tick's own state, read in place: for tick context, or when no tick can run
  // meanwhile (a simulation between ticks, a test). The main loop uses Latest() and
  // config().
  BoardState state() const { return state_; }
  bool calibrated() const { return calibrated_; }
  const ControlTick& control() const { return control_; }

  // What the last tick left for the main loop, all of it from that one tick.
  struct Snapshot {
    Telemetry telemetry;
    bool bridge_enabled = false;
    BoardState state = BoardState::kIdle;
    bool calibrated = false;
  };
  // Copies the last tick's snapshot; the tick may interrupt the copy (TickCount).
  Snapshot Latest() const;
  // The last tick's whole result (telemetry, actuation, window, verdicts), in place:
  // for tick context, or when no tick can run meanwhile (a simulation between ticks).
  const TickResult& last() const { return result_; }

  // --- interrupt context -----------------------------------------------------------
  template <hal::JointIo Io>
  void ISR_Tick(Io& io) {
    ISR_ApplyRequest();
    const Sample sample = io.ISR_Read();
    ISR_FollowHost();
    control_.ISR_Step(sample, &result_);
    ISR_AfterStep();
    // A state left in this tick (trial done, stop) disarms before the write.
    if (!control_.armed()) result_.actuation = Actuation{};
    io.ISR_Write(result_.actuation);
    done_.ISR_Advance();
  }

 private:
  enum class RequestKind : std::uint8_t {
    kConfigure,
    kSetCalibration,
    kStartTrial,
    kStartSweep,
    kStartStream,
    kStop,
    kClearFaults,
  };
  // A submitted command on its way to the tick (the mailbox, requests_), with the
  // submitter's tag its verdict returns with.
  struct Request {
    RequestKind kind = RequestKind::kStop;
    RequestTag tag = 0;
    ControlConfig config;  // kConfigure
    Calibration calibration;
    SineConfig sine;
    RampedSineConfig sweep;
    AngularVelocity stream_rate;
  };

  CommandOutcome Submit(const Request& request);
  // A request that carries nothing but its kind and tag (stop, clear faults).
  CommandOutcome Submit(RequestKind kind, RequestTag tag);
  // Submits a `kind` request carrying `value` in `field` if the board admits it
  // (`admitted`, CheckStart's) and the request's own validation found nothing (`error`);
  // otherwise the first refusal of the two.
  template <class Error, class T>
  CommandOutcome SubmitValid(const CommandOutcome& admitted, Error error,
                             RequestKind kind, RequestTag tag, T Request::*field,
                             const T& value);
  // The checks every start shares: idle, and calibrated unless it is the sweep (idle
  // alone is also what a configuration or a calibration needs). The main loop's (on
  // the last tick's snapshot) and the tick's (on its own state).
  static CommandOutcome CheckStart(bool needs_calibration, BoardState state,
                                   bool calibrated);
  CommandOutcome CheckStart(bool needs_calibration) const;
  void ISR_ApplyRequest();
  CommandOutcome ISR_Apply(const Request& c);
  void ISR_FollowHost();
  void ISR_AfterStep();
  void ISR_Enter(BoardState next);
  void ISR_Done(RequestTag tag, CommandOutcome outcome);

  ControlTick control_;
  TickResult result_;
  BoardState state_ = BoardState::kIdle;
  bool calibrated_ = false;
  SpscQueue<Request, 4> requests_;
  SpscQueue<AppEvent, 64> events_;
  struct WindowFitSums {
    std::uint32_t start_tick = 0;
    bool trial = false;  // a trial's window (windows_of_trial_ when it closed)
    InterfaceFitSums sums;
  };
  // Four windows: the main loop takes each with its kWindow event, and a trial ends at
  // most ten windows a second (5 Hz).
  SpscQueue<WindowFitSums, 4> window_fits_;
  // Fits on their way to the tick's attachment model (SolveWindowFit); the tick takes
  // one a tick, and a full queue drops the newest (the model keeps an older fit).
  SpscQueue<AttachmentParams, 2> attachments_;
  std::atomic<std::int32_t> stream_target_{0};
  std::atomic<std::uint16_t> raised_fault_{0};  // a Fault code, 0 = none
  static_assert(std::atomic<std::uint16_t>::is_always_lock_free);
  // A ClearFaults the tick is judging: answered from ISR_AfterStep.
  bool clear_pending_ = false;
  // The last motion started was a trial, not a calibration sweep: its windows' fits
  // feed the attachment model (SolveWindowFit).
  bool windows_of_trial_ = false;
  RequestTag clear_tag_ = 0;
  TickCount done_;  // ticks run to their end: Latest's consistent copy
  // Configurations the tick has applied; the main loop's copy and the count it was
  // taken at (config()).
  std::atomic<std::uint32_t> config_generation_{0};
  mutable ControlConfig main_config_;
  mutable std::uint32_t main_generation_ = 0;
};

}  // namespace mjc::app
