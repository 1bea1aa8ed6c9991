// The fixed-point signal chain against a double-precision implementation of the same
// equations on the same inputs, over one hour at 10 kHz (36 million ticks): a lossy
// (Kelvin–Voigt) interface driven at 0.5 Hz through 2° of cable slack, sensed by a
// 14-bit joint encoder and a 2048-count, 100:1 motor encoder.
//
// Prints, for ./bench:
//   energy_rel_error_1h: |E_fixed − E_double| / |E_double| of the net interface energy
//   positive_work_rel_error_1h: the same for the positive work Σ max(P, 0)·dt
//   power_max_err_lsb: the largest per-tick |P_fixed − P_double| in Power LSBs
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <vector>

#include "delay_line.h"
#include "mjc/core/backlash.h"
#include "mjc/core/encoder.h"
#include "mjc/core/interface_energy.h"
#include "mjc/core/velocity_estimator.h"

namespace {

using namespace mjc;
constexpr int kTickHz = 10000;
constexpr std::int64_t kTicks = 3600LL * kTickHz;

// Double-precision chain: the play operator, the least-squares slope in closed form
// num/D·f from running sums S0 = Σx, S1 = Σ i·x (exact in double: the inputs are
// multiples of 2^-24 and the sums stay far below 2^53 LSB), torque delayed by the same
// (N−1)/2 ticks, power as a double product.
struct ReferenceChain {
  double alpha, c_r, c_l, k_sea, out = 0;
  int n;
  std::vector<double> window;
  std::vector<double> torques;
  std::size_t head = 0, thead = 0;
  double s0 = 0, s1 = 0;
  ReferenceChain(double a, double cr, double cl, double k, int window_ticks)
      : alpha(a),
        c_r(cr),
        c_l(cl),
        k_sea(k),
        n(window_ticks),
        window(static_cast<std::size_t>(window_ticks), 0.0),
        torques(static_cast<std::size_t>(window_ticks / 2), 0.0) {}
  double Step(double motor, double joint) {
    const double lo = alpha * (motor - c_r), hi = alpha * (motor - c_l);
    out = out < lo ? lo : (out > hi ? hi : out);
    const double tau = k_sea * (out - joint);
    const double oldest = window[head];
    window[head] = joint;
    head = (head + 1) % window.size();
    s1 = s1 - s0 + oldest + (n - 1) * joint;
    s0 = s0 - oldest + joint;
    const double d = n * (double(n) * n - 1) / 12.0;
    const double velocity = (s1 - (n - 1) / 2.0 * s0) / d * kTickHz;
    const double aligned = torques[thead];
    torques[thead] = tau;
    thead = (thead + 1) % torques.size();
    return aligned * velocity;
  }
};

}  // namespace

int main(int argc, char** argv) {
  // A shorter run for a quick look: chain_accuracy <seconds>.
  const std::int64_t ticks = argc > 1 ? std::atoll(argv[1]) * kTickHz : kTicks;
  BacklashConfig bc;
  bc.alpha = Scale::Quantize(1.0);
  bc.c_right = Angle::Quantize(1.0 * std::numbers::pi / 180);
  bc.c_left = Angle::Quantize(-1.0 * std::numbers::pi / 180);
  BacklashModel::State bs;
  BacklashModel backlash(&bc, &bs);
  const Stiffness k_sea = Stiffness::Quantize(0.63);
  static std::int32_t window_storage[501];
  static std::int32_t delay_storage[250];
  VelocityEstimator est(window_storage);
  est.Configure({.window = 501, .tick_hz = kTickHz});
  DelayLine delay(delay_storage);
  delay.Fill(0);
  const JointEncoderConfig jc{};
  MotorEncoderConfig mc;
  MotorEncoderState ms;
  MotorEncoder motor_encoder(&mc, &ms);
  motor_encoder.Reconfigure();
  motor_encoder.Reset(0);

  // The reference sees exactly the quantised sensor values the fixed chain sees.
  ReferenceChain ref(bc.alpha.ToDouble(), bc.c_right.ToDouble(), bc.c_left.ToDouble(),
                     k_sea.ToDouble(), 501);
  EnergyAccumulator net, positive;
  double ref_net = 0, ref_positive = 0, worst_lsb = 0;
  const double amp = 25.0 * std::numbers::pi / 180, w = 2 * std::numbers::pi * 0.5,
               k_if = 3.1, b_if = 0.18;
  const double counts_per_rad = 2048.0 * 100 / (2 * std::numbers::pi);
  backlash.Reset(Angle{}, Angle{});
  est.Reset(Angle{});
  for (std::int64_t i = 0; i < ticks; ++i) {
    const double t = double(i) / kTickHz;
    // Joint motion and the cable side that a Kelvin–Voigt interface needs: the motor
    // leads the cable side by the slack in the direction of motion.
    const double theta = amp * std::sin(w * t);
    const double tau = k_if * theta + b_if * amp * w * std::cos(w * t);
    const double cable = theta + tau / 0.63;
    const double motor_rad =
        cable + (std::cos(w * t) >= 0 ? 1.0 : -1.0) * std::numbers::pi / 180;
    const auto count =
        static_cast<std::int64_t>(std::llround(motor_rad * counts_per_rad));
    const Angle motor = motor_encoder.Update(static_cast<std::uint16_t>(count & 0xFFFF));
    const auto jcount = static_cast<std::uint16_t>(
        static_cast<std::int32_t>(std::lround(theta / (2 * std::numbers::pi) * 16384)) &
        0x3FFF);
    const Angle joint = DecodeJointFrame(EncodeJointFrame(jcount, false), jc).angle;

    const Angle cable_fixed = backlash.Update(motor, joint);
    const Torque torque = Mul<Torque>(k_sea, cable_fixed - joint);
    const AngularVelocity v = est.Update(joint);
    const Torque aligned = Torque::FromRaw(delay.Push(torque.raw()));
    const Power p = Mul<Power>(aligned, v);
    net.Add(p);
    if (p.raw() > 0) positive.Add(p);

    const double p_ref = ref.Step(motor.ToDouble(), joint.ToDouble());
    ref_net += p_ref / kTickHz;
    if (p_ref > 0) ref_positive += p_ref / kTickHz;
    const double e = std::fabs(p.ToDouble() - p_ref) / Power::Epsilon().ToDouble();
    worst_lsb = e > worst_lsb ? e : worst_lsb;
  }
  const EnergyScale scale(kTickHz);
  const double e_net = scale.ToEnergy(net.raw_sum()).ToDouble();
  const double e_pos = scale.ToEnergy(positive.raw_sum()).ToDouble();
  std::printf("energy_rel_error_1h: %.3g\n",
              std::fabs(e_net - ref_net) / std::fabs(ref_net));
  std::printf("positive_work_rel_error_1h: %.3g\n",
              std::fabs(e_pos - ref_positive) / std::fabs(ref_positive));
  std::printf("power_max_err_lsb: %.2f LSB\n", worst_lsb);
  std::fprintf(stderr, "(net %.6f J vs %.6f J over %lld ticks)\n", e_net, ref_net,
               static_cast<long long>(ticks));
  return 0;
}
