#include "mjc/sim/scenarios.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <exception>
#include <limits>
#include <mutex>
#include <numbers>
#include <stdexcept>
#include <string>
#include <thread>

#include "mjc/host/board_client.h"
#include "mjc/host/calibration_io.h"
#include "mjc/host/describe.h"
#include "mjc/host/joint_limits.h"
#include "mjc/host/trial_runner.h"

namespace mjc::sim {
namespace {

std::vector<double> Resample(const std::vector<double>& values, std::size_t begin,
                             std::size_t end) {
  std::vector<double> out(kProfilePoints, 0.0);
  if (end <= begin + 1) return out;
  for (int i = 0; i < kProfilePoints; ++i) {
    const double span = static_cast<double>(end - 1 - begin);
    const double x = static_cast<double>(begin) + span * (i / double{kProfilePoints - 1});
    const auto k = static_cast<std::size_t>(x);
    const double f = x - static_cast<double>(k);
    const double a = values[k];
    const double b = values[std::min(k + 1, end - 1)];
    out[static_cast<std::size_t>(i)] = a + f * (b - a);
  }
  return out;
}

// `record` onto the board over the bus, as `mjc cal upload` sends it (ISO-TP), the
// board identified first as the tools do; throws unless the board accepts it.
void Upload(BusBoard& bus, const Calibration& record) {
  std::string why;
  host::WaitEnd end{};
  if (!bus.client().Identify(&end, &why)) {
    throw std::runtime_error("the board was not identified: " + why);
  }
  protocol::CalibrationRecord r;
  r.backlash = record.backlash;
  r.sea_stiffness = record.sea_stiffness;
  r.joint_zero_count = record.joint_zero_count;
  const auto isotp = bus.Connect();
  const host::UploadOutcome sent =
      host::UploadCalibration(bus.client(), *isotp, r, 1000, &why);
  if (sent.status != host::UploadStatus::kAnswered) {
    throw std::runtime_error("the calibration upload was not answered: " + why);
  }
  if (sent.result != protocol::CalibrationResult::kAccepted) {
    throw std::runtime_error("the board refused the calibration: " +
                             host::DescribeCalibrationResult(sent.result, sent.detail));
  }
}

// A trial's or sweep's frequency, repetitions and rests as the wire carries them (the
// inverse of the CAN node's Oscillation): mHz, 100 ms.
template <class Core, class Wire>
void SetWireTiming(const Core& core, Wire* wire) {
  wire->frequency_mHz =
      static_cast<std::uint16_t>(std::lround(core.frequency.ToDouble() * 1000));
  wire->repetitions = static_cast<std::uint8_t>(core.repetitions);
  wire->rest_100ms = static_cast<std::uint8_t>(core.rest_ms / 100);
}

// RMSE of `measured` against `reference` (into *rmse), and normalised to the
// reference's range (into *range), % (the paper's NRMSE): NaN when the range is at or
// below `floor` (EnergyNoiseFloor).
double Nrmse(const std::vector<double>& measured, const std::vector<double>& reference,
             double floor, double* rmse, double* range) {
  *rmse = host::Rmse(measured, reference);
  *range = host::Range(reference);
  return *range > floor ? 100.0 * *rmse / *range
                        : std::numeric_limits<double>::quiet_NaN();
}

// Tables II–III's errors across amplitudes, into *out's rmse_* (J), nrmse_* (%),
// range_* (J) and noise_floor_J: the board's mean loading, unloading and net work at
// each amplitude of `measured` against the truth at the same amplitude of `reference`
// (the board's own sweep, for its errors against the plant, or the model's predicted
// sweep).
template <class Errors>
void SetEnergyErrors(const std::vector<AmplitudePoint>& measured,
                     const std::vector<AmplitudePoint>& reference, Errors* out) {
  std::vector<double> load, unload, net, ref_load, ref_unload, ref_net;
  for (std::size_t i = 0; i < measured.size(); ++i) {
    load.push_back(measured[i].load.mean);
    unload.push_back(measured[i].unload.mean);
    net.push_back(measured[i].net.mean);
    ref_load.push_back(reference[i].truth_load.mean);
    ref_unload.push_back(reference[i].truth_unload.mean);
    ref_net.push_back(reference[i].truth_net.mean);
  }
  const double floor = EnergyNoiseFloor(measured, reference);
  out->noise_floor_J = floor;
  out->nrmse_load = Nrmse(load, ref_load, floor, &out->rmse_load, &out->range_load);
  out->nrmse_unload =
      Nrmse(unload, ref_unload, floor, &out->rmse_unload, &out->range_unload);
  out->nrmse_net = Nrmse(net, ref_net, floor, &out->rmse_net, &out->range_net);
}

// NaN without loading work: no ratio to take.
double EtaPercent(double load, double unload) {
  return load > 0 ? (1.0 - std::fabs(unload) / load) * 100.0
                  : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace

SineConfig PaperSine(double amplitude_deg, std::uint16_t repetitions,
                     double frequency_hz) {
  SineConfig s;
  s.amplitude = Angle::Quantize(amplitude_deg * std::numbers::pi / 180.0);
  s.frequency = Frequency::Quantize(frequency_hz);
  s.repetitions = repetitions;
  s.rest_ms = 1500;  // back to back: the paper's 3 s between amplitudes
  return s;
}

RampedSineConfig PaperCalibrationSweep() {
  RampedSineConfig s;
  s.end_amplitude = Angle::Quantize(30.0 * std::numbers::pi / 180.0);
  s.frequency = Frequency::FromDouble(0.5);
  s.repetitions = 10;
  s.rest_ms = 500;
  return s;
}

CalibrationOutcome RunCalibration(BusBoard& bus, const RampedSineConfig& sweep,
                                  const CalibrationJoint& joint_of) {
  // As `mjc calibrate` (host_tools/mjc/calibrate.cc) over the bus, with the host
  // library's functions: the sweep run and fitted (host::RunSweep: the record in force
  // read, the sweep configured and started, the board's angle telemetry kept until it
  // is idle again, the fit), the upload over ISO-TP, the record read back.
  CalibrationOutcome out;
  const plant::CableParams& cable = bus.plant().params().cable;
  out.true_c_right_rad = cable.c_right_rad;
  out.true_c_left_rad = cable.c_left_rad;
  protocol::SweepConfig config;
  config.end_amplitude = sweep.end_amplitude;
  SetWireTiming(sweep, &config);
  host::BoardClient& client = bus.client();
  // No fitted_at in the record: a simulated run has no date, and its outputs are the
  // same every run.
  host::SweepRun run = host::RunSweep(client, config, joint_of.robot, joint_of.fit_alpha);
  // Fig. 7: θ_m, θ_j as the host received them.
  out.motor_rad = std::move(run.samples.motor_rad);
  out.joint_rad = std::move(run.samples.joint_rad);
  if (run.fitted) {
    out.fit = run.fitted->fit;
    out.error_right_deg =
        (out.fit.c_right_rad - out.true_c_right_rad) * 180.0 / std::numbers::pi;
    out.error_left_deg =
        (out.fit.c_left_rad - out.true_c_left_rad) * 180.0 / std::numbers::pi;
  }
  if (!run.error.empty()) {
    out.message = run.error;
    return out;
  }
  std::string why;
  const protocol::CalibrationRecord& record = *run.fitted->record;
  out.record = {record.backlash, record.sea_stiffness, record.joint_zero_count};
  const auto isotp = bus.Connect();
  const host::UploadOutcome sent =
      host::UploadCalibration(client, *isotp, record, 1000, &why);
  if (sent.status != host::UploadStatus::kAnswered) {
    out.message = "the upload was not answered: " + why;
    return out;
  }
  if (sent.result != protocol::CalibrationResult::kAccepted) {
    out.message = "the board refused the calibration: " +
                  host::DescribeCalibrationResult(sent.result, sent.detail);
    return out;
  }
  // Read back: the board must hold exactly what was sent.
  const auto back = host::ReadCalibration(client, &why);
  out.uploaded = back && back->calibrated && back->record.backlash == record.backlash &&
                 back->record.sea_stiffness == record.sea_stiffness &&
                 back->record.joint_zero_count == record.joint_zero_count;
  out.message = out.uploaded ? "uploaded" : "the board holds another calibration";
  return out;
}

InterfaceTruth TrueInterface(const plant::InterfaceParams& interface,
                             double frequency_hz) {
  if (!interface.present) return {};
  if (interface.model == plant::InterfaceModel::kKelvinVoigt) {
    return {interface.stiffness_Nm_per_rad, interface.damping_Nm_s_per_rad};
  }
  const double k2 = interface.maxwell_stiffness_Nm_per_rad;
  if (k2 <= 0) return {interface.stiffness_Nm_per_rad, 0.0};
  const double x =
      2 * std::numbers::pi * frequency_hz * interface.damping_Nm_s_per_rad / k2;
  return {interface.stiffness_Nm_per_rad + k2 * x * x / (1 + x * x),
          interface.damping_Nm_s_per_rad / (1 + x * x)};
}

TrialOutcome RunTrial(BusBoard& bus, const SineConfig& sine, bool keep_trace,
                      bool keep_samples) {
  TrialOutcome out;
  // The probe, on the board's side of the bus, from the trial's first tick (the one
  // that takes the start): the plant's truth at the instant each tick samples, and
  // what the protocol does not carry at the tick rate (the board's power, its aligned
  // samples, the trace).
  const std::uint32_t delay = bus.app().control().delay_ticks();
  const double tick_hz = bus.tick_hz();
  std::vector<double> truth_energy, truth_power, board_power;
  const double expected_s =
      2.0 * sine.rest_ms / 1000.0 + sine.repetitions / sine.frequency.ToDouble() + 0.2;
  const auto expected_ticks = static_cast<std::size_t>(expected_s * tick_hz);
  truth_energy.reserve(expected_ticks);
  truth_power.reserve(expected_ticks);
  board_power.reserve(expected_ticks);
  std::vector<Angle> joints;  // the telemetry's θ_j by tick from `base`
  bool recording = false;
  std::uint32_t base = 0;
  double energy_before = 0, power_before = 0;
  bus.SetBeforeTick([&](SimBoard& board) {
    energy_before = board.plant().interface_energy_J();
    power_before = board.plant().interface_power_W();
  });
  bus.SetAfterTick([&](SimBoard& board) {
    const TickResult& r = board.app().last();
    if (!recording) {
      if (board.app().state() != app::BoardState::kRunning) return;
      recording = true;
      base = r.telemetry.tick;
    }
    const std::size_t i = truth_power.size();
    truth_energy.push_back(energy_before);
    truth_power.push_back(power_before);
    // The board's power refers to the instant `delay` ticks back (0 until known).
    board_power.push_back(0.0);
    if (r.telemetry.tick >= base + delay) {
      board_power[r.telemetry.tick - delay - base] = r.telemetry.power.ToDouble();
    }
    if (keep_trace && i % 20 == 0) {
      out.trace.push_back({static_cast<double>(i) / tick_hz,
                           r.telemetry.setpoint.ToDouble(), r.telemetry.motor.ToDouble(),
                           r.telemetry.joint.ToDouble(), r.telemetry.torque.ToDouble(),
                           r.telemetry.power.ToDouble(), power_before});
    }
    if (keep_samples) {
      if (r.telemetry.tick >= base + delay) {
        // θ_j of the aligned instant is the telemetry's joint `delay` ticks back.
        const std::size_t at = r.telemetry.tick - delay - base;
        out.samples.resize(at + 1);
        out.samples[at].velocity = r.telemetry.joint_velocity;
        out.samples[at].torque = r.telemetry.aligned_torque;
      }
      joints.push_back(r.telemetry.joint);
    }
  });

  // The host's side, as `mjc trial`: the trial configured, started and followed by
  // host::RunBoardTrial, its windows as they arrived over the bus.
  protocol::TrialConfig config;
  config.amplitude = sine.amplitude;
  SetWireTiming(sine, &config);
  const host::BoardTrial trial = host::RunBoardTrial(bus.client(), config, nullptr);
  bus.SetBeforeTick(nullptr);
  bus.SetAfterTick(nullptr);
  if (!trial.completed) {
    out.faulted = true;
    out.fault = trial.error;
  }
  out.ticks = static_cast<std::uint32_t>(truth_power.size());
  for (std::size_t i = 0; i < out.samples.size() && i < joints.size(); ++i) {
    out.samples[i].joint = joints[i];
  }

  // Windows against truth over the same ticks; power error over the cycles.
  std::size_t first = truth_power.size(), last = 0;
  for (const host::BoardWindow& w : trial.windows) {
    if (!recording || w.start_tick < base || w.end_tick - base > truth_energy.size()) {
      continue;
    }
    const std::size_t s = w.start_tick - base, p = w.peak_tick - base,
                      e = w.end_tick - base;
    if (e >= truth_energy.size()) continue;
    WindowOutcome wo;
    wo.motion = w.motion;
    wo.repetition = w.repetition;
    wo.load = w.loading_J;
    wo.unload = w.unloading_J;
    wo.net = w.net_J();
    // The board says when its η means nothing (no loading work to divide by).
    wo.eta = w.eta_valid ? w.eta_percent : std::numeric_limits<double>::quiet_NaN();
    wo.truth_load = truth_energy[p] - truth_energy[s];
    wo.truth_unload = truth_energy[e] - truth_energy[p];
    wo.truth_net = truth_energy[e] - truth_energy[s];
    wo.truth_eta = EtaPercent(wo.truth_load, wo.truth_unload);
    wo.profile = Resample(board_power, s, e);
    wo.truth_profile = Resample(truth_power, s, e);
    wo.peak_fraction = static_cast<double>(p - s) / static_cast<double>(e - s);
    wo.fit_valid = w.fit_valid;
    wo.stiffness = w.stiffness_Nm_rad;
    wo.damping = w.damping_Nms_rad;
    wo.offset = w.offset_Nm;
    wo.residual_rms = w.residual_rms_Nm;
    wo.first_sample = s;
    wo.end_sample = e;
    out.windows.push_back(std::move(wo));
    first = std::min(first, s);
    last = std::max(last, e);
  }
  if (last > first) {
    double ss = 0, peak = 0;
    for (std::size_t k = first; k < last; ++k) {
      const double d = board_power[k] - truth_power[k];
      ss += d * d;
      peak = std::max(peak, std::fabs(truth_power[k]));
    }
    out.power_rmse_W = std::sqrt(ss / static_cast<double>(last - first));
    out.truth_peak_power_W = peak;
  }
  return out;
}

RepeatabilityOutcome SummariseRepeatability(std::vector<TrialOutcome> trials) {
  RepeatabilityOutcome out;
  std::vector<double> all, all_truth;
  for (TrialOutcome& t : trials) {
    std::vector<double> eta, truth_eta;
    for (const WindowOutcome* w : host::AnalysedFlexions(t.windows, 5)) {
      eta.push_back(w->eta);
      truth_eta.push_back(w->truth_eta);
      all.push_back(w->eta);
      all_truth.push_back(w->truth_eta);
    }
    out.eta.push_back(host::Describe(eta));
    out.truth_eta.push_back(host::Describe(truth_eta));
    out.trials.push_back(std::move(t));
  }
  out.overall = host::Describe(all);
  out.truth_overall = host::Describe(all_truth);
  return out;
}

RepeatabilityOutcome RunRepeatability(BusBoard& board, const plant::PlantParams& subject,
                                      double amplitude_deg, std::uint64_t seed,
                                      const ProgressFn& progress, double progress_from,
                                      double progress_to, double frequency_hz) {
  std::vector<TrialOutcome> trials;
  const int kTrials = 5;
  for (int trial = 0; trial < kTrials; ++trial) {
    if (progress) {
      progress("repeatability: trial " + std::to_string(trial + 1) + "/5",
               progress_from + (progress_to - progress_from) * trial / kTrials);
    }
    // Re-don: a new seeded perturbation of the subject's interface.
    board.plant().SetInterface(
        plant::Redon(subject, seed + static_cast<std::uint64_t>(trial)).interface);
    trials.push_back(
        RunTrial(board, PaperSine(amplitude_deg, 5, frequency_hz), trial == 0));
  }
  return SummariseRepeatability(std::move(trials));
}

AmplitudePoint SummarisePoint(double amplitude_deg, const TrialOutcome& t,
                              std::uint16_t repetitions) {
  AmplitudePoint pt;
  pt.amplitude_deg = amplitude_deg;
  std::vector<double> l, u, n, e, tl, tu, tn, te, k, b;
  for (const WindowOutcome* w : host::AnalysedFlexions(t.windows, repetitions)) {
    l.push_back(w->load);
    u.push_back(w->unload);
    n.push_back(w->net);
    e.push_back(w->eta);
    tl.push_back(w->truth_load);
    tu.push_back(w->truth_unload);
    tn.push_back(w->truth_net);
    te.push_back(w->truth_eta);
    if (w->fit_valid) {
      k.push_back(w->stiffness);
      b.push_back(w->damping);
    }
    pt.flexions.push_back(*w);
  }
  pt.load = host::Describe(l);
  pt.unload = host::Describe(u);
  pt.net = host::Describe(n);
  pt.eta = host::Describe(e);
  pt.truth_load = host::Describe(tl);
  pt.truth_unload = host::Describe(tu);
  pt.truth_net = host::Describe(tn);
  pt.truth_eta = host::Describe(te);
  pt.stiffness = host::Describe(k);
  pt.damping = host::Describe(b);
  pt.power_rmse_pct_peak =
      t.truth_peak_power_W > 0 ? 100.0 * t.power_rmse_W / t.truth_peak_power_W : 0.0;
  return pt;
}

double EnergyNoiseFloor(const std::vector<AmplitudePoint>& measured,
                        const std::vector<AmplitudePoint>& reference) {
  double floor = 0;
  for (const AmplitudePoint& p : measured) {
    floor = std::max({floor, 2 * p.load.se, 2 * p.unload.se, 2 * p.net.se});
  }
  for (const AmplitudePoint& p : reference) {
    floor = std::max(floor, kEnergyFloorOfLoading * std::fabs(p.truth_load.mean));
  }
  return floor;
}

SubjectSweep SummariseSweep(const std::string& subject,
                            std::vector<AmplitudePoint> points) {
  SubjectSweep out;
  out.subject = subject;
  out.points = std::move(points);
  SetEnergyErrors(out.points, out.points, &out);
  return out;
}

SubjectSweep RunAmplitudeSweep(BusBoard& board, const plant::PlantParams& subject,
                               const std::vector<double>& amplitudes_deg,
                               const ProgressFn& progress, double progress_from,
                               double progress_to, double frequency_hz) {
  board.plant().SetInterface(subject.interface);
  std::vector<AmplitudePoint> points;
  for (std::size_t i = 0; i < amplitudes_deg.size(); ++i) {
    const double a = amplitudes_deg[i];
    if (progress) {
      progress("amplitude sweep: " + subject.name + " " +
                   std::to_string(static_cast<int>(a)) + "°",
               progress_from + (progress_to - progress_from) * static_cast<double>(i) /
                                   static_cast<double>(amplitudes_deg.size()));
    }
    points.push_back(
        SummarisePoint(a, RunTrial(board, PaperSine(a, 5, frequency_hz), false)));
  }
  SubjectSweep out = SummariseSweep(subject.name, std::move(points));
  out.truth = TrueInterface(subject.interface, frequency_hz);
  out.frequency_hz = frequency_hz;
  return out;
}

IdentifiedAttachment IdentifyAttachment(const SubjectSweep& sweep,
                                        double min_amplitude_deg) {
  std::vector<double> k, b, offset;
  for (const AmplitudePoint& p : sweep.points) {
    if (p.amplitude_deg < min_amplitude_deg) continue;
    for (const WindowOutcome& w : p.flexions) {
      if (!w.fit_valid) continue;
      k.push_back(w.stiffness);
      b.push_back(w.damping);
      offset.push_back(w.offset);
    }
  }
  return {host::Describe(k), host::Describe(b), host::Describe(offset)};
}

plant::InterfaceParams ModelInterface(const IdentifiedAttachment& identified,
                                      const plant::PlantParams& robot) {
  if (identified.stiffness.n == 0) {
    throw std::invalid_argument(
        "no attachment fit to build a model from: no valid fit at the amplitudes used");
  }
  plant::InterfaceParams i;
  i.present = true;
  i.model = plant::InterfaceModel::kKelvinVoigt;
  i.stiffness_Nm_per_rad = std::max(identified.stiffness.mean, 0.0);
  i.damping_Nm_s_per_rad =
      std::max(identified.damping.mean - robot.joint.viscous_Nm_s_per_rad, 0.0);
  i.preload_Nm = identified.offset.mean;
  return i;
}

ModelComparison CompareWithModel(const SubjectSweep& measured,
                                 const SubjectSweep& predicted,
                                 const IdentifiedAttachment& identified,
                                 const plant::InterfaceParams& model) {
  if (measured.points.size() != predicted.points.size()) {
    throw std::invalid_argument("the model's sweep has other amplitudes");
  }
  ModelComparison out;
  out.subject = measured.subject;
  out.identified = identified;
  out.model = model;
  for (std::size_t i = 0; i < measured.points.size(); ++i) {
    const AmplitudePoint& m = measured.points[i];
    const AmplitudePoint& p = predicted.points[i];
    if (m.amplitude_deg != p.amplitude_deg) {
      throw std::invalid_argument("the model's sweep has other amplitudes");
    }
    out.points.push_back({m.amplitude_deg, m.load, m.unload, m.net, p.truth_load.mean,
                          p.truth_unload.mean, p.truth_net.mean});
  }
  SetEnergyErrors(measured.points, predicted.points, &out);
  return out;
}

std::vector<TrialOutcome> RunTrials(const plant::PlantParams& robot,
                                    const ControlConfig& config,
                                    const Calibration& record,
                                    const std::vector<TrialSpec>& specs, int threads,
                                    const ProgressFn& progress,
                                    const host::RobotDescription* joint,
                                    const TrialFinishedFn& finished) {
  std::vector<TrialOutcome> out(specs.size());
  std::vector<std::exception_ptr> errors(specs.size());
  std::atomic<std::size_t> next{0};
  std::mutex progress_mutex;
  std::size_t done = 0;
  const auto work = [&] {
    for (std::size_t i = next++; i < specs.size(); i = next++) {
      const TrialSpec& spec = specs[i];
      try {
        plant::PlantParams params = spec.robot ? *spec.robot : robot;
        params.interface = spec.interface;
        params.sensors.noise_seed = spec.noise_seed;
        // A board powered up at rest, given the record the sweep made as `mjc cal
        // upload` gives it.
        BusBoard board(params, config);
        Upload(board, spec.record ? *spec.record : record);
        if (joint) {
          const host::ParamWriteOutcome limits =
              host::SendJointLimits(board.client(), *joint, 500);
          if (limits.end != host::ParamWriteEnd::kDone) {
            throw std::runtime_error("sending " + joint->name +
                                     "'s limits: " + limits.why);
          }
        }
        out[i] = RunTrial(
            board, PaperSine(spec.amplitude_deg, spec.repetitions, spec.frequency_hz),
            spec.keep_trace);
      } catch (...) {
        errors[i] = std::current_exception();
      }
      if (progress || finished) {
        const std::lock_guard<std::mutex> lock(progress_mutex);
        ++done;
        if (finished && !errors[i]) {
          try {
            finished(i, out[i]);
          } catch (...) {
            errors[i] = std::current_exception();
          }
        }
        if (progress) {
          progress(spec.label,
                   static_cast<double>(done) / static_cast<double>(specs.size()));
        }
      }
    }
  };
  if (threads <= 0) threads = static_cast<int>(std::thread::hardware_concurrency());
  const std::size_t workers =
      std::clamp<std::size_t>(static_cast<std::size_t>(std::max(threads, 1)), 1,
                              std::max<std::size_t>(specs.size(), 1));
  if (workers == 1) {
    work();
  } else {
    std::vector<std::thread> pool;
    for (std::size_t w = 0; w < workers; ++w) pool.emplace_back(work);
    for (std::thread& t : pool) t.join();
  }
  // The first failure in spec order, whatever the order the runs ended in.
  for (const std::exception_ptr& e : errors) {
    if (e) std::rethrow_exception(e);
  }
  return out;
}

}  // namespace mjc::sim
