#include "mjc/sim/scenarios.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <exception>
#include <mutex>
#include <numbers>
#include <stdexcept>
#include <thread>

#include "mjc/host/board_client.h"
#include "mjc/host/describe.h"

namespace mjc::sim {
namespace {

// Ticks the board keeps running after a trial ends, so that windows still inside the
// estimator's delay line complete.
std::uint32_t FlushTicks(const SimBoard& board) {
  return static_cast<std::uint32_t>(board.tick_hz() / 10);  // 100 ms > any delay
}

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

double EtaPercent(double load, double unload) {
  return load > 0 ? (1.0 - std::fabs(unload) / load) * 100.0 : 0.0;
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

CalibrationOutcome RunCalibration(SimBoard& board, const RampedSineConfig& sweep,
                                  const CalibrationJoint& joint_of) {
  CalibrationOutcome out;
  app::JointApp& app = board.app();
  const plant::CableParams& cable = board.plant().params().cable;
  out.true_c_right_rad = cable.c_right_rad;
  out.true_c_left_rad = cable.c_left_rad;
  if (app.StartCalibrationSweep(sweep).result != app::CommandOutcomeCode::kAccepted) {
    out.message = "the board refused the calibration sweep";
    return out;
  }
  std::vector<double> motor, joint;
  host::MotionEnd sweep_end(app::BoardState::kCalibrating);
  for (std::uint64_t i = 0; i < 100ull * board.tick_hz() * 60; ++i) {
    board.Tick();
    const Telemetry& t = app.last().telemetry;
    const bool over = sweep_end.Over(app.state());
    if (sweep_end.started()) {
      motor.push_back(t.motor.ToDouble());
      joint.push_back(t.joint.ToDouble());
      if (motor.size() % 10 == 0) {
        out.motor_rad.push_back(motor.back());
        out.joint_rad.push_back(joint.back());
      }
    }
    if (app.state() == app::BoardState::kFault) {
      out.message =
          "the sweep faulted: fault " + host::DescribeFault(app.control().fault());
      return out;
    }
    if (over) break;
  }
  // The joint trails the cable side by a few ms on the robot alone (the SEA spring
  // against the joint's damping): fit that lag too, or it reads as extra slack.
  host::BacklashFitOptions options;
  options.fit_lag = true;
  options.sample_rate_hz = board.tick_hz();
  const ControlConfig& board_config = app.control().config();
  if (joint_of.robot != nullptr) {
    host::UseRobotAlpha(*joint_of.robot, joint_of.fit_alpha, &options);
    const double shift =
        host::JointZeroShift(board_config.joint_encoder.zero_offset, *joint_of.robot);
    for (double& j : joint) j += shift;
  }
  out.fit = host::FitBacklash(motor, joint, options);
  out.error_right_deg =
      (out.fit.c_right_rad - out.true_c_right_rad) * 180.0 / std::numbers::pi;
  out.error_left_deg =
      (out.fit.c_left_rad - out.true_c_left_rad) * 180.0 / std::numbers::pi;
  std::string why;
  const auto config = host::ToFirmwareConfig(out.fit, &why);
  if (!config) {
    out.message = "calibration refused: " + why;
    return out;
  }
  // The backlash is what was fitted; stiffness and zero stay the board's unless the
  // joint's description gives them.
  protocol::CalibrationRecord record;
  record.backlash = *config;
  record.sea_stiffness = board_config.sea_stiffness;
  record.joint_zero_count = board_config.joint_encoder.zero_offset;
  if (joint_of.robot != nullptr) host::UseRobotJoint(*joint_of.robot, &record);
  out.record = {record.backlash, record.sea_stiffness, record.joint_zero_count};
  const app::CommandOutcome o = app.SetCalibration(out.record);
  board.Tick();
  out.uploaded = o.result == app::CommandOutcomeCode::kAccepted && app.calibrated();
  out.message = out.uploaded ? "uploaded" : "the board refused the calibration";
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

TrialOutcome RunTrial(SimBoard& board, const SineConfig& sine, bool keep_trace,
                      bool keep_samples) {
  TrialOutcome out;
  app::JointApp& app = board.app();
  const app::CommandOutcome o = app.StartTrial(sine);
  if (o.result != app::CommandOutcomeCode::kAccepted) {
    out.faulted = true;
    out.fault =
        "trial refused (result " + std::to_string(static_cast<int>(o.result)) + ")";
    return out;
  }
  app::AppEvent event;
  while (app.PopEvent(&event)) {
  }
  const std::uint32_t delay = app.control().delay_ticks();
  // Truth and board power by board tick, from the trial's first tick.
  const std::uint32_t base = app.last().telemetry.tick + 1;
  std::vector<double> truth_energy, truth_power, board_power;
  // The trial's length (two rests, the cycles) and the flush: no regrowth on the way.
  const double expected_s =
      2.0 * sine.rest_ms / 1000.0 + sine.repetitions / sine.frequency.ToDouble() + 0.2;
  const auto expected_ticks = static_cast<std::size_t>(expected_s * board.tick_hz());
  truth_energy.reserve(expected_ticks);
  truth_power.reserve(expected_ticks);
  board_power.reserve(expected_ticks);
  struct BoardWindow {
    WindowSummary w;
    InterfaceFit fit;
  };
  std::vector<BoardWindow> windows;
  std::vector<Angle> joints;  // the telemetry's θ_j by tick from `base`
  host::MotionEnd trial_end(app::BoardState::kRunning);
  std::uint32_t flush = 0;
  const std::uint64_t limit = static_cast<std::uint64_t>(board.tick_hz()) * 600;
  for (std::uint64_t i = 0; i < limit; ++i) {
    const plant::Plant& plant = board.plant();
    const double power_W = plant.interface_power_W();
    truth_energy.push_back(plant.interface_energy_J());
    truth_power.push_back(power_W);
    board.Tick();
    const TickResult& r = app.last();
    // The board's power refers to the instant `delay` ticks back.
    board_power.resize(truth_power.size(), 0.0);
    if (r.telemetry.tick >= base + delay) {
      board_power[r.telemetry.tick - delay - base] = r.telemetry.power.ToDouble();
    }
    if (keep_trace && i % 20 == 0) {
      out.trace.push_back({static_cast<double>(i) / board.tick_hz(),
                           r.telemetry.setpoint.ToDouble(), r.telemetry.motor.ToDouble(),
                           r.telemetry.joint.ToDouble(), r.telemetry.torque.ToDouble(),
                           r.telemetry.power.ToDouble(), power_W});
    }
    if (keep_samples && r.telemetry.tick >= base + delay) {
      // θ_j of the aligned instant is the telemetry's joint `delay` ticks back.
      const std::size_t at = r.telemetry.tick - delay - base;
      out.samples.resize(at + 1);
      out.samples[at].velocity = r.telemetry.joint_velocity;
      out.samples[at].torque = r.telemetry.aligned_torque;
    }
    if (keep_samples) joints.push_back(r.telemetry.joint);
    while (app.PopEvent(&event)) {
      if (event.kind == app::AppEvent::Kind::kWindow) {
        // The main loop's solve, from the sums the tick queued beside the event.
        InterfaceFitSums sums;
        InterfaceFit fit;
        if (app.PopWindowFit(event.window.start_tick, &sums))
          fit = SolveInterfaceFit(sums);
        windows.push_back({event.window, fit});
      }
      if (event.kind == app::AppEvent::Kind::kFault) {
        out.faulted = true;
        out.fault = "fault " + host::DescribeFault(event.fault);
      }
    }
    if (out.faulted) break;
    if (trial_end.Over(app.state()) && ++flush > FlushTicks(board)) break;
  }
  out.ticks = static_cast<std::uint32_t>(truth_power.size());
  for (std::size_t i = 0; i < out.samples.size() && i < joints.size(); ++i) {
    out.samples[i].joint = joints[i];
  }

  // Windows against truth over the same ticks; power error over the cycles.
  std::size_t first = truth_power.size(), last = 0;
  for (const BoardWindow& bw : windows) {
    const WindowSummary& w = bw.w;
    if (w.start_tick < base || w.end_tick - base > truth_energy.size()) continue;
    const std::size_t s = w.start_tick - base, p = w.peak_tick - base,
                      e = w.end_tick - base;
    if (e >= truth_energy.size()) continue;
    WindowOutcome wo;
    wo.motion = w.motion;
    wo.repetition = w.repetition;
    wo.load = w.loading.ToDouble();
    wo.unload = w.unloading.ToDouble();
    wo.net = w.net.ToDouble();
    wo.eta = w.eta_percent.ToDouble();
    wo.truth_load = truth_energy[p] - truth_energy[s];
    wo.truth_unload = truth_energy[e] - truth_energy[p];
    wo.truth_net = truth_energy[e] - truth_energy[s];
    wo.truth_eta = EtaPercent(wo.truth_load, wo.truth_unload);
    wo.profile = Resample(board_power, s, e);
    wo.truth_profile = Resample(truth_power, s, e);
    wo.peak_fraction = static_cast<double>(p - s) / static_cast<double>(e - s);
    const InterfaceFit& fit = bw.fit;
    wo.fit_valid = fit.valid();
    wo.stiffness = fit.stiffness.ToDouble();
    wo.damping = fit.damping.ToDouble();
    wo.offset = fit.offset.ToDouble();
    wo.residual_rms = fit.residual_rms.ToDouble();
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

RepeatabilityOutcome RunRepeatability(SimBoard& board, const plant::PlantParams& subject,
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

AmplitudePoint SummarisePoint(double amplitude_deg, const TrialOutcome& t) {
  AmplitudePoint pt;
  pt.amplitude_deg = amplitude_deg;
  std::vector<double> l, u, n, e, tl, tu, tn, te, k, b;
  for (const WindowOutcome* w : host::AnalysedFlexions(t.windows, 5)) {
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

SubjectSweep SummariseSweep(const std::string& subject,
                            std::vector<AmplitudePoint> points) {
  SubjectSweep out;
  out.subject = subject;
  std::vector<double> load, unload, net, tload, tunload, tnet;
  for (const AmplitudePoint& pt : points) {
    load.push_back(pt.load.mean);
    unload.push_back(pt.unload.mean);
    net.push_back(pt.net.mean);
    tload.push_back(pt.truth_load.mean);
    tunload.push_back(pt.truth_unload.mean);
    tnet.push_back(pt.truth_net.mean);
  }
  out.points = std::move(points);
  auto nrmse = [](const std::vector<double>& a, const std::vector<double>& b,
                  double* rmse) {
    *rmse = host::Rmse(a, b);
    const double range = host::Range(b);
    return range > 0 ? 100.0 * *rmse / range : 0.0;
  };
  out.nrmse_load = nrmse(load, tload, &out.rmse_load);
  out.nrmse_unload = nrmse(unload, tunload, &out.rmse_unload);
  out.nrmse_net = nrmse(net, tnet, &out.rmse_net);
  return out;
}

SubjectSweep RunAmplitudeSweep(SimBoard& board, const plant::PlantParams& subject,
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
  std::vector<double> load, unload, net, mload, munload, mnet;
  for (std::size_t i = 0; i < measured.points.size(); ++i) {
    const AmplitudePoint& m = measured.points[i];
    const AmplitudePoint& p = predicted.points[i];
    if (m.amplitude_deg != p.amplitude_deg) {
      throw std::invalid_argument("the model's sweep has other amplitudes");
    }
    out.points.push_back({m.amplitude_deg, m.load, m.unload, m.net, p.truth_load.mean,
                          p.truth_unload.mean, p.truth_net.mean});
    load.push_back(m.load.mean);
    unload.push_back(m.unload.mean);
    net.push_back(m.net.mean);
    mload.push_back(p.truth_load.mean);
    munload.push_back(p.truth_unload.mean);
    mnet.push_back(p.truth_net.mean);
  }
  const auto nrmse = [](const std::vector<double>& a, const std::vector<double>& b,
                        double* rmse) {
    *rmse = host::Rmse(a, b);
    const double range = host::Range(b);
    return range > 0 ? 100.0 * *rmse / range : 0.0;
  };
  out.nrmse_load = nrmse(load, mload, &out.rmse_load);
  out.nrmse_unload = nrmse(unload, munload, &out.rmse_unload);
  out.nrmse_net = nrmse(net, mnet, &out.rmse_net);
  return out;
}

std::vector<TrialOutcome> RunTrials(const plant::PlantParams& robot,
                                    const ControlConfig& config,
                                    const Calibration& record,
                                    const std::vector<TrialSpec>& specs, int threads,
                                    const ProgressFn& progress) {
  std::vector<TrialOutcome> out(specs.size());
  std::vector<std::exception_ptr> errors(specs.size());
  std::atomic<std::size_t> next{0};
  std::mutex progress_mutex;
  std::size_t done = 0;
  const auto work = [&] {
    for (std::size_t i = next++; i < specs.size(); i = next++) {
      const TrialSpec& spec = specs[i];
      try {
        plant::PlantParams params = robot;
        params.interface = spec.interface;
        params.sensors.noise_seed = spec.noise_seed;
        SimBoard board(params, config);
        board.app().SetCalibration(record);
        board.Tick();
        out[i] = RunTrial(board, PaperSine(spec.amplitude_deg, 5, spec.frequency_hz),
                          spec.keep_trace);
      } catch (...) {
        errors[i] = std::current_exception();
      }
      if (progress) {
        const std::lock_guard<std::mutex> lock(progress_mutex);
        ++done;
        progress(spec.label,
                 static_cast<double>(done) / static_cast<double>(specs.size()));
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
