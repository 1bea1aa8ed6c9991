// Position setpoint generators (docs/DESIGN.md §2, step 6): the sinusoidal trial, the
// increasing-amplitude calibration sweep, hold, and rate-limited streamed setpoints.
// TrajectoryGenerator::Step() runs once per control tick and returns the setpoint, its
// derivative as velocity feed-forward, and the motion segment the energy windows
// (docs/DESIGN.md §2, step 4) are cut by.
//
// Sine and sweep timing is integer-exact. A cycle lasts N = 4·Q ticks, with Q the
// ticks per quarter cycle,
//     Q = round(f_tick / (4·f)),
// so every quarter cycle -- flexion loading, flexion unloading, extension loading,
// extension unloading -- is exactly Q ticks, each repetition exactly N ticks, and a trial
// of R repetitions exactly R·N ticks after its leading rest, with no drift however long
// it runs. The phase at tick k of a cycle is floor(k·2^32/N) (uint32, 2^32 = one turn),
// stepped with an integer remainder (no division per tick), so it is exactly a quarter
// turn at each segment boundary: the commanded peak (sin = 1) falls on the first tick
// of an unloading segment, the zero crossings on the first tick of each loading segment.
// The price is that the frequency actually run is f_tick/N: it equals the requested
// one whenever 4·f divides f_tick (0.5, 1, 1.25, 2, 2.5 Hz ... at 10 kHz), and is
// otherwise within 2/N relative of it (6 Hz at 10 kHz: N = 1,668, run at 5.995 Hz).
// Velocity feed-forward uses the frequency actually run, so it is the derivative of the
// generated position.
//
// Accuracy against the exact values at tick k of a cycle, neutral + A·sin(2πk/N) and
// A·ω·cos(2πk/N) with ω = 2π·f_tick/N (A in rad, V = A·ω in rad/s):
//   position <= 0.5 + 0.038·A LSB of Angle: the product's rounding, plus A times the
//     0.84 LSB (Q1.30) of Sin and the < 1 LSB (2^-32 turn) floor of the phase;
//   velocity <= 1 + 0.0024·V LSB of AngularVelocity: rounding of A·ω and of the
//     product, plus V times the same two relative errors.
// At the paper's 25°, 0.5 Hz: 0.52 and 1.003 LSB (measured 0.51 and 0.73). The sweep
// adds its ramps' roundings (<= 0.5 LSB each): position <= 1 + 0.038·A, velocity
// <= 2.12 + 0.0024·V. Tested in tests/unit/core/trajectory_vectors.cc.
#pragma once

#include <cstdint>
#include <numbers>

#include "mjc/core/quantities.h"

namespace mjc {

// The motion segment of a setpoint. Stable numbers: they travel over CAN and into logs.
enum class Segment : std::uint8_t {
  kIdle = 0,                // no trajectory, or a sine/sweep has finished
  kRest = 1,                // at neutral before the first or after the last cycle
  kFlexionLoading = 2,      // phase [0, π/2): neutral -> neutral + A
  kFlexionUnloading = 3,    // phase [π/2, π): neutral + A -> neutral
  kExtensionLoading = 4,    // phase [π, 3π/2): neutral -> neutral − A
  kExtensionUnloading = 5,  // phase [3π/2, 2π): neutral − A -> neutral
  kHold = 6,
  kStream = 7,
};

struct TrajectoryPoint {
  Angle position;            // setpoint, rad
  AngularVelocity velocity;  // d position / dt, feed-forward, rad/s
  Segment segment = Segment::kIdle;
  // Sine and sweep: the number of cycles completed before this tick, i.e. the 0-based
  // index of the current cycle; equal to the configured repetitions during the
  // trailing rest and once done. 0 in hold and stream.
  std::uint16_t repetition = 0;
  // True exactly when segment == kIdle: nothing is running, or a sine/sweep finished.
  bool done = true;
};

// Why a configuration was refused. Stable numbers, grouped by range, never renumbered:
// 0 ok, 1..15 amplitude and position, 16..31 timing, 32..47 streaming.
enum class TrajectoryError : std::uint8_t {
  kOk = 0,
  kAmplitudeNotPositive = 1,  // amplitude (sweep: end amplitude) <= 0
  kAmplitudeTooLarge = 2,     // an amplitude > kMaxTrajectoryAmplitude
  kAmplitudeNegative = 3,     // sweep start amplitude < 0
  kSetpointOutOfRange = 4,    // neutral ± amplitude outside Angle's range
  kVelocityOutOfRange = 5,    // peak velocity outside AngularVelocity's range
  kFrequencyNotPositive = 16,
  kFrequencyTooHigh = 17,  // above tick rate / 4
  kZeroRepetitions = 18,
  kRestTooLong = 19,          // rest_ms > kMaxRestMs
  kTickRateOutOfRange = 20,   // outside [1, kMaxTickRateHz]
  kTickRateMismatch = 21,     // config's tick rate is not the generator's
  kRateNotPositive = 32,      // stream max_rate <= 0
  kRateBelowResolution = 33,  // stream max_rate·dt below 1 LSB of Angle
  kNotStreaming = 34,         // SetStreamTarget outside stream mode
};

enum class TrajectoryMode : std::uint8_t {
  kIdle = 0,
  kHold = 1,
  kSine = 2,
  kSweep = 3,
  kStream = 4,
};

inline constexpr std::uint32_t kDefaultTickRateHz = 10000;
// Up to 65,535 Hz the ticks per cycle N <= f_tick·2^16 (the slowest Q15.16 frequency is
// 2^-16 Hz) fit a uint32, and the 64-bit intermediates of the velocity scaling cannot
// overflow. The board ticks at 10 kHz; 20-40 kHz stays legal.
inline constexpr std::uint32_t kMaxTickRateHz = 65535;
// Half a turn. Finger joints move less than 100° and with α = r_m/r_j ≈ 1 the motor
// pulley moves alike (the paper's largest amplitude is 25° = 0.44 rad); anything larger
// is most likely degrees sent as radians, and "25 rad" would wind the cable 4 turns.
inline constexpr Angle kMaxTrajectoryAmplitude = Angle::FromDouble(std::numbers::pi);
// A minute: the paper rests 3 s between amplitude trials.
inline constexpr std::uint32_t kMaxRestMs = 60000;

// A sinusoidal trial: `rest_ms` at neutral, then `repetitions` cycles of
//     position = neutral + amplitude·sin(2π·f·t),  velocity = amplitude·2π·f·cos(2π·f·t)
// starting at phase 0 (so the first cycle opens with flexion loading, position rising),
// then `rest_ms` at neutral again, then done at neutral. The commanded velocity steps
// from 0 to amplitude·2πf at the first cycle tick and back to 0 after the last, as in
// the paper's trials. The paper's 3 s between amplitude trials is rest_ms = 1500 on
// back-to-back trials (each rests before and after), or 3000 for 3 s at both ends.
struct SineConfig {
  Angle neutral;    // rad; neutral ± amplitude must lie inside Angle's ±128 rad
  Angle amplitude;  // rad, (0, kMaxTrajectoryAmplitude]
  // Hz, (0, tick_rate_hz/4]; run as tick_rate_hz / N with N a multiple of 4 (see top).
  Frequency frequency;
  std::uint16_t repetitions = 5;  // cycles, >= 1
  // Rest before the first and after the last cycle, ms, [0, kMaxRestMs]; run as
  // round(rest_ms·tick_rate_hz/1000) ticks (exact for tick rates that are whole kHz).
  std::uint32_t rest_ms = 0;
  // Must equal the generator's tick rate, [1, kMaxTickRateHz].
  std::uint32_t tick_rate_hz = kDefaultTickRateHz;
};

// A sine whose amplitude ramps: the calibration sweep (paper Fig. 7), which the wire's
// protocol::SweepConfig asks for. Like SineConfig, but the amplitude ramps
// linearly in time from start_amplitude at the first cycle tick to end_amplitude at the
// end of the last cycle (one rounding per tick, no accumulated error). Segments,
// repetition and done are as for the sine. Velocity is the exact derivative,
// A(t)·2πf·cos + (dA/dt)·sin.
struct RampedSineConfig {
  Angle neutral;                  // rad; neutral ± max amplitude inside Angle's range
  Angle start_amplitude;          // rad, [0, kMaxTrajectoryAmplitude]
  Angle end_amplitude;            // rad, (0, kMaxTrajectoryAmplitude]; may be below start
  Frequency frequency;            // Hz, (0, tick_rate_hz/4]
  std::uint16_t repetitions = 5;  // cycles over which the amplitude ramps, >= 1
  std::uint32_t rest_ms = 0;      // ms, [0, kMaxRestMs]
  std::uint32_t tick_rate_hz = kDefaultTickRateHz;  // [1, kMaxTickRateHz]
};

// kOk, or the first failing check in this order: tick rate, amplitude(s), frequency,
// repetitions, rest, setpoint range, velocity range.
[[nodiscard]] TrajectoryError Validate(const SineConfig& config);
[[nodiscard]] TrajectoryError Validate(const RampedSineConfig& config);
// The checks StartStream applies to its max_rate at tick_rate_hz: kOk,
// kTickRateOutOfRange, kRateNotPositive or kRateBelowResolution.
[[nodiscard]] TrajectoryError ValidateStreamRate(AngularVelocity max_rate,
                                                 std::uint32_t tick_rate_hz);
// Q = round(f_tick / (4·f)), the ticks of each quarter cycle a sine or sweep at
// `frequency` runs (see top); for 0 < frequency <= tick_rate_hz/4 (Validate's range).
std::uint32_t QuarterTicks(Frequency frequency, std::uint32_t tick_rate_hz);

namespace trajectory_detail {

// value(k) = start + round((end − start)·k / ticks), ties toward +inf, advanced once per
// tick with an integer remainder: no division per tick, value(ticks) = end exactly.
class LinearRamp {
 public:
  constexpr LinearRamp() = default;
  // ticks >= 1.
  LinearRamp(std::int32_t start, std::int32_t end, std::uint64_t ticks);
  constexpr std::int32_t value() const { return static_cast<std::int32_t>(value_); }
  void Advance();

 private:
  std::int64_t value_ = 0;
  std::int64_t quotient_ = 0;    // floor((end − start) / ticks)
  std::uint64_t remainder_ = 0;  // (end − start) − quotient·ticks, in [0, ticks)
  std::uint64_t ticks_ = 1;
  std::uint64_t accumulator_ = 0;  // in [0, ticks)
};

}  // namespace trajectory_detail

// Owns the active generator. Not thread-safe: configure and step from the same context
// (the control tick), or hand configurations over through the tick's double buffer.
class TrajectoryGenerator {
 public:
  // tick_rate_hz: the rate Step() is called at, [1, kMaxTickRateHz]; outside it every
  // Start… call is refused (kTickRateOutOfRange / kTickRateMismatch), Hold and Stop
  // still work. Starts idle at initial_position.
  explicit constexpr TrajectoryGenerator(std::uint32_t tick_rate_hz = kDefaultTickRateHz,
                                         Angle initial_position = Angle{})
      : tick_rate_hz_(tick_rate_hz), position_(initial_position) {}

  // Starts a sine trial from its first tick, replacing whatever runs. The setpoint
  // jumps to config.neutral: bring the joint there first (Hold, or StartStream with a
  // target of neutral). On any error nothing changes and the old trajectory continues.
  [[nodiscard]] TrajectoryError StartSine(const SineConfig& config);
  // The calibration sweep, with the same contract as StartSine.
  [[nodiscard]] TrajectoryError StartSweep(const RampedSineConfig& config);
  // Constant setpoint `position` (rad, any value), velocity 0, segment kHold, until
  // replaced.
  void Hold(Angle position);
  // Rate-limited streaming from `from` (rad, usually the present position). Each Step()
  // moves the setpoint toward the latest target by at most
  // floor(max_rate·dt / 1 LSB of Angle), so |step| <= max_rate/f_tick always, and
  // reports the step taken times f_tick as velocity (<= max_rate). The target starts
  // at `from`. max_rate: rad/s, > 0 and >= 1 LSB of Angle per tick (6.0e-4 rad/s at
  // 10 kHz); otherwise refused and the old trajectory continues.
  [[nodiscard]] TrajectoryError StartStream(Angle from, AngularVelocity max_rate);
  // New target for the stream (rad, any value; the host's 100-1000 Hz updates). Outside
  // stream mode: kNotStreaming, ignored.
  [[nodiscard]] TrajectoryError SetStreamTarget(Angle target);
  // Idle at the last setpoint returned by Step() (or the initial position), velocity 0,
  // segment kIdle, done.
  void Stop();

  // The setpoint for this tick; call exactly once per control tick. The first call
  // after a Start… returns that trajectory's tick 0.
  TrajectoryPoint Step();

  TrajectoryMode mode() const { return mode_; }
  // The last setpoint returned by Step() (before any Step: the initial position or the
  // Hold / stream start position).
  Angle position() const { return position_; }
  std::uint32_t tick_rate_hz() const { return tick_rate_hz_; }
  // Sine and sweep: N, the exact length of one cycle in ticks; 0 in other modes.
  std::uint32_t ticks_per_cycle() const;
  // Sine and sweep: the length of each rest in ticks; 0 in other modes.
  std::uint32_t rest_ticks() const;

 private:
  enum class Stage : std::uint8_t { kLeadingRest, kCycling, kTrailingRest };

  TrajectoryError StartOscillation(TrajectoryMode mode, Angle neutral,
                                   Angle start_amplitude, Angle end_amplitude,
                                   Frequency frequency, std::uint16_t repetitions,
                                   std::uint32_t rest_ms, std::uint32_t tick_rate_hz);
  TrajectoryPoint StepOscillation();
  TrajectoryPoint StepStream();
  void AdvanceCycle();

  std::uint32_t tick_rate_hz_;
  TrajectoryMode mode_ = TrajectoryMode::kIdle;
  Angle position_;                // last setpoint returned, or the hold position
  std::uint16_t repetition_ = 0;  // reported while idle after a finished trial

  // Sine and sweep.
  Angle neutral_;
  trajectory_detail::LinearRamp amplitude_;      // Angle raw
  trajectory_detail::LinearRamp peak_velocity_;  // amplitude·ω, AngularVelocity raw
  AngularVelocity amplitude_rate_;               // d amplitude / dt (sweep)
  bool ramping_ = false;  // amplitude changes (a sweep): the ramps advance each tick
  std::uint32_t quarter_ticks_ = 0;      // Q
  std::uint32_t phase_step_ = 0;         // floor(2^30 / Q)
  std::uint32_t phase_remainder_ = 0;    // 2^30 mod Q
  std::uint32_t tick_in_quarter_ = 0;    // [0, Q)
  std::uint32_t phase_offset_ = 0;       // floor(tick_in_quarter·2^30 / Q)
  std::uint32_t phase_accumulator_ = 0;  // tick_in_quarter·2^30 mod Q
  std::uint32_t quadrant_ = 0;           // [0, 4)
  std::uint32_t rest_ticks_ = 0;
  std::uint32_t rest_left_ = 0;
  std::uint16_t repetitions_ = 0;
  Stage stage_ = Stage::kLeadingRest;

  // Stream.
  Angle target_;
  std::int32_t max_step_ = 0;  // Angle raw per tick, >= 1
};

// Inline, so that the tick calls the mode's step directly. With AdvanceCycle inlined
// and the sine and cosine products unsaturated (MulInRange, trajectory.cc) it took the
// tick from 945 to 926 Cortex-M4 instructions (100 mid-trial ticks).
inline TrajectoryPoint TrajectoryGenerator::Step() {
  switch (mode_) {
    case TrajectoryMode::kSine:
    case TrajectoryMode::kSweep:
      return StepOscillation();
    case TrajectoryMode::kStream:
      return StepStream();
    case TrajectoryMode::kHold:
      return {position_, AngularVelocity{}, Segment::kHold, 0, false};
    case TrajectoryMode::kIdle:
      break;
  }
  return {position_, AngularVelocity{}, Segment::kIdle, repetition_, true};
}

}  // namespace mjc
