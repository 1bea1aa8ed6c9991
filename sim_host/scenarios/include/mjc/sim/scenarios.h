// The paper's experiments (docs/DESIGN.md §5) on the simulated board: the calibration
// sweep and fit, single trials with plant ground truth, the repeatability study (Table I,
// Fig. 9) and the amplitude sweep (Figs. 10–12, Tables II–III). "Board" numbers are
// what the unmodified firmware estimated from its sensors; "truth" numbers are the
// plant's interface power and energy over the same windows, which the firmware never
// sees (the paper's "simulation" column).
//
// One path with the lab's tools: the board (its CAN node on the plant) sits on an
// in-process bus (sim::BusBoard, lock-stepped), and the host library drives it as
// `mjc calibrate` and `mjc trial` do. Where each figure comes from:
//  - over the protocol, what a lab gets from the tools: the calibration sweep's θ_m, θ_j
//    (the board's angle telemetry, Fig. 7), the fit made from them, the record uploaded
//    over ISO-TP and read back; every window's energies, η, ticks and attachment fit
//    (host::RunBoardTrial's windows: Tables I–III, Figs. 9–12, attachment_fit.csv);
//  - read on the board's side of the bus (a probe; the simulator's privilege): the
//    plant's truth (interface energy and power at the instant each tick samples,
//    aligned to the windows' tick ranges that arrived over the bus), and what the
//    protocol does not carry at the tick rate: the board's power every tick (power
//    RMSE, the windows' power profiles of Fig. 9), the aligned θ_j, θ̇_j, τ samples
//    (TrialOutcome::samples) and Fig. 8's trace.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "mjc/app/joint_config.h"
#include "mjc/host/calibration_fit.h"
#include "mjc/host/report.h"
#include "mjc/host/robot_description.h"
#include "mjc/plant/params.h"
#include "mjc/sim/bus_board.h"

namespace mjc::sim {

// Called with a stage name and the fraction done of the whole run, [0, 1].
using ProgressFn = std::function<void(const std::string& stage, double fraction)>;

struct CalibrationOutcome {
  host::BacklashFit fit;
  double true_c_right_rad = 0;
  double true_c_left_rad = 0;
  double error_right_deg = 0;  // fitted − true
  double error_left_deg = 0;
  bool uploaded = false;  // accepted by ToFirmwareConfig and by the board, read back
  Calibration record;     // what was uploaded (when uploaded)
  std::string message;
  // θ_m, θ_j as the host received them: the board's angle telemetry (its
  // telemetry_angles_hz, 1 kHz by default), what the fit used (Fig. 7).
  std::vector<double> motor_rad;
  std::vector<double> joint_rad;
};

// The joint a calibration is for. Without a description, as `mjc calibrate` without
// --robot: the fit takes α = 1 and the record keeps the board's stiffness and joint
// zero. With one, as `mjc calibrate --robot`: α from the description (or fitted within
// ±20 % of it with fit_alpha), the description's stiffness and joint zero in the record
// (host::UseRobotAlpha, UseRobotJoint, JointZeroShift).
struct CalibrationJoint {
  const host::RobotDescription* robot = nullptr;
  bool fit_alpha = false;
};

// The paper's calibration sweep: 30° at 0.5 Hz over 10 cycles, 500 ms rests (the
// defaults of `mjc calibrate`).
RampedSineConfig PaperCalibrationSweep();

// `mjc calibrate` over the bus: reads the record in force, runs the increasing-amplitude
// sweep on the robot alone (the plant must have no interface) and keeps the board's
// angle telemetry, fits c_r, c_l (and the joint's lag) with NLopt, uploads the record
// over ISO-TP and reads it back. The board must be idle.
CalibrationOutcome RunCalibration(BusBoard& board, const RampedSineConfig& sweep,
                                  const CalibrationJoint& joint = {});

struct WindowOutcome {
  Motion motion = Motion::kFlexion;
  std::uint16_t repetition = 0;
  // Board estimate (J, %), as its window frames carried it. η is NaN where there is no
  // ratio to take (no loading work: the board's eta_valid clear; the same for truth).
  double load = 0, unload = 0, net = 0, eta = 0;
  // Plant ground truth over the same ticks.
  double truth_load = 0, truth_unload = 0, truth_net = 0, truth_eta = 0;
  // Power over the window, resampled to kProfilePoints (W), board and truth (Fig. 9):
  // both probed on the board's side.
  std::vector<double> profile;
  std::vector<double> truth_profile;
  double peak_fraction = 0;  // where the commanded peak falls in the window, [0, 1]
  // The board's fit of the attachment (interface_fit.h), as its WindowFit frames
  // carried it.
  bool fit_valid = false;
  double stiffness = 0, damping = 0, offset = 0,
         residual_rms = 0;  // N·m/rad, N·m·s/rad, N·m
  // The window's aligned ticks as indices into TrialOutcome::samples: [first, end).
  std::size_t first_sample = 0, end_sample = 0;
};

// One tick's aligned signals as the board's window tracker sees them: θ_j, θ̇_j and τ
// of the instant delay_ticks() back.
struct AlignedSample {
  Angle joint;
  AngularVelocity velocity;
  Torque torque;
};

struct TraceRow {
  double t, setpoint, motor, joint, torque, power, truth_power;
};

struct TrialOutcome {
  std::vector<WindowOutcome> windows;  // every completed window, in order
  // Probed on the board's side (the protocol carries neither at the tick rate):
  std::vector<TraceRow> trace;         // every 20th tick (500 Hz), when requested
  std::vector<AlignedSample> samples;  // every aligned tick from the trial's first, when
                                       // requested
  double power_rmse_W = 0;             // board vs truth power, aligned, over the cycles
  double truth_peak_power_W = 0;       // max |truth power| over the cycles
  std::uint32_t ticks = 0;             // from the trial's first tick to the host's end
  bool faulted = false;                // the trial did not complete (host::BoardTrial)
  std::string fault;
};

inline constexpr int kProfilePoints = 100;

// One sine trial to completion on a calibrated, idle board, as `mjc trial` runs it:
// configured (its TrialConfig: the rests in whole 100 ms), started and followed by
// host::RunBoardTrial on the bus's client; the windows are those that arrived.
TrialOutcome RunTrial(BusBoard& board, const SineConfig& sine, bool keep_trace,
                      bool keep_samples = false);

// The attachment's true stiffness and damping as a linear fit over a sinusoid of
// `frequency_hz` sees them: Kelvin–Voigt k and b; for the standard linear solid
// (k ∥ (k_2 in series with b)), the real part of its complex stiffness and the
// imaginary part over ω, with λ = b/k_2:
//   k_eff = k + k_2·(ωλ)²/(1 + (ωλ)²),   b_eff = b/(1 + (ωλ)²).
// The hand's side of the interface only: the joint's bearings (b_j) and inertia (J_j)
// also load the SEA and are not in these values.
struct InterfaceTruth {
  double stiffness = 0;  // N·m/rad
  double damping = 0;    // N·m·s/rad
};
InterfaceTruth TrueInterface(const plant::InterfaceParams& interface,
                             double frequency_hz);
// The drive frequency of PaperSine, Hz.
inline constexpr double kPaperFrequencyHz = 0.5;
// The drive frequencies the scenarios are checked at (tests/sim/frequency_test.cc):
// a human finger's flexion pace from slow to brisk. The board's velocity window
// (50 ms) and its power estimate's latency are fixed in the firmware, so a faster drive
// is a larger fraction of a cycle inside them; 2 Hz still keeps every fidelity bound.
inline constexpr double kMinDriveFrequencyHz = 0.25;
inline constexpr double kMaxDriveFrequencyHz = 2.0;

// The paper's trial: `repetitions` cycles of a sinusoid of `amplitude_deg` at
// `frequency_hz` about the neutral position, with 1.5 s rests before and after (back to
// back, the paper's 3 s between amplitudes; long enough for the joint to settle on the
// attachment at every frequency above: its time constant b/k is ~0.06 s).
SineConfig PaperSine(double amplitude_deg, std::uint16_t repetitions = 5,
                     double frequency_hz = kPaperFrequencyHz);

struct RepeatabilityOutcome {
  std::vector<TrialOutcome> trials;
  std::vector<host::Stats> eta;        // board, per trial (middle three flexions)
  std::vector<host::Stats> truth_eta;  // truth, per trial
  host::Stats overall;                 // board, all analysed flexions
  host::Stats truth_overall;
};

// Five trials of five repetitions at `amplitude_deg`, the interface re-donned (a seeded
// perturbation of `subject`) before each.
RepeatabilityOutcome RunRepeatability(BusBoard& board, const plant::PlantParams& subject,
                                      double amplitude_deg, std::uint64_t seed,
                                      const ProgressFn& progress, double progress_from,
                                      double progress_to,
                                      double frequency_hz = kPaperFrequencyHz);

struct AmplitudePoint {
  double amplitude_deg = 0;
  host::Stats load, unload, net, eta;                          // board
  host::Stats truth_load, truth_unload, truth_net, truth_eta;  // truth
  double power_rmse_pct_peak = 0;
  // The board's attachment fit over the analysed flexions it could fit.
  host::Stats stiffness, damping;
  std::vector<WindowOutcome> flexions;  // the analysed ones
};

// When a normalised error means something. The paper normalises Tables II–III's RMSE
// to the reference's range across amplitudes; a range the board cannot resolve (the
// net work of an elastic attachment: ~0 at every amplitude) turns any error into
// thousands of percent. A range counts only above the noise floor: twice the largest
// standard error of the board's per-amplitude means (a smaller difference between
// amplitudes is inside the board's own scatter), and at least kEnergyFloorOfLoading of
// the largest reference loading work (a variation smaller than that is, at the
// experiment's scale, none). Below it the NRMSE is NaN, and the tables print the range
// and the floor instead of a percentage. The same floor decides whether a window's η
// can be judged: η = 1 − |unloading|/loading of a loading work at or below it is the
// ratio of two noises.
inline constexpr double kEnergyFloorOfLoading = 0.01;
// The floor of `measured`'s board means against `reference`'s truth (J).
double EnergyNoiseFloor(const std::vector<AmplitudePoint>& measured,
                        const std::vector<AmplitudePoint>& reference);

struct SubjectSweep {
  std::string subject;
  std::vector<AmplitudePoint> points;
  // RMSE board vs truth across amplitudes (J), and normalised to the truth's range (%;
  // NaN when that range is within the noise: EnergyNoiseFloor).
  double rmse_load = 0, rmse_unload = 0, rmse_net = 0;
  double nrmse_load = 0, nrmse_unload = 0, nrmse_net = 0;
  double range_load = 0, range_unload = 0, range_net = 0;  // the truth's (J)
  double noise_floor_J = 0;
  InterfaceTruth truth;  // the subject's attachment (TrueInterface at frequency_hz)
  double frequency_hz = kPaperFrequencyHz;
};

// The amplitude sweep for one subject: each amplitude a five-repetition trial at
// `frequency_hz`.
SubjectSweep RunAmplitudeSweep(BusBoard& board, const plant::PlantParams& subject,
                               const std::vector<double>& amplitudes_deg,
                               const ProgressFn& progress, double progress_from,
                               double progress_to,
                               double frequency_hz = kPaperFrequencyHz);

// The statistics of the two functions above, from trials already run.
RepeatabilityOutcome SummariseRepeatability(std::vector<TrialOutcome> trials);
// `repetitions`: the trial's cycles, of which the middle three are analysed.
AmplitudePoint SummarisePoint(double amplitude_deg, const TrialOutcome& trial,
                              std::uint16_t repetitions = 5);
SubjectSweep SummariseSweep(const std::string& subject,
                            std::vector<AmplitudePoint> points);

// Experiment against model (the paper's Tables II–III): the attachment the board
// identified over a subject's sweep becomes a Kelvin–Voigt interface, the simulator
// runs the same sweep with it, and its plant's interface work (the prediction, as the
// paper's Simscape model measured it) is set beside the board's measurement.

// The mean of the board's attachment fits over a sweep's analysed flexions at
// `min_amplitude_deg` and above (the fits' own accuracy is judged at ≥ 11°: below, the
// joint swings too few encoder counts for θ̇_j; interface_fit_sim_test.cc).
struct IdentifiedAttachment {
  host::Stats stiffness, damping, offset;  // N·m/rad, N·m·s/rad, N·m
};
IdentifiedAttachment IdentifyAttachment(const SubjectSweep& sweep,
                                        double min_amplitude_deg = 11.0);

// The model's interface: k = k̄_i, b = b̄_i less the robot's own joint bearings (the
// SEA torque the board fits also turns the bearings, b_j, which the robot's model
// already has), τ_0 = τ̄_0 as the strap's preload.
plant::InterfaceParams ModelInterface(const IdentifiedAttachment& identified,
                                      const plant::PlantParams& robot);

struct ModelPoint {
  double amplitude_deg = 0;
  host::Stats load, unload, net;                           // the board's measurement (J)
  double model_load = 0, model_unload = 0, model_net = 0;  // the prediction (J)
};

struct ModelComparison {
  std::string subject;
  IdentifiedAttachment identified;
  plant::InterfaceParams model;
  std::vector<ModelPoint> points;
  // RMSE measurement vs prediction across amplitudes (J), and normalised to the
  // prediction's range (%), as the paper's Tables II and III (NaN when that range is
  // within the noise: EnergyNoiseFloor).
  double rmse_load = 0, rmse_unload = 0, rmse_net = 0;
  double nrmse_load = 0, nrmse_unload = 0, nrmse_net = 0;
  double range_load = 0, range_unload = 0, range_net = 0;  // the prediction's (J)
  double noise_floor_J = 0;
};

// `measured`: the board's sweep on the subject; `predicted`: the same amplitudes on the
// model interface, whose plant truth is the prediction. Throws std::invalid_argument
// when the two sweeps' amplitudes differ.
ModelComparison CompareWithModel(const SubjectSweep& measured,
                                 const SubjectSweep& predicted,
                                 const IdentifiedAttachment& identified,
                                 const plant::InterfaceParams& model);

// One trial on a board and bus of its own: the robot with `interface` donned and its
// sensor noise seeded by `noise_seed`, powered up at rest, given the calibration
// record over the bus (ISO-TP, as `mjc cal upload`), then
// RunTrial(PaperSine(amplitude_deg, 5, frequency_hz)).
struct TrialSpec {
  plant::InterfaceParams interface;
  double amplitude_deg = 25.0;
  bool keep_trace = false;
  std::uint64_t noise_seed = 1;
  std::string label;  // for progress lines
  double frequency_hz = kPaperFrequencyHz;
  // Cycles of the trial (PaperSine's repetitions).
  std::uint16_t repetitions = 5;
  // A plant and calibration record of the spec's own instead of RunTrials' `robot` and
  // `record` (a robot variant calibrated for itself); they must outlive RunTrials.
  const plant::PlantParams* robot = nullptr;
  const Calibration* record = nullptr;
};

// Runs every spec on `threads` threads (0: one per core; 1: in the calling thread).
// A trial depends on nothing but its spec, so the outcomes, in spec order, are the
// same bit for bit whatever the number of threads. `progress` is called once per
// finished trial, serialised, in the order they finish. Rethrows the first spec's
// exception, if any, after all have run. With a `joint` description, each board is
// sent its limits after the record (host::SendJointLimits, as `mjc trial --robot`
// sends them before anything moves); a board refusing them fails that spec.
// `finished`, when given, is called with each spec's index and outcome as it ends
// (before `progress`, serialised with it), so a caller can keep what ended even when a
// later spec fails or the process dies.
using TrialFinishedFn = std::function<void(std::size_t index, const TrialOutcome&)>;
std::vector<TrialOutcome> RunTrials(const plant::PlantParams& robot,
                                    const ControlConfig& config,
                                    const Calibration& record,
                                    const std::vector<TrialSpec>& specs, int threads,
                                    const ProgressFn& progress,
                                    const host::RobotDescription* joint = nullptr,
                                    const TrialFinishedFn& finished = nullptr);

}  // namespace mjc::sim
