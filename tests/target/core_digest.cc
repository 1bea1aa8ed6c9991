#include "core_digest.h"

#include <Eigen/Core>

#include "mjc/core/control_tick.h"
#include "mjc/core/fixed_eigen.h"
#include "mjc/core/quantities.h"
#include "mjc/core/wrapping.h"
#include "vector_test.h"

namespace mjc::test {
namespace {

class Fnv1a {
 public:
  template <class T>
  void Add(T value) {
    auto bits = static_cast<std::uint64_t>(value);
    for (unsigned i = 0; i < sizeof(T); ++i) {
      hash_ = (hash_ ^ (bits & 0xFFu)) * 0x100000001B3ull;
      bits >>= 8;
    }
  }
  std::uint64_t value() const { return hash_; }

 private:
  std::uint64_t hash_ = 0xCBF29CE484222325ull;
};

// The whole control tick over a sine trial and a fault: every telemetry field of every
// tick and every window summary. The sensor words come from integer arithmetic only
// (libm may differ between the host's and the target's C library; the core must not):
// the motor follows the setpoint, the joint a sixth of it, plus a count of noise. The
// cable's friction (0.1 N·m, 0.16 rad of the 0.63 N·m/rad spring) is below the spring
// torque of the larger swings, so the cable side also slides (backlash.h).
void HashControlTicks(Fnv1a& h, vt::Rng& rng, std::uint32_t ticks) {
  static ControlTick tick;
  ControlConfig config;
  config.backlash.c_right = Angle::FromDouble(0.0175);
  config.backlash.c_left = Angle::FromDouble(-0.0175);
  config.backlash.cable_friction = Torque::FromDouble(0.1);
  tick.Configure(config);
  tick.Arm(true);
  SineConfig sine;
  sine.amplitude = Angle::FromDouble(0.4363);
  sine.frequency = Frequency::FromDouble(2.0);
  sine.repetitions = 5;
  sine.rest_ms = 100;
  Angle setpoint;
  TickResult r;
  for (std::uint32_t i = 0; i < ticks; ++i) {
    if (i == 5) h.Add(static_cast<std::uint8_t>(tick.trajectory().StartSine(sine)));
    Sample s;
    const std::int32_t noise = static_cast<std::int32_t>(rng.Next() % 3u) - 1;
    s.motor_count = static_cast<std::uint16_t>((setpoint.raw() / 515 + noise) & 0xFFFF);
    const std::int32_t joint = setpoint.raw() / 6434 / 6 + noise;
    s.joint_frame = EncodeJointFrame(static_cast<std::uint16_t>(joint & 0x3FFF), false);
    if (i == ticks - 200) s.joint_frame ^= 0x0001u;  // a parity fault near the end
    tick.ISR_Step(s, &r);
    setpoint = r.telemetry.setpoint;
    const Telemetry& t = r.telemetry;
    h.Add(t.motor.raw());
    h.Add(t.joint.raw());
    h.Add(t.cable_side.raw());
    h.Add(t.torque.raw());
    h.Add(t.setpoint.raw());
    h.Add(t.duty.raw());
    h.Add(t.joint_velocity.raw());
    h.Add(t.aligned_torque.raw());
    h.Add(t.power.raw());
    h.Add(t.energy_sum);
    h.Add(static_cast<std::uint8_t>(t.segment));
    h.Add(static_cast<std::uint16_t>(t.fault));
    h.Add(static_cast<std::uint8_t>(r.actuation.bridge_enabled));
    if (r.window_completed) {
      const WindowSummary& w = r.window;
      h.Add(w.start_tick);
      h.Add(w.peak_tick);
      h.Add(w.end_tick);
      h.Add(w.loading.raw());
      h.Add(w.unloading.raw());
      h.Add(w.net.raw());
      h.Add(w.positive_work.raw());
      h.Add(w.negative_work.raw());
      h.Add(w.eta_percent.raw());
      h.Add(w.peak_power.raw());
      h.Add(w.peak_torque.raw());
      // The window's fit sums: their 96-bit adds take another path on the Cortex-M4.
      const InterfaceFitSums& f = r.window_fit;
      h.Add(f.count);
      h.Add(f.theta);
      h.Add(f.omega);
      h.Add(f.tau);
      for (const Wide96* sum : {&f.theta_theta, &f.theta_omega, &f.omega_omega,
                                &f.theta_tau, &f.omega_tau, &f.tau_tau}) {
        h.Add(sum->high());
        h.Add(sum->low());
      }
    }
  }
}

}  // namespace

std::uint64_t CoreDigest(std::uint32_t steps) {
  vt::Rng rng(0x4D4A43);  // "MJC"
  Fnv1a h;
  Eigen::Matrix<Coefficient, 3, 3> a;
  Eigen::Matrix<Angle, 3, 1> x = Eigen::Matrix<Angle, 3, 1>::Zero();
  std::uint16_t counter = 0;
  std::int64_t extended = 0;
  for (std::uint32_t i = 0; i < steps; ++i) {
    // Shift by a random amount so magnitudes span the whole range, edges included.
    const auto shift = [&rng] { return static_cast<int>(rng.Next() % 32u); };
    const auto tq = Torque::FromRaw(rng.NextI32() >> shift());
    const auto w = AngularVelocity::FromRaw(rng.NextI32() >> shift());
    const auto k = Stiffness::FromRaw(rng.NextI32() >> shift());
    const auto th = Angle::FromRaw(rng.NextI32() >> shift());
    const auto th2 = Angle::FromRaw(rng.NextI32() >> shift());
    const auto d = Duty::FromRaw(rng.NextI16());

    h.Add(Mul<Power>(tq, w).raw());
    h.Add(Mul<Torque>(k, th - th2).raw());
    h.Add((th + th2).raw());
    h.Add((th - th2).raw());
    h.Add((-th).raw());
    h.Add(Abs(th2).raw());
    h.Add(FixedCast<Fixed<Radian, 10>>(th).raw());
    h.Add(FixedCast<Fixed<Radian, 28>>(th).raw());
    h.Add(Divide<Ratio>(th, th2).raw());
    h.Add(Mul<Duty>(d, d).raw());
    h.Add((tq * static_cast<int>(rng.NextI16())).raw());

    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) a(r, c) = Coefficient::FromRaw(rng.NextI32() >> 2);
    }
    x(static_cast<Eigen::Index>(i % 3u)) = th;
    x = a.lazyProduct(x).cast<Angle>();
    for (int r = 0; r < 3; ++r) h.Add(x(r).raw());

    counter = WrappingAdd(counter, static_cast<std::uint16_t>(rng.Next() & 0x7FFFu));
    extended += WrappingDelta(counter, static_cast<std::uint16_t>(extended & 0xFFFF));
    h.Add(extended);
  }
  // 2.5 s of 2 Hz sine trial plus rests, at 10 kHz.
  HashControlTicks(h, rng, 28000);
  return h.value();
}

}  // namespace mjc::test
