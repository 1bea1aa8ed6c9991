// Cortex-M4 benchmark image: runs each core kernel once between two marker calls.
// scripts/cm4-instructions traces the run in QEMU and counts the instructions executed
// between mjc_bench_begin and mjc_bench_end; the "baseline" entry (an empty body)
// measures the markers' own cost, which the script subtracts. Built NO_HEAP and
// NO_DOUBLE: it is also the link-time proof that the core needs neither.
#include "bench_cm4.h"
#include "core_kernels.h"
#include "mjc/app/can_node.h"
#include "mjc/core/control_tick.h"
#include "mjc/core/position_loop.h"

extern "C" {
extern std::uint32_t __stack_limit[];
}

namespace {

using namespace mjc;
using namespace mjc::literals;

// Inputs and outputs through volatile globals: the compiler cannot precompute a
// kernel, and loading/storing them is part of every entry including the baseline.
volatile std::int32_t g_in[4] = {(0.2_Nm).raw(), (0.15_rad_s).raw(), (0.4_rad).raw(),
                                 (0.39_rad).raw()};
volatile std::int32_t g_out = 0;
bench::Matrix3 g_matrix = bench::Matrix3::Identity();
bench::Vector3 g_x = bench::Vector3::Constant(0.1_rad);
bench::Vector3 g_y;

void Baseline() { g_out = g_in[0]; }
void FixedMul() {
  g_out = bench::TorqueTimesVelocity(Torque::FromRaw(g_in[0]),
                                     AngularVelocity::FromRaw(g_in[1]))
              .raw();
}
void SpringTorque() {
  g_out =
      bench::SpringTorque(0.63_Nm_rad, Angle::FromRaw(g_in[2]), Angle::FromRaw(g_in[3]))
          .raw();
}
void FixedDivide() {
  g_out = bench::AngleRatio(Angle::FromRaw(g_in[2]), Angle::FromRaw(g_in[3])).raw();
}
void MatVec3() {
  bench::MatVec3(g_matrix, g_x, g_y);
  g_out = g_y(0).raw();
}

// The control tick mid-trial: a 20 Hz sine so that windows open and close within the
// traced run (each window completion takes the longer path), with non-zero gains on
// every term of the position loop. The sensor words for the measured ticks are made
// before the markers by an identical shadow tick fed the same way, so the counts hold
// ISR_Step and a load of its sample, nothing else.
ControlTick g_tick;
ControlTick g_shadow;
TickResult g_result;
Angle g_setpoint;
constexpr int kMeasuredTicks = 101;
// Ticks that fill the velocity window (ControlTick::kMaxVelocityWindow and more) before
// anything is measured.
constexpr int kFillTicks = 1100;
Sample g_samples[kMeasuredTicks];

Sample SensorWords(Angle setpoint) {
  // An ideal motor at the setpoint, the joint a sixth of the way.
  Sample s;
  s.motor_count = static_cast<std::uint16_t>((setpoint.raw() / 515) & 0xFFFF);
  const std::int32_t joint = setpoint.raw() / 6434 / 6;
  s.joint_frame = EncodeJointFrame(static_cast<std::uint16_t>(joint & 0x3FFF), false);
  return s;
}

void StepOnce() {
  g_tick.ISR_Step(SensorWords(g_setpoint), &g_result);
  g_setpoint = g_result.telemetry.setpoint;
  g_out = g_result.telemetry.power.raw();
}
void ControlTick1() {
  g_tick.ISR_Step(g_samples[0], &g_result);
  g_out = g_result.telemetry.power.raw();
}
void ControlTick100() {
  for (int i = 1; i < kMeasuredTicks; ++i) g_tick.ISR_Step(g_samples[i], &g_result);
  g_out = g_result.telemetry.power.raw();
}

// A whole trial, for the mean the tick costs (./bench: tick_instructions_cm4): the
// board idle until the velocity window is full, then a 20 Hz sine of 5 repetitions with
// 30 ms of rest before and after, every tick of it measured: 300 + 5 × 500 + 300 ticks,
// and 9 of its 10 windows complete inside them (each 50 ms after its end: the
// estimator's delay; the last one's falls after the trailing rest). At 20 Hz a window
// completes every 250 ticks, 40 times as often as in the paper's 0.5 Hz trials, so the
// mean errs high. The trial's sensor
// words are made before the markers from a trajectory started alike (the setpoint the
// tick commands is the trajectory's: no backlash compensation, and no fault stops it).
// A rehearsal on a second tick, before the markers, counts the windows and faults, so
// the measured loop holds the ticks alone; the image checks that the measured tick
// ended where the rehearsal did.
constexpr std::uint16_t kTrialRepetitions = 5;
constexpr std::uint32_t kTrialRestMs = 30;
constexpr int kTrialTicks = 300 + kTrialRepetitions * 500 + 300;
static_assert(kTrialTicks == 3100, "the entry's name, control_tick_trial_x3100, says");
constexpr int kTrialWindows = 2 * kTrialRepetitions - 1;
ControlTick g_trial_tick;
ControlTick g_rehearsal_tick;
Sample g_trial_samples[kTrialTicks];
TickResult g_rehearsal_result;

SineConfig TrialSine() {
  SineConfig sine;
  sine.amplitude = Angle::FromDouble(0.4363);
  sine.frequency = Frequency::FromDouble(20.0);
  sine.repetitions = kTrialRepetitions;
  sine.rest_ms = kTrialRestMs;
  return sine;
}

void ControlTickTrial() {
  for (const Sample& s : g_trial_samples) g_trial_tick.ISR_Step(s, &g_result);
  g_out = g_result.telemetry.power.raw();
}

// The main loop's CAN work, which shares the core with the tick: one received frame
// of each kind the bus can bring (another board's, a malformed one, a setpoint, a
// parameter read that needs a reply) and the heaviest Poll (every telemetry message
// and the heartbeat due at once). With the tick's count these bound the work per
// 100 µs under a full-rate flood (./bench: flood_instructions_per_tick).
app::JointApp g_app{ControlConfig{}};
service::JointService g_service{&g_app, nullptr};
app::CanNode g_node{&g_service, app::CanNodeConfig{}};
protocol::CanFrame g_frames[4];

void DrainTx() {
  protocol::CanFrame f;
  while (g_node.PopTx(&f)) {
  }
}
void FrameForeign() { g_node.HandleFrame(g_frames[0]); }
void FrameMalformed() { g_node.HandleFrame(g_frames[1]); }
void FrameSetpoint() { g_node.HandleFrame(g_frames[2]); }
void FrameParamRead() { g_node.HandleFrame(g_frames[3]); }
void PollAllDue() {
  g_service.Poll();
  g_node.Poll();
}

// Names are stable: ./bench prints each as "<name>_cm4: <count> instructions".
constexpr bench::Entry kEntries[] = {
    {"baseline", Baseline},
    {"fixed_mul", FixedMul},
    {"spring_torque", SpringTorque},
    {"fixed_div", FixedDivide},
    {"eigen_matvec3", MatVec3},
    {"control_tick", ControlTick1},
    {"control_tick_x100", ControlTick100},
    {"control_tick_trial_x3100", ControlTickTrial},
    {"can_frame_foreign", FrameForeign},
    {"can_frame_malformed", FrameMalformed},
    {"can_frame_setpoint", FrameSetpoint},
    {"can_frame_param_read", FrameParamRead},
    {"can_poll_all_due", PollAllDue},
};

// Formats v in decimal: no printf here (newlib's stdio allocates).
void WriteNumber(const char* label, std::uint32_t v) {
  char text[16];
  int i = 15;
  text[i] = 0;
  do {
    text[--i] = static_cast<char>('0' + v % 10u);
    v /= 10u;
  } while (v != 0 && i > 0);
  qemu::SemihostWrite(label);
  qemu::SemihostWrite(text + i);
  qemu::SemihostWrite("\n");
}

// Stack high-water mark: paint the unused stack below the current frame, run, and
// find the lowest word that changed.
constexpr std::uint32_t kPaint = 0xC0FFEE11u;

__attribute__((noinline)) void PaintStack() {
  std::uintptr_t sp = 0;
  asm volatile("mov %0, sp" : "=r"(sp));
  const std::uintptr_t stop = sp - 256;  // leave this frame alone
  for (auto p = reinterpret_cast<std::uintptr_t>(__stack_limit); p < stop; p += 4) {
    *reinterpret_cast<volatile std::uint32_t*>(p) = kPaint;
  }
}

std::uint32_t StackUsed(const std::uint32_t* top_of_main) {
  const volatile std::uint32_t* p = __stack_limit;
  while (*p == kPaint) ++p;
  return static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(top_of_main) -
                                    reinterpret_cast<std::uintptr_t>(p));
}

// The benchmarks' tick: ±1° of slack, the shipped joint's cable friction, the position
// loop's gains, armed.
void ConfigureTick(ControlTick& tick) {
  ControlConfig config;
  config.backlash.c_right = Angle::FromDouble(0.0175);
  config.backlash.c_left = Angle::FromDouble(-0.0175);
  config.backlash.cable_friction = Torque::FromDouble(0.3);
  config.position.kp = Fixed<PerRadian, 16>::FromDouble(8.0);
  config.position.ki = Fixed<PerRadianSecond, 16>::FromDouble(20.0);
  config.position.kd = Fixed<SecondPerRadian, 16>::FromDouble(0.05);
  config.position.kff = Fixed<SecondPerRadian, 16>::FromDouble(0.1);
  tick.Configure(config);
  tick.Arm(true);
}

void SetUpTick(ControlTick& tick) {
  ConfigureTick(tick);
  SineConfig sine;
  sine.amplitude = Angle::FromDouble(0.4363);
  sine.frequency = Frequency::FromDouble(20.0);
  sine.repetitions = 50;
  if (tick.trajectory().StartSine(sine) != TrajectoryError::kOk) qemu::SemihostExit(3);
}

void SetUpCan() {
  using namespace mjc::protocol;
  g_frames[0] = Encode(TelemetryAngles{Angle::FromRaw(12345), Angle::FromRaw(-678)}, 2);
  g_frames[1] = Encode(Setpoint{Angle::FromRaw(0), 0}, 1);
  g_frames[1].length = 3;
  g_frames[2] = Encode(Setpoint{Angle::FromRaw(1 << 20), 7}, 1);
  g_frames[3] = Encode(ParamRead{ParamId::kPositionKp}, 1);
}

// Configured, armed, idle until the velocity window is full, the trial's sine started.
void PrepareTrialTick(ControlTick& tick) {
  ConfigureTick(tick);
  TickResult r;
  for (int i = 0; i < kFillTicks; ++i) tick.ISR_Step(SensorWords(Angle{}), &r);
  if (tick.trajectory().StartSine(TrialSine()) != TrajectoryError::kOk) {
    qemu::SemihostExit(3);
  }
}

void SetUpTrial() {
  PrepareTrialTick(g_trial_tick);
  PrepareTrialTick(g_rehearsal_tick);
  TrajectoryGenerator shadow(g_trial_tick.config().tick_hz);
  if (shadow.StartSine(TrialSine()) != TrajectoryError::kOk) qemu::SemihostExit(3);
  Angle setpoint;  // the idle tick's
  for (Sample& s : g_trial_samples) {
    s = SensorWords(setpoint);
    setpoint = shadow.Step().position;
  }
  // The rehearsal: every window completes and nothing faults.
  int windows = 0;
  for (const Sample& s : g_trial_samples) {
    g_rehearsal_tick.ISR_Step(s, &g_rehearsal_result);
    windows += g_rehearsal_result.window_completed ? 1 : 0;
  }
  if (windows != kTrialWindows || g_rehearsal_tick.fault() != Fault::kNone) {
    qemu::SemihostExit(4);
  }
}

void SetUp() {
  SetUpCan();
  SetUpTrial();
  SetUpTick(g_tick);
  SetUpTick(g_shadow);
  for (int i = 0; i < kFillTicks; ++i) StepOnce();  // fill the velocity window
  // The shadow replays the same ticks, then records the next ones' sensor words.
  TickResult r;
  Angle setpoint;
  for (int i = 0; i < kFillTicks + kMeasuredTicks; ++i) {
    const Sample s = SensorWords(setpoint);
    if (i >= kFillTicks) g_samples[i - kFillTicks] = s;
    g_shadow.ISR_Step(s, &r);
    setpoint = r.telemetry.setpoint;
  }
}

}  // namespace

int main() {
  std::uint32_t top_of_main = 0;
  SetUp();
  PaintStack();
  for (const bench::Entry& e : kEntries) {
    bench::Measure(e);
    DrainTx();
  }
  // The measured trial ended where its rehearsal did (the same energy and the same
  // clock), so it too ran whole, every window and no fault.
  if (g_trial_tick.fault() != Fault::kNone ||
      g_result.telemetry.energy_sum != g_rehearsal_result.telemetry.energy_sum ||
      g_result.telemetry.tick != g_rehearsal_result.telemetry.tick) {
    qemu::SemihostExit(4);
  }
  // A thousand more ticks (several window completions) for the high-water mark.
  g_setpoint = g_result.telemetry.setpoint;
  for (int i = 0; i < 1000; ++i) StepOnce();
  WriteNumber("stack_used_bytes: ", StackUsed(&top_of_main));
  WriteNumber("control_tick_ram_bytes: ", sizeof(ControlTick));
  return 0;
}
