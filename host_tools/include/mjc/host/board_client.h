#pragma once

// One joint board seen from the host over a CanLink: commands with their answers,
// trial configuration, and what the board reports (heartbeat, telemetry, window
// summaries reassembled from their seven frames, faults), and the host's heartbeat that
// lets the board stop a motion when this host goes away. Used by mjc trial, calibrate,
// cal and monitor.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "mjc/host/can_link.h"
#include "mjc/protocol/codec.h"

namespace mjc::host {

// A window summary as the host reassembles it, in physical units.
struct BoardWindow {
  Motion motion = Motion::kFlexion;
  std::uint16_t repetition = 0;
  bool eta_valid =
      false;  // false: the board could not form η (eta_percent means nothing)
  double eta_percent = 0;
  double loading_J = 0, unloading_J = 0, positive_J = 0, negative_J = 0;
  double peak_power_W = 0, peak_torque_Nm = 0;
  std::uint32_t start_tick = 0, peak_tick = 0, end_tick = 0;
  // The attachment's least-squares fit τ = k·θ_j + b·θ̇_j + τ_0 over the window
  // (WindowFit, WindowFitResidual); the values mean nothing unless fit_valid.
  bool fit_valid = false;
  int fit_status = 0;  // InterfaceFitStatus
  double stiffness_Nm_rad = 0, damping_Nms_rad = 0, offset_Nm = 0, residual_rms_Nm = 0;
  double net_J() const { return loading_J + unloading_J; }
};

struct BoardStatus {
  bool heard = false;
  protocol::BoardState state = protocol::BoardState::kIdle;
  bool calibrated = false;
  Fault fault = Fault::kNone;
  std::uint32_t tick = 0;
  double motor_rad = 0, joint_rad = 0, torque_Nm = 0, power_W = 0, energy_J = 0;
};

// One angle sample (a TelemetryAngles frame, or one of a TelemetryAngleBatch's): θ_m
// and θ_j in rad.
struct AngleSample {
  double motor_rad = 0;
  double joint_rad = 0;
};

// The continuity of one board's batched angle telemetry (TelemetryAngleBatch, CAN FD):
// each batch's first_sample must be the previous batch's plus kSamples. A gap is
// counted as lost samples and lost frames and never filled in; a count that goes back
// (the board restarted and counts from 0 again) starts over, counted as a restart.
// Classical TelemetryAngles frames carry no count: a lost one is not seen.
class AngleSequence {
 public:
  // Takes the next batch heard from the board.
  void OnBatch(const protocol::TelemetryAngleBatch& batch);
  std::uint64_t batches() const { return batches_; }
  std::uint64_t lost_samples() const { return lost_samples_; }
  std::uint64_t lost_frames() const { return lost_frames_; }
  std::uint64_t restarts() const { return restarts_; }

 private:
  bool started_ = false;
  std::uint32_t next_ = 0;  // the first_sample the next batch should carry
  std::uint64_t batches_ = 0, lost_samples_ = 0, lost_frames_ = 0, restarts_ = 0;
};

// The host's heartbeat period. A board that has heard one stops a running motion
// (kHostHeartbeatLost) when none arrives for its host_timeout_ms, 300 ms by default:
// two heartbeats may be lost.
inline constexpr std::chrono::milliseconds kHostHeartbeatPeriod{100};

// How long a wait for a board may last, measured by the board rather than by this
// machine's clock. A real board keeps real time, so for a lab both bounds are wall
// time; a simulated board on a loaded machine may run slower than real time, and is
// then waited for as long as it keeps talking and has not used up its own time.
// The wall-clock silence after which the tools take a node as gone: 10 s, or
// MJC_SILENCE_S (1..3600 s) when set. A real board keeps real time and sends a heartbeat
// every 100 ms; a simulated board in a deliberately slowed, loaded test VM runs at a
// tenth of real time or less, and scripts/kernel-vm sets MJC_SILENCE_S in proportion to
// its slowdown there. A value outside the range is ignored (10 s).
std::chrono::milliseconds DefaultSilence();

// The wall-clock silence for an exchange a board answers within TIMEOUT of its own time
// (a command, a parameter, the start of a motion): TIMEOUT itself, since a real board
// that says nothing for that long is gone; no shorter than MJC_SILENCE_S when that is
// set, for a simulated board starved of CPU in a test VM.
std::chrono::milliseconds ExchangeSilence(std::chrono::milliseconds timeout);

struct Patience {
  // Board time the wait may take, read off its heartbeat's tick counter (counted from
  // the first heartbeat the wait sees); 0 = no bound beyond silence.
  std::chrono::milliseconds board{0};
  // Wall time without a single frame from the node, after which it is taken as gone.
  // A real board sends at least its heartbeat every 100 ms; a simulated one starved of
  // CPU (a slow machine, a frame flood in a slowed virtual machine) was seen silent for
  // seconds.
  std::chrono::milliseconds silence = DefaultSilence();
};

// What the tools allow a board for answering a start command: like Patience, its own
// time while it talks, and silence. A real board answers within a millisecond.
inline constexpr int kStartAnswerMs = 10000;

// A board that talks but sends no heartbeat for this long is taken as silent: the
// tools read its state and its clock from the heartbeat.
inline constexpr std::chrono::milliseconds kHeartbeatSilence{10000};

// How often a board sends its BoardInfo, in its own time (TelemetryRates::info_hz). A
// second board answering with the same node id has sent one within this much of its
// time, so a node heard for longer has shown every board behind it.
inline constexpr std::chrono::milliseconds kBoardInfoPeriod{
    1000 / protocol::TelemetryRates{}.info_hz};

// Why a bounded wait ended without what it waited for.
enum class WaitEnd : std::uint8_t {
  kSilent = 1,       // no frame from the node for Patience::silence
  kBoardTime = 2,    // the board's clock advanced Patience::board
  kLinkFailed = 3,   // this side could not send or receive
  kInterrupted = 4,  // the interrupt flag (BoardClient::SetInterrupt) was raised
  kAmbiguous = 5,    // two boards answer with this node id (BoardClient::ambiguous)
  kWrongMotion = 6,  // the board runs another motion than the one this client started
                     // (BoardClient::Start; motion_mismatch says which)
};

// Follows a motion a board was told to start (a trial or a stream: kRunning; a
// calibration sweep: kCalibrating) through the states it reports, until it is over:
// idle again once the motion's state was seen, or faulted. An idle board before that is
// the board before the start took effect. The tools' waits over the bus and the
// simulator's loops on the application share it.
class MotionEnd {
 public:
  explicit constexpr MotionEnd(protocol::BoardState motion) : motion_(motion) {}
  // The state the board reports now: true once the motion is over.
  constexpr bool Over(protocol::BoardState state) {
    if (state == motion_) started_ = true;
    return state == protocol::BoardState::kFault ||
           (started_ && state == protocol::BoardState::kIdle);
  }
  // The motion's state was seen.
  constexpr bool started() const { return started_; }

 private:
  protocol::BoardState motion_;
  bool started_ = false;
};

enum class HostHeartbeats : std::uint8_t {
  kOff = 0,   // the board is not supervised by this client
  kSend = 1,  // a HostHeartbeat every kHostHeartbeatPeriod while the client polls
};

// Who answers with one node id, from its BoardInfo frames and heartbeat clock: one
// board, or two or more (ambiguous). Two boards show as BoardInfo frames of two
// instances while neither restarted, an instance heard again after another, or the
// heartbeat's tick running backwards twice with no BoardInfo (a restart) between. A
// restart into a new instance (a simulated board draws one at every start) is one
// board: its clock starts anew right after its BoardInfo.
class BoardIdentity {
 public:
  void OnInfo(const protocol::BoardInfo& info);
  void OnHeartbeat(std::uint32_t tick);

  // A sign of a second board on the node id, from one frame on: a motion stops at the
  // first one.
  bool ambiguous() const { return ambiguous_; }
  // Two boards proven by repeated evidence: two instances each heard in at least two
  // BoardInfo frames, or the node's clock stepping back twice without a restart. One
  // frame, which a corrupted or stray frame on a flooded bus can also make, is not.
  bool proven() const;
  // "node 3 is answered by two boards (instances 3f2a and 9b01): give each its own node
  // id" once proven(); while only ambiguous(), what was seen and that it may be a stray
  // frame; empty while neither.
  std::string Message(int node) const;
  // The BoardInfo last heard (nullopt before one arrives).
  const std::optional<protocol::BoardInfo>& info() const { return info_; }
  // Every instance heard, in the order heard.
  const std::vector<std::uint16_t>& instances() const { return instances_; }
  std::uint64_t heartbeats() const { return heartbeats_; }
  // BoardInfo frames heard, of every instance, since the first sign of a second board.
  // Five without proof: a sign only (a second board would have sent two meanwhile).
  std::size_t infos_since_sign() const { return infos_ - infos_at_sign_; }
  // The tick of the last heartbeat.
  std::uint32_t tick() const { return tick_; }
  // How far the node's clock has run while heard, in ticks: the sum of the steps
  // between consecutive heartbeats that go forwards by at most two seconds. Two boards'
  // interleaved clocks jump back and forth by more, and add nothing: a wait for the
  // node's time cannot end on such a jump before the two boards are told apart.
  std::uint64_t elapsed_ticks() const { return elapsed_; }

 private:
  void Sign(std::uint16_t instance);

  std::optional<protocol::BoardInfo> info_;
  // The instance taken as this node's, those that restarted into another, and an
  // instance not yet judged: a restart when the next heartbeat starts its clock anew.
  std::optional<std::uint16_t> current_;
  std::optional<std::uint16_t> new_;
  std::vector<std::uint16_t> instances_;
  std::vector<int> infos_heard_;  // BoardInfo frames of each of instances_
  std::size_t infos_ = 0, infos_at_sign_ = 0;
  // The first sign of a second board: the instance heard, amid the current one's.
  std::optional<std::pair<std::uint16_t, std::uint16_t>> sign_;
  std::vector<std::uint16_t> retired_;
  bool info_since_heartbeat_ = false;
  int clock_reversals_ = 0;
  bool ambiguous_ = false;
  std::uint64_t heartbeats_ = 0;
  std::uint32_t tick_ = 0;
  std::uint64_t elapsed_ = 0;
};

class BoardClient {
 public:
  using Clock = std::function<std::chrono::steady_clock::time_point()>;

  // `link` must outlive the client; it is filtered to this node's frames. With
  // HostHeartbeats::kSend every wait of the client (Poll, Command, ReadParam) sends
  // the heartbeat on time, however long it is; between calls nothing is sent, so a
  // caller that stops polling (a prompt, a long computation) must leave the board at
  // rest first. Off by default: a board simulated faster than real time would count a
  // wall-clock cadence as lost heartbeats. `now` is the clock of every deadline and of
  // the cadence (tests give a simulated one).
  BoardClient(CanLink* link, std::uint8_t node,
              HostHeartbeats heartbeats = HostHeartbeats::kOff,
              Clock now = &std::chrono::steady_clock::now);

  // Sends a command and waits for its CommandResult: nullopt when it cannot be sent, or
  // the board does not answer within timeout_ms (then *why says which). The timeout is
  // board time while the board talks, and wall-clock silence otherwise (Patience).
  // The answer is the one to this command: its code, sequence and this client's
  // session (another tool's answers are not taken). `config`: a start's ConfigDigest.
  std::optional<protocol::CommandOutcomeCode> Command(protocol::CommandCode code,
                                                      int timeout_ms, std::string* why,
                                                      protocol::ConfigDigest config = 0);
  // The last answer Command took (its owner and detail say who holds a busy board).
  const std::optional<protocol::CommandResult>& answer() const { return answer_; }
  // Why the board refused the last command, in words: "node 1 is in use by session
  // 3a1f, started by its trial (…)", "node 1 holds another configuration than …".
  std::string RefusalMessage(protocol::CommandOutcomeCode outcome) const;

  // Starts a trial or a calibration sweep bound to this session: sends `config`, then
  // the start naming it (ConfigDigestOf), and waits for the board's MotionConfig. From
  // the start on, the motion's frames are checked against it: a MotionConfig or a
  // WindowStart naming another configuration or session, or a window before the
  // board said what it runs, is a mismatch (motion_mismatch), after which no window
  // and no angle sample is taken and every wait ends (WaitEnd::kWrongMotion). Returns
  // kAccepted once the board runs exactly `config`; a refusal's outcome (a
  // configuration from another sender that came between the two frames is retried
  // twice); nullopt when unanswered, or accepted but running something else (then
  // motion_mismatch() is true and the caller must stop it).
  std::optional<protocol::CommandOutcomeCode> Start(const protocol::TrialConfig& config,
                                                    int timeout_ms, std::string* why);
  std::optional<protocol::CommandOutcomeCode> Start(const protocol::SweepConfig& config,
                                                    int timeout_ms, std::string* why);
  // Ends the binding of the last Start (the motion is over): later motions' frames are
  // taken as before.
  void ReleaseMotion();
  // The bound motion's frames named another configuration or session; the message
  // names both ("node 1 runs configuration 5c1d0e2a (40.0° × 5 …, another sender's),
  // not this session's 0b7e… (6.0° × 3 …)").
  bool motion_mismatch() const { return !mismatch_.empty(); }
  const std::string& mismatch() const { return mismatch_; }
  // Windows dropped because they belonged to no motion this client could vouch for.
  std::uint64_t unbound_windows() const { return unbound_windows_; }

  // Sends one host message (TrialConfig, SweepConfig, …) to this node; false with the
  // reason when the link cannot send it.
  template <class M>
  bool Send(const M& message, std::string* why) {
    if (link_->Send(protocol::Encode(message, node_), why)) return true;
    link_failed_ = true;
    return false;
  }

  // Reads a parameter: nullopt when the board does not answer (timeout_ms as for
  // Command), or answers with a status other than kOk (then *why says which).
  std::optional<std::int32_t> ReadParam(protocol::ParamId id, int timeout_ms,
                                        std::string* why);

  // Writes a parameter's raw value and waits for the board's answer (timeout_ms as for
  // Command; a control parameter is answered once the tick has applied or refused it):
  // its status, and the value it holds now. nullopt when it cannot be sent or is not
  // answered (then *why says which).
  std::optional<protocol::ParamValue> WriteParam(protocol::ParamId id, std::int32_t raw,
                                                 int timeout_ms, std::string* why);

  // Handles what arrives within timeout_ms: returns once something has, or at the
  // timeout, sending heartbeats meanwhile when they are on. False only when the link
  // failed (then *why says how); a quiet bus is not a failure.
  bool Poll(int timeout_ms, std::string* why);

  // The wait loop every caller shares: Poll until `done()` holds (true), or until the
  // patience runs out, the link fails, the interrupt flag is raised or the node shows a
  // sign of a second board (false, with *end and *why saying which). `done` may take
  // what arrived (windows, samples). Without `stop_at_a_sign` only proof of a second
  // board ends it (Identify judges a sign before anything is done).
  bool Await(const std::function<bool()>& done, const Patience& patience, WaitEnd* end,
             std::string* why, bool stop_at_a_sign = true);

  // Follows the motion this client just started (MotionEnd) with Await: true once it
  // is over — status() then says idle or faulted. `each` (may be empty) is called on
  // every pass first, to take what arrived (windows, samples) and show progress.
  bool AwaitMotionEnd(protocol::BoardState motion, const std::function<void()>& each,
                      const Patience& patience, WaitEnd* end, std::string* why);

  // Listens until the node has shown who it is: its clock has advanced a BoardInfo
  // period and a tenth (kBoardInfoPeriod; every board answering with this node id has
  // then sent its BoardInfo) — 110 ms of a real board's time. False when it stays
  // silent, or is two boards (kAmbiguous), with *end and *why saying which. A board
  // that sends no BoardInfo (an older image) is identified all the same, with info()
  // empty. A sign of a second board is judged first: five more BoardInfo frames, or
  // both instances heard twice (proof). `silence` as Patience::silence. The tools call
  // it before they act on a node.
  bool Identify(WaitEnd* end, std::string* why,
                std::chrono::milliseconds silence = Patience{}.silence);

  // Two or more physical boards answer with this node id (BoardIdentity). Their frames
  // are then indistinguishable, and every wait ends (kAmbiguous).
  bool ambiguous() const { return identity_.ambiguous(); }
  bool proven_ambiguous() const { return identity_.proven(); }
  std::string AmbiguityMessage() const { return identity_.Message(node_); }
  // The BoardInfo last heard from the node (nullopt before one arrives).
  const std::optional<protocol::BoardInfo>& info() const { return identity_.info(); }
  // Every instance (BoardInfo::instance) heard from this node, in the order heard.
  const std::vector<std::uint16_t>& instances() const { return identity_.instances(); }

  // Makes every wait return (WaitEnd::kInterrupted) once *flag is true: a signal
  // handler's flag, so a tool can stop what it started.
  void SetInterrupt(const std::atomic<bool>* flag) { interrupt_ = flag; }
  bool interrupted() const { return interrupt_ != nullptr && interrupt_->load(); }

  // Windows completed since the last call.
  std::vector<BoardWindow> TakeWindows();

  // Keeps every angle sample (TelemetryAngles, or each of a TelemetryAngleBatch's) from
  // now on (off by default, so a long-running client does not grow), until
  // KeepAngles(false).
  void KeepAngles(bool on) { keep_angles_ = on; }
  // The samples kept since the last call, in arrival order.
  std::vector<AngleSample> TakeAngles();

  std::uint8_t node() const { return node_; }
  // This client's session: non-zero when it sends heartbeats (the motions it starts are
  // then supervised by them alone), 0 otherwise.
  protocol::SessionId session() const { return session_; }
  // True once a send or receive failed on this side (the link is unusable): what tells
  // a failed Command or ReadParam from a board that did not answer.
  bool link_failed() const { return link_failed_; }
  const BoardStatus& status() const { return status_; }
  // Frames this node sent (not a host's frames to it) so far, and of those the
  // heartbeats: what a wait watches for signs of life and for the board's own clock.
  std::uint64_t frames() const { return frames_; }
  std::uint64_t heartbeats() const { return heartbeats_heard_; }
  // The batched angle telemetry's continuity (CAN FD): frames lost on the way, seen as
  // gaps in the batches' sample count.
  const AngleSequence& angle_sequence() const { return angle_sequence_; }
  // Frames of this node the codec refused.
  std::uint64_t malformed() const { return malformed_; }
  // Windows dropped because a part was lost, malformed or out of order (each counted
  // once); never half-assembled into TakeWindows.
  std::uint64_t incomplete_windows() const { return incomplete_windows_; }

  // Bus-off reports the link received since this client was made: CAN error frames
  // saying the controller went bus-off. Frames are lost until it recovers, and a board
  // whose own controller went bus-off stops its motion (kCanBusOff).
  std::uint64_t bus_off() const { return bus_off_seen_ - bus_off_at_start_; }
  // Called by the waits as soon as a WindowStart from the node arrives (the board
  // began a window; mjc trial --sync-line marks it on a GPIO line).
  void OnWindowStart(std::function<void(const protocol::WindowStart&)> handler) {
    on_window_start_ = std::move(handler);
  }

  // Called by the waits (Poll, Command, ReadParam) as soon as they see a new bus-off
  // report, with bus_off() so far: what lets a tool say so at once.
  void OnBusOff(std::function<void(std::uint64_t total)> handler) {
    on_bus_off_ = std::move(handler);
  }

 private:
  void Handle(const protocol::CanFrame& frame);
  // A window's frames in the board's order: header 0, energy 1, work 2, peaks 3,
  // ticks 4, fit 5, residual 6 (the last, which completes it).
  static constexpr int kLastWindowPart = 6;
  bool AcceptWindowPart(int part);
  // Sends the heartbeat when it is due; false when the link failed.
  bool Beat(std::string* why);
  // Calls the bus-off handler when the link counted new bus-off reports.
  void NoteBusOff();
  // Sends `request` (a ParamRead or ParamWrite of `id`) and waits for the ParamValue of
  // `id`; `what` names the request in the timeout's message ("a parameter read").
  template <class Config>
  std::optional<protocol::CommandOutcomeCode> StartBound(protocol::CommandCode code,
                                                         const Config& config,
                                                         int timeout_ms,
                                                         std::string* why);
  // Why a wait ended in silence, from what the node said before it: nothing ("node 1
  // is silent …"), a motion and then nothing, or frames without a heartbeat (its
  // bootloader's BootStatus and why it stays, or heartbeats switched off).
  std::string SilenceMessage() const;
  std::string NoHeartbeatMessage() const;
  // A frame of the bound motion named something else: `what` says what.
  void Mismatch(const std::string& what);
  // What a ConfigDigest names: ours, or a configuration frame seen on the bus.
  std::string NameConfig(protocol::ConfigDigest digest) const;
  // Whether a window or sample of the bound motion may be taken now.
  bool MotionTrusted() const { return !bound_ || (confirmed_ && mismatch_.empty()); }
  template <class Request>
  std::optional<protocol::ParamValue> AskParam(const Request& request,
                                               protocol::ParamId id, int timeout_ms,
                                               const char* what, std::string* why);

  CanLink* link_;
  std::uint8_t node_;
  HostHeartbeats heartbeats_;
  Clock now_;
  // When the next heartbeat is due (the epoch: at the first poll) and its sequence.
  std::chrono::steady_clock::time_point next_heartbeat_{};
  std::uint8_t heartbeat_sequence_ = 0;
  protocol::SessionId session_ = 0;
  std::uint8_t sequence_ = 0;
  BoardStatus status_;
  BoardWindow partial_;
  // The window part last seen, in the order the board sends them (0 header, 1 energy,
  // 2 work, 3 peaks, 4 ticks); -1 between windows. broken_: the window in progress
  // lost a part and is already counted in incomplete_windows_.
  int last_part_ = -1;
  bool broken_ = false;
  std::vector<BoardWindow> windows_;
  bool keep_angles_ = false;
  std::vector<AngleSample> angles_;
  AngleSequence angle_sequence_;
  std::optional<protocol::CommandResult> last_result_;
  std::optional<protocol::CommandResult> answer_;
  // The bootloader's last BootStatus, until the application's heartbeat is heard.
  std::optional<protocol::BootStatus> boot_status_;
  // The motion this client started (Start) and whether the board confirmed it runs it.
  bool bound_ = false;
  bool confirmed_ = false;
  protocol::CommandCode bound_code_ = protocol::CommandCode::kStartTrial;
  protocol::ConfigDigest bound_config_ = 0;
  std::string bound_name_;
  std::string mismatch_;
  std::uint64_t unbound_windows_ = 0;
  // Configuration frames other senders sent this node (the newest 8): what names a
  // digest that is not ours.
  std::vector<std::pair<protocol::ConfigDigest, std::string>> configs_seen_;
  std::optional<protocol::ParamValue> last_param_;
  std::uint64_t frames_ = 0;
  std::uint64_t heartbeats_heard_ = 0;
  const std::atomic<bool>* interrupt_ = nullptr;
  std::uint64_t malformed_ = 0;
  std::uint64_t incomplete_windows_ = 0;
  bool link_failed_ = false;
  std::uint64_t bus_off_at_start_ = 0;
  std::uint64_t bus_off_seen_ = 0;
  std::function<void(std::uint64_t)> on_bus_off_;
  std::function<void(const protocol::WindowStart&)> on_window_start_;
  BoardIdentity identity_;
};

}  // namespace mjc::host
