#include "safe_stop_rig.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <deque>
#include <functional>
#include <memory>
#include <numbers>
#include <optional>
#include <utility>
#include <vector>

#include "mjc/app/joint_board.h"
#include "mjc/plant/params.h"
#include "mjc/protocol/codec.h"
#include "mjc/sim/scenarios.h"

namespace mjc::safe_stop {
namespace {

using protocol::CanFrame;
using protocol::CommandCode;
using protocol::CommandOutcomeCode;

constexpr std::uint8_t kNode = 1;
// The rig's host session: its motions are supervised by its heartbeats.
constexpr protocol::SessionId kSession = 0x5EED;

// The trial: the paper's 25° at 0.5 Hz, 200 ms of rest first. On subject1 it swings
// the motor pulley ±0.435 rad, the joint ±0.053 rad, the SEA torque ±0.23 N·m and the
// joint velocity ±0.167 rad/s (plant truth).
constexpr double kAmplitudeRad = 25.0 * std::numbers::pi / 180.0;
constexpr std::uint8_t kRest100ms = 2;
constexpr std::uint32_t kRestTicks = 2000;  // kRest100ms at 10 kHz

// Lowered limits, each well inside what that trial reaches on the way to its first
// flexion peak, so the crossing is a physical one mid-motion.
constexpr double kJointMaxRad = 0.03;
constexpr double kMotorMaxRad = 0.3;
// The torque limit's cause is the subject resisting the flexion: the strap preload
// ramps from subject1's 0.012 N·m to 1 N·m (the model's largest) over 100 ms from the
// start of the flexion. With the limit at 0.15 N·m the load keeps the spring beyond it
// after the stop (the unpowered cable holds up to its 0.3 N·m sheath friction), until
// the subject relaxes.
constexpr double kTorqueMaxNm = 0.15;
constexpr double kPushPreloadNm = 1.0;
constexpr std::uint32_t kPushRampTicks = 1000;

// Where the injected faults strike, in ticks after the motion started: mid-flexion
// (the motor pulley near 0.19 rad, moving at 1.2 rad/s), and for the stuck joint the
// first flexion peak, so that the whole way down to the extension peak (0.87 rad of
// motor travel, beyond stuck_motor_travel) is evidence.
constexpr std::uint32_t kMidFlexionTicks = kRestTicks + 1500;
constexpr std::uint32_t kFlexionPeakTicks = kRestTicks + 5000;
// The command-timeout case streams a 25° 0.5 Hz sine for a second before going quiet.
constexpr std::uint32_t kStreamTicks = 10000;

// A bus-off recovery is 128 × 11 recessive bits: 1.41 ms at 1 Mbit/s.
constexpr std::uint32_t kBusOffRecoveryTicks = 15;

// After the stop: how long the operator takes to bring the pulley back to 0 by hand,
// holds it there, and lets everything settle before clearing (longer than any window
// of the velocity estimator, so no motion before the return is still in its window).
constexpr std::uint32_t kHandReturnTicks = 5000;
constexpr std::uint32_t kHandHoldTicks = 1000;
constexpr std::uint32_t kSettleTicks = 3000;

// The velocity case's persisting cause: after the stop the operator's hand drives the
// unpowered pulley on, in the direction of the motion, at this speed (motor-pulley
// rad/s). Through subject1's hand the joint follows at a fraction of it: its mean speed
// over the span is 0.28 rad/s (plant truth) when the clear is judged, nearly three
// times the lowered limit and far outside the mean's noise (σ ≈ 0.008 rad/s: 0.7
// counts of joint noise on each of two readings 50 ms apart).
constexpr double kHandSpeedRadS = 3.0;

// Longest wait for a stop after the cause: the stuck motor needs 200 ms of evidence
// and the stuck joint up to half a cycle (1 s); the host timeout 300 ms.
constexpr std::uint32_t kMaxStopTicks = 20000;

bool IsLimit(FaultCase c) {
  return c == FaultCase::kJointAngleLimit || c == FaultCase::kMotorAngleLimit ||
         c == FaultCase::kTorqueLimit || c == FaultCase::kVelocityLimit;
}
bool IsStuck(FaultCase c) {
  return c == FaultCase::kJointStuck || c == FaultCase::kMotorStuck;
}
// Cases whose cause lasts until removed, so a ClearFaults can be tried against it.
bool CausePersists(FaultCase c) {
  return c == FaultCase::kJointParity || c == FaultCase::kJointErrorFlag ||
         c == FaultCase::kTickOverrun || IsLimit(c);
}

// What the raw sample words say, in double precision and without the firmware's code:
// the joint frame's parity, EF and angle, the motor count extended and converted, the
// play operator of eq. 4 with the board's calibration and the SEA torque of eq. 5, and
// the supervisor's stuck rules applied to the raw counts.
class SampleReference {
 public:
  explicit SampleReference(const ControlConfig& config) : config_(config) {}

  void set_config(const ControlConfig& config) { config_ = config; }
  // The firmware restarts its signal chain when a config or calibration is applied;
  // the reference starts again on the same tick's sample.
  void Restart() { seeded_ = false; }

  // One tick's sample, the duty written over the tick before it and the position
  // loop's error behind that duty (the setpoint the board commanded then, less the
  // motor angle computed here then).
  void Update(const Sample& s, double applied_duty, double applied_error) {
    parity_ok_ = std::popcount(s.joint_frame) % 2 == 0;
    error_flag_ = (s.joint_frame & 0x4000u) != 0;
    overrun_ = s.tick_overrun;
    const bool good = parity_ok_ && !error_flag_;
    const double previous_joint = joint_;
    if (good) {
      joint_count_ = static_cast<std::uint16_t>(s.joint_frame & 0x3FFFu);
      int c = (joint_count_ - config_.joint_encoder.zero_offset) & 0x3FFF;
      if (c >= 8192) c -= 16384;
      joint_ = c * 2.0 * std::numbers::pi / 16384.0;
    }
    const MotorEncoderConfig& m = config_.motor_encoder;
    if (!seeded_) {
      // At power-on and after every restart here the pulley rests at 0, where the
      // signed reading of the timer is the motor's count.
      motor_count_ = static_cast<std::int16_t>(s.motor_count);
    } else {
      motor_count_ += static_cast<std::int16_t>(s.motor_count - last_raw_motor_);
    }
    last_raw_motor_ = s.motor_count;
    motor_ = static_cast<double>(motor_count_) * 2.0 * std::numbers::pi *
             m.gear_denominator /
             (static_cast<double>(m.counts_per_rev) * m.gear_numerator);
    const BacklashConfig& b = config_.backlash;
    const double lower = b.alpha.ToDouble() * (motor_ - b.c_right.ToDouble());
    const double upper = b.alpha.ToDouble() * (motor_ - b.c_left.ToDouble());
    cable_ = std::clamp(seeded_ ? cable_ : joint_, lower, upper);
    torque_ = config_.sea_stiffness.ToDouble() * (cable_ - joint_);

    // The joint's mean speed over the velocity span, (N − 1)/2 ticks (supervisor.h):
    // this θ_j less the one a span before, from a history that starts full of the
    // first reading.
    const std::size_t span = (std::size_t{config_.velocity_window} - 1) / 2;
    if (!seeded_) {
      history_.assign(span, joint_);
      next_ = 0;
    }
    velocity_ = (joint_ - history_[next_]) * config_.tick_hz / static_cast<double>(span);
    history_[next_] = joint_;
    next_ = (next_ + 1) % span;

    // The supervisor's history rules (supervisor.cc), on these numbers: history
    // starts with the first sample after a restart.
    const SupervisorConfig& v = config_.supervisor;
    const bool frozen = seeded_ && motor_count_ == last_motor_count_;
    const bool driven = std::fabs(applied_duty) >= v.stuck_duty.ToDouble() &&
                        std::fabs(applied_error) > v.stuck_hold_error.ToDouble();
    motor_frozen_ticks_ = frozen && driven ? motor_frozen_ticks_ + 1 : 0;
    motor_stuck_ = seeded_ && motor_frozen_ticks_ >= v.motor_stuck_ticks;
    joint_jump_ =
        seeded_ && std::fabs(joint_ - previous_joint) > v.joint_jump_max.ToDouble();
    joint_stuck_ =
        seeded_ && joint_count_ == last_joint_count_ &&
        std::fabs(motor_ - motor_at_joint_change_) > v.stuck_motor_travel.ToDouble();
    if (!seeded_ || joint_count_ != last_joint_count_) motor_at_joint_change_ = motor_;
    last_joint_count_ = joint_count_;
    last_motor_count_ = motor_count_;
    seeded_ = true;
  }

  bool parity_ok() const { return parity_ok_; }
  bool error_flag() const { return error_flag_; }
  bool overrun() const { return overrun_; }
  double joint() const { return joint_; }        // last good θ_j, rad
  double motor() const { return motor_; }        // θ_m, motor-pulley rad
  double torque() const { return torque_; }      // τ, N·m
  double velocity() const { return velocity_; }  // mean over the span, rad/s
  bool joint_jump() const { return joint_jump_; }
  bool joint_stuck() const { return joint_stuck_; }
  bool motor_stuck() const { return motor_stuck_; }

  // Whether this sample fails a check a clear is judged on (those without history:
  // the frame, the overrun flag, the limits of the config).
  bool ClearBlocked() const {
    const SupervisorConfig& v = config_.supervisor;
    return !parity_ok_ || error_flag_ || overrun_ || joint_ < v.joint_min.ToDouble() ||
           joint_ > v.joint_max.ToDouble() || motor_ < v.motor_min.ToDouble() ||
           motor_ > v.motor_max.ToDouble() ||
           std::fabs(torque_) > v.torque_max.ToDouble() ||
           std::fabs(velocity_) > v.velocity_max.ToDouble();
  }

 private:
  ControlConfig config_;
  bool seeded_ = false;
  bool parity_ok_ = true, error_flag_ = false, overrun_ = false;
  std::uint16_t joint_count_ = 0, last_joint_count_ = 0, last_raw_motor_ = 0;
  std::int64_t motor_count_ = 0, last_motor_count_ = 0;
  double joint_ = 0, motor_ = 0, cable_ = 0, torque_ = 0, motor_at_joint_change_ = 0;
  std::vector<double> history_;  // θ_j of the span's last ticks
  std::size_t next_ = 0;         // the oldest
  double velocity_ = 0;
  std::uint32_t motor_frozen_ticks_ = 0;
  bool joint_jump_ = false, joint_stuck_ = false, motor_stuck_ = false;
};

ControlConfig CaseConfig(FaultCase c) {
  ControlConfig config = app::DefaultJointConfig();
  SupervisorConfig& s = config.supervisor;
  if (c == FaultCase::kJointAngleLimit) s.joint_max = Angle::Quantize(kJointMaxRad);
  if (c == FaultCase::kMotorAngleLimit) s.motor_max = Angle::Quantize(kMotorMaxRad);
  if (c == FaultCase::kVelocityLimit) {
    s.velocity_max = AngularVelocity::Quantize(kVelocityMaxRadS);
  }
  return config;  // the torque limit is lowered over the bus (Rig::PowerOn)
}

// The rig's bus, as the board's CAN port sees it: the host side's frames wait in the
// inbox for the board's main loop; the board's frames reach the host side at once, or,
// while the bus is down, wait in the board's queue; a bus-off report waits for the main
// loop, as the driver's interrupt flag would.
class RigBus final : public hal::CanPort {
 public:
  explicit RigBus(std::function<void(const CanFrame&)> deliver)
      : deliver_(std::move(deliver)) {}
  std::deque<CanFrame> inbox;
  bool down = false;
  std::uint32_t bus_off = 0;

 private:
  bool DoSend(const CanFrame& frame) override {
    if (down) return false;
    deliver_(frame);
    return true;
  }
  bool DoReceive(CanFrame* frame) override {
    if (inbox.empty()) return false;
    *frame = inbox.front();
    inbox.pop_front();
    return true;
  }
  std::uint32_t DoTakeBusOff() override { return std::exchange(bus_off, 0); }
  hal::CanPortCounters DoCounters() const override { return {}; }
  std::function<void(const CanFrame&)> deliver_;
};

// The board (the firmware's JointBoard on the plant) and the host's side of the bus,
// one tick at a time.
class Rig {
 public:
  explicit Rig(FaultCase c)
      : case_(c),
        config_(CaseConfig(c)),
        bus_([this](const CanFrame& frame) { Receive(frame); }),
        board_(plant::LoadPlantParams("subject1"),
               app::JointBoardConfig{config_, {}, 0, 1}, &bus_),
        reference_(config_),
        base_preload_Nm_(board_.plant().params().interface.preload_Nm) {}

  sim::SimBoard& board() { return board_; }
  app::CanNode& node() { return board_.board().node(); }
  const SampleReference& reference() const { return reference_; }
  const std::string& error() const { return error_; }
  void Fail(const std::string& why) {
    if (error_.empty()) error_ = why;
  }

  // The board's clock as the main loop sees it between ticks: the last tick's number.
  std::uint32_t now() const { return next_tick_ - 1; }
  std::uint32_t next_tick() const { return next_tick_; }
  bool bridge() { return board_.io().bridge_enabled(); }
  app::BoardState state() { return board_.app().state(); }
  // Plant-truth joint velocity at the instant tick `tick`'s sample was taken.
  double truth_velocity(std::uint32_t tick) const { return truth_velocity_.at(tick); }
  // Its mean over the `span` ticks up to now, as the board's travel spans them: the
  // speeds at the instants between the two readings, the ends counted half.
  double truth_mean_velocity(std::uint32_t span) const {
    double sum = 0.5 * (truth_velocity(now() - span) + truth_velocity(now()));
    for (std::uint32_t i = 1; i < span; ++i) sum += truth_velocity(now() - i);
    return sum / span;
  }

  // Powers on, calibrates, lowers the torque limit (its case), starts heartbeats.
  void PowerOn() {
    heartbeats_ = true;
    Tick();  // the first tick seeds the signal chain
    Calibration cal;
    const plant::CableParams& cable = board_.plant().params().cable;
    cal.backlash.c_right = Angle::Quantize(cable.c_right_rad);
    cal.backlash.c_left = Angle::Quantize(cable.c_left_rad);
    if (board_.app().SetCalibration(cal).result != app::CommandOutcomeCode::kAccepted) {
      return Fail("calibration refused");
    }
    config_ = cal.AppliedTo(config_);
    Reconfigured();
    Tick();
    if (!board_.app().calibrated()) return Fail("calibration not applied");
    if (case_ == FaultCase::kTorqueLimit) {
      config_.supervisor.torque_max = Torque::Quantize(kTorqueMaxNm);
      Send(protocol::ParamWrite{protocol::ParamId::kTorqueMax,
                                config_.supervisor.torque_max.raw()});
      Reconfigured();
      for (int i = 0; i < 10 && !param_ok_; ++i) Tick();
      if (!param_ok_) return Fail("torque limit write not acknowledged");
    }
    for (int i = 0; i < 100; ++i) Tick();
  }

  // Starts the trial (or the stream) and returns its first tick; 0 on failure.
  std::uint32_t StartMotion() {
    const bool stream = case_ == FaultCase::kCommandTimeout;
    protocol::ConfigDigest digest = 0;  // the start names the trial's configuration
    if (!stream) {
      protocol::TrialConfig trial;
      trial.amplitude = Angle::Quantize(kAmplitudeRad);
      trial.frequency_mHz = 500;
      trial.repetitions = 5;
      trial.rest_100ms = kRest100ms;
      Send(trial);
      digest = protocol::ConfigDigestOf(trial);
    }
    const CommandCode code =
        stream ? CommandCode::kStartStream : CommandCode::kStartTrial;
    const std::uint8_t seq = SendCommand(code, digest);
    const std::uint32_t first = next_tick_;
    const auto outcome = AwaitResult(code, seq);
    if (!outcome || *outcome != CommandOutcomeCode::kAccepted) {
      Fail("the board refused to start");
      return 0;
    }
    if (stream) {
      streaming_ = true;
      stream_start_tick_ = first;
      next_setpoint_tick_ = next_tick_;
    }
    return first;
  }

  // One tick and the main loop around it: the host's frames taken by a pass of the
  // board's main loop before the tick (the pulley moved by hand to `hand_pulley_rad` if
  // given), and a pass after it that sends the tick's verdicts, events and telemetry.
  void Tick(const double* hand_pulley_rad = nullptr) {
    HostSide();
    if (bus_.down && static_cast<std::int32_t>(now() - bus_up_tick_) >= 0) {
      bus_.down = false;
    }
    board_.Poll();
    if (overrun_) board_.io().InjectOverrun();
    if (pushing_ && next_tick_ >= push_start_) {
      const double f =
          std::min(1.0, static_cast<double>(next_tick_ - push_start_) / push_ramp_);
      plant::InterfaceParams interface = board_.plant().params().interface;
      interface.preload_Nm = push_from_ + (push_to_ - push_from_) * f;
      board_.plant().SetInterface(interface);
      if (f >= 1.0) pushing_ = false;
    }
    truth_velocity_.push_back(board_.plant().truth().joint_velocity_rad_s);
    if (hand_pulley_rad != nullptr) {
      // SimBoard::Tick with the motor pulley held by the operator's hand instead of
      // driven: only while the bridge is off.
      board_.app().ISR_Tick(board_.io());
      if (bridge()) Fail("the bridge came on while the pulley was held by hand");
      board_.plant().StepPrescribedMotor(*hand_pulley_rad, board_.tick_period_s());
    } else {
      board_.Tick();
    }
    if (board_.app().last().telemetry.tick != next_tick_) Fail("tick count mismatch");
    if (restart_pending_) reference_.Restart();
    restart_pending_ = false;
    reference_.Update(board_.io().last_sample(), applied_duty_, applied_error_);
    applied_duty_ = board_.io().duty();
    applied_error_ =
        board_.app().last().telemetry.setpoint.ToDouble() - reference_.motor();
    ++next_tick_;
    if (bus_.down && static_cast<std::int32_t>(now() - bus_up_tick_) >= 0) {
      bus_.down = false;
    }
    board_.Poll();
  }

  std::uint8_t SendCommand(CommandCode code, protocol::ConfigDigest config = 0) {
    Send(protocol::Command{code, ++sequence_, kSession, config});
    return sequence_;
  }

  // Ticks until the board answers command `seq`; its outcome, or none after 20 ticks.
  std::optional<CommandOutcomeCode> AwaitResult(CommandCode code, std::uint8_t seq) {
    for (int i = 0; i < 20; ++i) {
      for (const protocol::CommandResult& r : results_) {
        if (r.code == code && r.sequence == seq) return r.outcome;
      }
      Tick();
    }
    return std::nullopt;
  }

  // The subject's push: from tick `start` the strap preload ramps linearly from its
  // present value to `to_Nm` over `ramp` ticks. Relax() ramps it back to subject1's.
  void Push(std::uint32_t start, double to_Nm, std::uint32_t ramp) {
    push_from_ = board_.plant().params().interface.preload_Nm;
    push_to_ = to_Nm;
    push_start_ = start;
    push_ramp_ = ramp;
    pushing_ = true;
  }
  void Relax(std::uint32_t ramp) { Push(next_tick_, base_preload_Nm_, ramp); }

  void StopHeartbeats() { heartbeats_ = false; }
  void ResumeHeartbeats() {
    heartbeats_ = true;
    next_heartbeat_tick_ = next_tick_;
  }
  void StopStream() { streaming_ = false; }
  void SetOverrun(bool on) { overrun_ = on; }
  void BusOff() {
    ++bus_.bus_off;
    bus_.down = true;
    bus_up_tick_ = now() + kBusOffRecoveryTicks;
  }
  // An emergency stop to every node (mjc estop), received before the next tick.
  void StopAll() { Send(protocol::StopAll{protocol::kStopAllKey, kSession}); }
  std::uint32_t last_heartbeat_rx() const { return last_heartbeat_rx_; }
  std::uint32_t last_setpoint_rx() const { return last_setpoint_rx_; }
  const std::vector<protocol::FaultEvent>& fault_events() const { return fault_events_; }

 private:
  template <class M>
  void Send(const M& message) {
    if (bus_.down) return;  // lost with the bus
    bus_.inbox.push_back(protocol::Encode(message, kNode));
  }

  void Reconfigured() {
    reference_.set_config(config_);
    restart_pending_ = true;  // the next tick applies it
  }

  // The host's periodic frames, received in the main loop before the next tick (the
  // first after the first tick: the board's clock starts there).
  void HostSide() {
    const std::uint32_t hz = board_.tick_hz();
    if (heartbeats_ && next_tick_ >= next_heartbeat_tick_ && next_tick_ > 0) {
      Send(protocol::HostHeartbeat{++heartbeat_sequence_, kSession});
      if (!bus_.down) last_heartbeat_rx_ = now();
      next_heartbeat_tick_ = next_tick_ + hz / 10;  // 10 Hz
    }
    if (streaming_ && next_tick_ >= next_setpoint_tick_) {
      const double t = static_cast<double>(next_tick_ - stream_start_tick_) / hz;
      protocol::Setpoint s;
      s.position =
          Angle::Quantize(kAmplitudeRad * std::sin(2 * std::numbers::pi * 0.5 * t));
      s.sequence = ++setpoint_sequence_;
      Send(s);
      if (!bus_.down) last_setpoint_rx_ = now();
      next_setpoint_tick_ = next_tick_ + hz / 100;  // 100 Hz
    }
  }

  void Receive(const CanFrame& frame) {
    using protocol::Function;
    switch (static_cast<Function>(protocol::FunctionOf(frame.id))) {
      case Function::kFault: {
        protocol::FaultEvent f;
        if (protocol::Decode(frame, &f) != protocol::DecodeError::kOk) {
          return Fail("a FaultEvent frame did not decode");
        }
        fault_events_.push_back(f);
        return;
      }
      case Function::kCommandResult: {
        protocol::CommandResult r;
        if (protocol::Decode(frame, &r) != protocol::DecodeError::kOk) {
          return Fail("a CommandResult frame did not decode");
        }
        results_.push_back(r);
        return;
      }
      case Function::kParamValue: {
        protocol::ParamValue v;
        if (protocol::Decode(frame, &v) == protocol::DecodeError::kOk &&
            v.id == protocol::ParamId::kTorqueMax &&
            v.status == protocol::ParamStatus::kOk &&
            v.value == config_.supervisor.torque_max.raw()) {
          param_ok_ = true;
        }
        return;
      }
      default:
        return;  // telemetry, heartbeats, window reports
    }
  }

  FaultCase case_;
  ControlConfig config_;
  RigBus bus_;
  sim::SimBoard board_;
  SampleReference reference_;
  std::string error_;
  std::uint32_t next_tick_ = 0;
  double applied_duty_ = 0;
  double applied_error_ = 0;
  bool restart_pending_ = true;
  std::vector<double> truth_velocity_;  // by board tick

  bool heartbeats_ = false;
  std::uint32_t next_heartbeat_tick_ = 0;
  std::uint8_t heartbeat_sequence_ = 0;
  std::uint32_t last_heartbeat_rx_ = 0;
  bool streaming_ = false;
  std::uint32_t stream_start_tick_ = 0, next_setpoint_tick_ = 0, last_setpoint_rx_ = 0;
  std::uint16_t setpoint_sequence_ = 0;
  bool overrun_ = false;
  bool pushing_ = false;
  double push_from_ = 0, push_to_ = 0;
  std::uint32_t push_start_ = 0, push_ramp_ = 1;
  double base_preload_Nm_;
  std::uint32_t bus_up_tick_ = 0;
  std::uint8_t sequence_ = 0;
  bool param_ok_ = false;
  std::vector<protocol::FaultEvent> fault_events_;
  std::vector<protocol::CommandResult> results_;
};

// Whether the cause of `c` shows on the last tick's sample, by the reference. For the
// velocity limit both the mean speed the board judges and the plant truth's mean over
// the same span must be beyond.
bool CausePresent(FaultCase c, Rig& rig, std::uint16_t span) {
  const SampleReference& r = rig.reference();
  switch (c) {
    case FaultCase::kJointParity:
      return !r.parity_ok();
    case FaultCase::kJointErrorFlag:
      return r.parity_ok() && r.error_flag();
    case FaultCase::kTickOverrun:
      return r.overrun();
    case FaultCase::kJointAngleLimit:
      return r.joint() > kJointMaxRad;
    case FaultCase::kMotorAngleLimit:
      return r.motor() > kMotorMaxRad;
    case FaultCase::kTorqueLimit:
      return std::fabs(r.torque()) > kTorqueMaxNm;
    case FaultCase::kVelocityLimit:
      return std::fabs(r.velocity()) > kVelocityMaxRadS &&
             std::fabs(rig.truth_mean_velocity(span)) > kVelocityMaxRadS;
    default:
      return false;
  }
}

// Ticks from the stop to the ClearFaults that should be refused, chosen where the
// cause still shows clearly. Joint angle and torque: 100 ms, for the joint to settle
// against the hand (b/(K + k) = 49 ms), so the clear is judged on a sample clearly
// beyond the limit rather than one within the encoder's noise of the crossing. Motor
// angle: at once (the motor count has no noise, and within tens of ms the spring
// back-drives the unpowered pulley inside the limit). Velocity: a span and a half, the
// operator's hand driving the joint on meanwhile (kHandSpeedRadS), so that the whole
// span the mean covers is that motion.
std::uint32_t RefusalDelay(FaultCase c, std::uint16_t span) {
  if (c == FaultCase::kJointAngleLimit || c == FaultCase::kTorqueLimit) return 1000;
  if (c == FaultCase::kVelocityLimit) return 3u * span / 2u;
  return 1;
}

}  // namespace

const char* Name(FaultCase c) {
  switch (c) {
    case FaultCase::kJointParity:
      return "joint_parity";
    case FaultCase::kJointErrorFlag:
      return "joint_error_flag";
    case FaultCase::kJointJump:
      return "joint_jump";
    case FaultCase::kJointStuck:
      return "joint_stuck";
    case FaultCase::kMotorStuck:
      return "motor_stuck";
    case FaultCase::kJointAngleLimit:
      return "joint_angle_limit";
    case FaultCase::kMotorAngleLimit:
      return "motor_angle_limit";
    case FaultCase::kTorqueLimit:
      return "torque_limit";
    case FaultCase::kVelocityLimit:
      return "velocity_limit";
    case FaultCase::kTickOverrun:
      return "tick_overrun";
    case FaultCase::kCommandTimeout:
      return "command_timeout";
    case FaultCase::kHostHeartbeatLost:
      return "host_heartbeat_lost";
    case FaultCase::kCanBusOff:
      return "can_bus_off";
    case FaultCase::kEmergencyStop:
      return "emergency_stop";
  }
  return "?";
}

Fault ExpectedFault(FaultCase c) {
  switch (c) {
    case FaultCase::kJointParity:
      return Fault::kJointParity;
    case FaultCase::kJointErrorFlag:
      return Fault::kJointErrorFlag;
    case FaultCase::kJointJump:
      return Fault::kJointJump;
    case FaultCase::kJointStuck:
      return Fault::kJointStuck;
    case FaultCase::kMotorStuck:
      return Fault::kMotorStuck;
    case FaultCase::kJointAngleLimit:
      return Fault::kJointAngleLimit;
    case FaultCase::kMotorAngleLimit:
      return Fault::kMotorAngleLimit;
    case FaultCase::kTorqueLimit:
      return Fault::kTorqueLimit;
    case FaultCase::kVelocityLimit:
      return Fault::kVelocityLimit;
    case FaultCase::kTickOverrun:
      return Fault::kTickOverrun;
    case FaultCase::kCommandTimeout:
      return Fault::kCommandTimeout;
    case FaultCase::kHostHeartbeatLost:
      return Fault::kHostHeartbeatLost;
    case FaultCase::kCanBusOff:
      return Fault::kCanBusOff;
    case FaultCase::kEmergencyStop:
      return Fault::kEmergencyStop;
  }
  return Fault::kNone;
}

Measurement Measure(FaultCase c) {
  Measurement m;
  m.which = c;
  Rig rig(c);
  const auto finish = [&]() -> Measurement& {
    if (m.error.empty()) m.error = rig.error();
    return m;
  };
  m.tick_hz = rig.board().tick_hz();
  m.delay_ticks = rig.board().app().control().delay_ticks();
  m.host_timeout_ms = rig.node().config().host_timeout_ms;
  m.stream_timeout_ms = rig.node().config().stream_timeout_ms;

  rig.PowerOn();
  if (!rig.error().empty()) return finish();
  const std::uint32_t start = rig.StartMotion();
  if (!rig.error().empty()) return finish();
  if (c == FaultCase::kTorqueLimit)
    rig.Push(start + kRestTicks, kPushPreloadNm, kPushRampTicks);

  // Run to the cause. Limits: the trial crosses them on its own; the first sample
  // beyond is found by the reference, tick by tick, until the board stops.
  const std::uint32_t inject =
      start + (c == FaultCase::kJointStuck       ? kFlexionPeakTicks
               : c == FaultCase::kCommandTimeout ? kStreamTicks
                                                 : kMidFlexionTicks);
  bool have_cause = false;
  bool have_detectable = false;
  if (!IsLimit(c)) {
    while (rig.next_tick() < inject && rig.error().empty()) rig.Tick();
    if (!rig.bridge() || rig.state() != app::BoardState::kRunning) {
      m.error = "not running when the fault was due";
      return finish();
    }
    plant::Plant& plant = rig.board().plant();
    using Kind = plant::SensorFaultKind;
    switch (c) {
      case FaultCase::kJointParity:
        plant.InjectFault({Kind::kJointParity, 0, 0});
        break;
      case FaultCase::kJointErrorFlag:
        plant.InjectFault({Kind::kJointErrorFlag, 0, 0});
        break;
      case FaultCase::kJointJump:
        plant.InjectFault({Kind::kJointJump, 1, 100});
        break;
      case FaultCase::kJointStuck:
        plant.InjectFault({Kind::kJointStuck, 0, 0});
        break;
      case FaultCase::kMotorStuck:
        plant.InjectFault({Kind::kMotorStuck, 0, 0});
        break;
      case FaultCase::kTickOverrun:
        rig.SetOverrun(true);
        break;
      case FaultCase::kCommandTimeout:
        rig.StopStream();
        break;
      case FaultCase::kHostHeartbeatLost:
        rig.StopHeartbeats();
        break;
      case FaultCase::kCanBusOff:
        rig.BusOff();
        break;
      case FaultCase::kEmergencyStop:
        rig.StopAll();
        break;
      default:
        break;
    }
    have_cause = true;
    // A sample fault is carried by the next tick's sample; a lost message counts from
    // the tick it was last received at, bus-off from the tick of the call, a StopAll
    // from the tick after which it was received.
    m.cause_tick = c == FaultCase::kCommandTimeout      ? rig.last_setpoint_rx()
                   : c == FaultCase::kHostHeartbeatLost ? rig.last_heartbeat_rx()
                   : c == FaultCase::kCanBusOff || c == FaultCase::kEmergencyStop
                       ? rig.now()
                       : rig.next_tick();
    if (!IsStuck(c)) {
      m.detectable_tick = m.cause_tick;
      have_detectable = true;
    }
  }

  // Run to the stop, watching for the first sample beyond a limit (the velocity's
  // cause: the plant truth at the sample instant) and the first the stuck and velocity
  // rules can judge.
  const std::uint32_t give_up = rig.next_tick() + kMaxStopTicks;
  bool bridge_at_cause = rig.bridge();
  while (rig.error().empty() && rig.next_tick() < give_up) {
    const bool on_before = rig.bridge();
    rig.Tick();
    const std::uint32_t tick = rig.now();
    const SampleReference& r = rig.reference();
    if (IsLimit(c) && !have_cause &&
        (c == FaultCase::kVelocityLimit
             ? std::fabs(rig.truth_velocity(tick)) > kVelocityMaxRadS
             : CausePresent(c, rig, 0))) {
      have_cause = true;
      m.cause_tick = tick;
      bridge_at_cause = on_before;
    }
    const bool rule =
        c == FaultCase::kJointStuck   ? r.joint_stuck()
        : c == FaultCase::kMotorStuck ? r.motor_stuck()
        : c == FaultCase::kVelocityLimit
            ? std::fabs(r.velocity()) > kVelocityMaxRadS - kVelocityReferenceTolRadS
        : IsLimit(c) ? have_cause
                     : false;
    if (!have_detectable && rule) {
      have_detectable = true;
      m.detectable_tick = tick;
    }
    m.velocity_before_stop = m.velocity_at_stop;
    m.velocity_at_stop = std::fabs(r.velocity());
    if (c == FaultCase::kVelocityLimit && rig.now() >= m.delay_ticks) {
      m.truth_mean_at_stop = std::fabs(rig.truth_mean_velocity(m.delay_ticks));
    }
    if (!rig.bridge()) {
      m.stop_tick = tick;
      m.raised = rig.board().app().last().raised;
      break;
    }
  }
  if (!rig.error().empty()) return finish();
  if (m.stop_tick == 0) {
    m.error = "the bridge never went off";
    return finish();
  }
  if (!have_cause || !have_detectable) {
    m.error = "the board stopped before the reference saw the cause";
    return finish();
  }
  if (!bridge_at_cause) m.error = "the bridge was already off at the cause";

  // The latch, through a refused clear while the cause persists, to the accepted one.
  std::uint32_t latched_ok = 0, latched_seen = 0;
  const auto tick_latched = [&](const double* hand = nullptr) {
    rig.Tick(hand);
    ++latched_seen;
    if (!rig.bridge() && rig.state() == app::BoardState::kFault) ++latched_ok;
  };
  if (CausePersists(c)) {
    const std::uint32_t at = m.stop_tick + RefusalDelay(c, m.delay_ticks);
    // The velocity's cause kept up by hand: the pulley driven on from where it is.
    const double hand_from = rig.board().plant().truth().motor_pulley_angle_rad;
    const double hand_rate =
        std::copysign(kHandSpeedRadS, rig.truth_velocity(rig.now())) /
        static_cast<double>(m.tick_hz);
    std::uint32_t hand_ticks = 0;
    const auto tick_refusing = [&] {
      if (c != FaultCase::kVelocityLimit) return tick_latched();
      const double pulley = hand_from + hand_rate * ++hand_ticks;
      tick_latched(&pulley);
    };
    while (rig.now() < at) tick_refusing();
    m.refusal_tried = true;
    const std::uint8_t seq = rig.SendCommand(CommandCode::kClearFaults);
    tick_refusing();  // judges the clear on this tick's sample
    m.cause_present_at_refusal = CausePresent(c, rig, m.delay_ticks);
    m.fault_after_refusal = !rig.bridge() && rig.state() == app::BoardState::kFault;
    const auto outcome = rig.AwaitResult(CommandCode::kClearFaults, seq);
    if (!outcome) {
      m.error = "the refused clear was not answered";
      return finish();
    }
    m.refusal_outcome = *outcome;
  }

  // The subject relaxes, the operator brings the pulley back to 0 by hand, the sensor
  // recovers, everything settles.
  if (c == FaultCase::kTorqueLimit) {
    rig.Relax(kPushRampTicks);
    for (std::uint32_t i = 0; i < kPushRampTicks; ++i) tick_latched();
  }
  const double from = rig.board().plant().truth().motor_pulley_angle_rad;
  for (std::uint32_t i = 1; i <= kHandReturnTicks + kHandHoldTicks; ++i) {
    const double f = std::min(1.0, static_cast<double>(i) / kHandReturnTicks);
    const double pulley = from * 0.5 * (1 + std::cos(std::numbers::pi * f));
    tick_latched(&pulley);
  }
  rig.board().plant().ClearFaults();
  rig.SetOverrun(false);
  if (c == FaultCase::kHostHeartbeatLost) rig.ResumeHeartbeats();
  for (std::uint32_t i = 0; i < kSettleTicks; ++i) tick_latched();

  const std::uint8_t seq = rig.SendCommand(CommandCode::kClearFaults);
  rig.Tick();  // judges the clear on this tick's sample
  ++latched_seen;
  if (!rig.bridge()) ++latched_ok;
  m.cause_gone_at_clear =
      !rig.reference().ClearBlocked() && !CausePresent(c, rig, m.delay_ticks);
  const auto outcome = rig.AwaitResult(CommandCode::kClearFaults, seq);
  m.clear_answered = outcome.has_value();
  if (outcome) m.clear_outcome = *outcome;
  m.idle_after_clear = rig.state() == app::BoardState::kIdle && !rig.bridge();
  m.latched_ticks = latched_seen;
  m.latched = latched_seen > 0 && latched_ok == latched_seen;

  const auto& events = rig.fault_events();
  m.fault_frames = static_cast<int>(events.size());
  if (!events.empty()) {
    m.frame_fault = events.front().fault;
    m.frame_tick = events.front().tick;
    if (events.front().state != protocol::BoardState::kFault) {
      m.error = "the FaultEvent does not report the fault state";
    }
  }
  return finish();
}

}  // namespace mjc::safe_stop
