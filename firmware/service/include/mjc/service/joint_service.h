// The joint board's main loop around its application: what the board decides between
// ticks, whatever carries the requests. It restores the stored calibration at start-up
// and saves each one the tick applied; drains the tick's events, solves each window's
// attachment fit and hands it back to the tick's model; keeps the trial and sweep
// configurations a start runs; supervises the host session that started a motion and
// the setpoint stream; and holds the board for its bootloader at rest.
//
// It takes typed requests (the methods below) and emits typed reports (Report) to one
// ReportSink, in the order they arise: the CAN node (mjc/app/can_node.h) is a sink that
// encodes them as frames, a test can be another. Requests are answered by reports, some
// at once (a refusal), some at a later Poll (the tick's verdict).
//
// Contexts: everything here runs in the main loop, never in the control tick. Nothing
// allocates or blocks.
#pragma once

#include <cstdint>
#include <optional>

#include "mjc/app/board_clock.h"
#include "mjc/app/calibration_store.h"
#include "mjc/app/joint_app.h"
#include "mjc/protocol/calibration_record.h"
#include "mjc/protocol/codec.h"
#include "mjc/protocol/messages.h"
#include "mjc/protocol/params.h"

namespace mjc::service {

using app::BoardState;
using app::CommandOutcome;
using app::CommandOutcomeCode;

// A command: stop, clear faults, or start a trial, a sweep or a stream. A start runs the
// configuration whose digest it names (0 for a stream), under its session (0: none, so
// unsupervised).
struct CommandRequest {
  protocol::CommandCode code = protocol::CommandCode::kStop;
  std::uint8_t sequence = 0;
  protocol::SessionId session = 0;
  protocol::ConfigDigest config = 0;
};

// How the service watches the host: a setpoint stream older than stream_timeout_ms
// stops the motor (Fault::kCommandTimeout); a motion whose session's heartbeats stay
// away host_timeout_ms (0: never) stops (Fault::kHostHeartbeatLost). A stream moves
// its setpoint at most stream_rate.
struct Supervision {
  std::uint16_t stream_timeout_ms = 50;
  std::uint16_t host_timeout_ms = 300;
  AngularVelocity stream_rate = AngularVelocity::FromDouble(2.0);
};

struct Report {
  enum class Kind : std::uint8_t {
    kCommandDone = 1,      // command: a command's answer, refusal or the tick's verdict
    kMotionStarted = 2,    // motion: a start's verdict was kAccepted (after its answer)
    kParamDone = 3,        // param, outcome: a control parameter's write answered
    kCalibrationDone = 4,  // calibration, detail: an upload answered (applied and saved)
    kBootHold = 5,         // boot: a hold answered (kNone: the board leaves)
    kFault = 6,            // fault, tick: the tick latched a fault
    kStateChanged = 7,     // state
    kWindow = 8,           // window, fit: a window ended; its attachment fit
    kWindowStart = 9,      // window_start: the setpoint entered a loading segment
  };
  Kind kind = Kind::kStateChanged;
  protocol::CommandResult command;
  protocol::MotionConfig motion;
  protocol::ParamId param = protocol::ParamId{};
  CommandOutcome outcome;
  protocol::CalibrationResult calibration = protocol::CalibrationResult::kAccepted;
  std::uint8_t detail = 0;
  protocol::BootError boot = protocol::BootError::kNone;
  Fault fault = Fault::kNone;
  std::uint32_t tick = 0;
  BoardState state = BoardState::kIdle;
  WindowSummary window;
  InterfaceFit fit;
  protocol::WindowStart window_start;
};

// Where the reports go (Convention: a public non-virtual call over a private virtual).
class ReportSink {
 public:
  void Take(const Report& report) { DoTake(report); }

 protected:
  ~ReportSink() = default;

 private:
  virtual void DoTake(const Report& report) = 0;
};

struct ServiceCounters {
  std::uint32_t stream_timeouts = 0;
  std::uint32_t host_timeouts = 0;
  std::uint32_t storage_failures = 0;
};

class JointService {
 public:
  // `app` must outlive the service; `store` (may be null: nothing persists) keeps every
  // applied calibration.
  JointService(app::JointApp* app, app::CalibrationStore* store);

  // The sink every report goes to from now on (null: reports are dropped).
  void Attach(ReportSink* sink) { sink_ = sink; }
  void SetSupervision(const Supervision& s) { supervision_ = s; }

  // Start-up, before the tick runs: hands the newest stored calibration to the app (it
  // takes effect at the first tick) and returns it; nullopt leaves the board
  // uncalibrated. unreadable_pages() then names a page the flash could not read.
  std::optional<app::CalibrationStore::Loaded> Boot();
  std::uint8_t unreadable_pages() const;

  // --- requests --------------------------------------------------------------------
  void Submit(const CommandRequest& command);
  // The configurations a later start runs (the latest of each).
  void SetTrialConfig(const protocol::TrialConfig& trial);
  void SetSweepConfig(const protocol::SweepConfig& sweep);
  // A streamed setpoint (rad): the stream's target, and proof the stream is alive.
  void Setpoint(Angle target);
  // A host's heartbeat: keeps alive the motion its session started.
  void HostHeartbeat(protocol::SessionId session);
  // Faults raised from outside the tick: the next tick latches them and stops the motor.
  void EmergencyStop() { app_->RaiseFault(Fault::kEmergencyStop); }
  void BusOff() { app_->RaiseFault(Fault::kCanBusOff); }
  // A host asks the board into its bootloader: accepted only at rest (kBootHold).
  void BootHold();
  // A calibration to apply (idle only) and, once the tick applied it, to save.
  void Upload(const protocol::CalibrationRecord& record);
  // A new control configuration, for the parameter `id` written (kParamDone).
  void Configure(const ControlConfig& control, protocol::ParamId id);

  // --- what requests are judged by ---------------------------------------------------
  // A parameter write or calibration awaits the tick's verdict: the next one waits.
  bool ConfigChangePending() const { return config_change_pending_; }
  // A motion runs or is about to start.
  bool MotionRuns() const;
  const ControlConfig& control() const { return app_->config(); }
  app::JointApp::Snapshot Latest() const { return app_->Latest(); }

  // Once per control tick (after it): the clock, the tick's events as reports (with
  // each window's fit, handed to the tick's attachment model), window starts, and the
  // stream and host timeouts.
  void Poll();

  // The last Poll's tick and the board's clock.
  const app::JointApp::Snapshot& last() const { return last_; }
  const app::BoardClock& clock() const { return clock_; }
  std::uint32_t tick_hz() const { return app_->config().tick_hz; }
  // A hold was accepted and nothing waits to be applied and saved: the board may enter
  // its bootloader once the answers are out.
  bool EnterBootloaderNow() const { return leaving_ && !config_change_pending_; }
  bool leaving() const { return leaving_; }
  std::uint32_t dropped_events() const { return app_->dropped_events(); }
  const ServiceCounters& counters() const { return counters_; }

 private:
  // What a request handed to the app came from, for answering its verdict.
  enum class Origin : std::uint8_t { kCommand = 1, kParam = 2, kCalibration = 3 };

  // Request tags: the origin in bits 24-31; a command's code and sequence, or a
  // parameter's id, below; a command's session in bits 32-47 (its answer names it).
  static app::RequestTag Tag(Origin origin, std::uint32_t low) {
    return (app::RequestTag{static_cast<std::uint8_t>(origin)} << 24) | low;
  }
  static Origin OriginOf(app::RequestTag tag) {
    return static_cast<Origin>((tag >> 24) & 0xFFu);
  }
  static protocol::SessionId SessionOf(app::RequestTag tag) {
    return static_cast<protocol::SessionId>((tag >> 32) & 0xFFFFu);
  }

  void Emit(const Report& r) {
    if (sink_ != nullptr) sink_->Take(r);
  }
  // Answers a request the app refused at once, or (OnVerdict) the tick's verdict.
  void Answer(app::RequestTag tag, const CommandOutcome& outcome);
  void AnswerCalibration(const CommandOutcome& outcome);
  void OnVerdict(const app::AppEvent& e);
  void OnEvent(const app::AppEvent& e);
  void AnnounceWindow();
  void Supervise();

  app::JointApp* app_;
  app::CalibrationStore* store_;
  ReportSink* sink_ = nullptr;
  Supervision supervision_;
  ServiceCounters counters_;
  app::BoardClock clock_;
  app::JointApp::Snapshot last_;
  protocol::TrialConfig trial_;
  protocol::SweepConfig sweep_;
  bool have_trial_ = false;
  bool have_sweep_ = false;
  // A parameter write or calibration the tick has not yet answered.
  bool config_change_pending_ = false;
  // The calibration awaiting the tick's verdict; saved to the store once applied.
  protocol::CalibrationRecord pending_record_;
  // The setpoint's segment at the last poll: a change into a loading segment is a
  // window's start (AnnounceWindow).
  Segment last_segment_ = Segment::kIdle;
  // Streaming: the tick of the last setpoint (or of the stream's start).
  std::uint32_t last_setpoint_tick_ = 0;
  // Host supervision. A start command awaiting the tick's verdict, and its session;
  // the session the running motion belongs to (0: unsupervised, or none running) and
  // the tick of its last heartbeat (or of the motion's start).
  bool start_pending_ = false;
  protocol::SessionId start_session_ = 0;
  protocol::SessionId motion_session_ = 0;
  // What the pending start and the motion last started run: their start code and the
  // digest of their configuration (MotionConfig, WindowStart). motion_code_ is 0 while
  // no motion runs (a refused start names the one that holds the board).
  protocol::CommandCode start_code_ = protocol::CommandCode::kStop;
  protocol::ConfigDigest start_config_ = 0;
  std::uint8_t motion_code_ = 0;
  protocol::ConfigDigest motion_config_ = 0;
  std::uint32_t last_host_tick_ = 0;
  // A BootHold was accepted: the board is on its way into the bootloader.
  bool leaving_ = false;
};

}  // namespace mjc::service
