// The simulated joint: equations in plant.h.
#include "mjc/plant/plant.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace mjc::plant {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
// The joint sensor's resolution: the AS5047P's 14-bit angle.
constexpr double kJointCountsPerRev = 16384.0;
constexpr double kJointCountsPerRad = kJointCountsPerRev / kTwoPi;

// The joint sensor's SPI frame as the AS5047P datasheet gives it (ANGLECOM read): bits
// 13..0 the angle, bit 14 EF (error flag), bit 15 PARD, the even parity of bits 14..0.
// Written here from the datasheet rather than taken from the firmware's decoder, so the
// board's decoding is checked against a sensor it does not share code with.
constexpr std::uint16_t kFrameCountMask = 0x3FFFu;
constexpr std::uint16_t kFrameErrorFlag = 0x4000u;
constexpr std::uint16_t kFrameParity = 0x8000u;

std::uint16_t SensorFrame(std::uint16_t count14, bool error_flag) {
  auto low = static_cast<std::uint16_t>((count14 & kFrameCountMask) |
                                        (error_flag ? kFrameErrorFlag : 0u));
  unsigned ones = 0;
  for (std::uint16_t bits = low; bits != 0;
       bits = static_cast<std::uint16_t>(bits >> 1)) {
    ones += bits & 1u;
  }
  return static_cast<std::uint16_t>(low | ((ones & 1u) != 0 ? kFrameParity : 0u));
}
// Longest step a single Step()/StepPrescribedMotor() call accepts, s.
constexpr double kMaxCallStep_s = 0.01;

struct ContactForce {
  double torque = 0;     // ≥ 0, pushes the penetration apart
  double loss_rate = 0;  // W, ≥ 0
};

// Penalty contact of penetration delta (> 0 when touching) closing at delta_dot.
ContactForce Contact(double delta, double delta_dot, const CableParams& c) {
  if (delta <= 0.0) return {};
  const double ramp = std::min(delta / c.contact_damping_ramp_rad, 1.0);
  const double spring = c.contact_stiffness_Nm_per_rad * delta;
  const double torque =
      std::max(0.0, spring + c.contact_damping_Nm_s_per_rad * ramp * delta_dot);
  // Power into the contact minus the rate of change of its spring energy.
  return {torque, (torque - spring) * delta_dot};
}

// A contact over a substep whose penetration goes from delta0 at a rate `rate` (so
// delta0 + h·rate at the end). The spring's torque is the discrete gradient of its
// energy ½k_c·max(0, δ)² between the ends, so its work over the substep is exactly the
// change of that energy, touch-down and lift-off included; the damper acts at the
// midpoint, ramped in and clamped as in Contact().
struct ContactStep {
  double torque = 0;  // ≥ 0
  double loss_W = 0;  // ≥ 0, the damper (and the clamp) at the midpoint
  double slope = 0;   // d torque / d rate, N·m·s/rad (Newton's Jacobian)
};

inline ContactStep ContactOver(double delta0, double rate, double h, double spring_slope,
                               const CableParams& c) {
  const double delta1 = delta0 + h * rate;
  if (delta0 <= 0.0 && delta1 <= 0.0) return {};
  const double damping = c.contact_damping_Nm_s_per_rad;
  const double ramp_rad = c.contact_damping_ramp_rad;
  const double mid = 0.5 * (delta0 + delta1);
  double spring = c.contact_stiffness_Nm_per_rad * mid;
  double damper = damping * rate;
  double slope = spring_slope + damping;
  if (delta0 < ramp_rad || delta1 < ramp_rad) {  // not pressed in over the whole substep
    const double k = c.contact_stiffness_Nm_per_rad;
    if (delta0 < 0.0) {  // touches down inside the substep
      const double span = delta1 - delta0;
      spring = 0.5 * k * delta1 * delta1 / span;
      slope = spring_slope * delta1 * (delta1 - 2.0 * delta0) / (span * span);
    } else if (delta1 < 0.0) {  // lifts off inside the substep
      const double span = delta0 - delta1;
      spring = 0.5 * k * delta0 * delta0 / span;
      slope = spring_slope * delta0 * delta0 / (span * span);
    } else {
      slope = spring_slope;
    }
    if (mid >= ramp_rad) {
      slope += damping;
    } else if (mid > 0.0) {
      damper = damping * (mid / ramp_rad) * rate;
      slope += damping * (mid + 0.5 * h * rate) / ramp_rad;
    } else {
      damper = 0.0;
    }
  }
  const double torque = spring + damper;
  if (torque <= 0.0) return {0.0, -spring * rate, 0.0};
  return {torque, damper * rate, slope};
}

// floor(x) as an integer, x clamped to ±4e18 counts (an angle beyond ~10^9 rad
// saturates): without SSE4.1 std::floor is a libm call, and the sensors take one every
// tick.
std::int64_t FloorToInt(double x) {
  const double clamped = std::clamp(x, -4.0e18, 4.0e18);
  const auto truncated = static_cast<std::int64_t>(clamped);
  return static_cast<double>(truncated) > clamped ? truncated - 1 : truncated;
}

// tanh through one exp: glibc's tanh goes through expm1 and costs twice as much, and
// this one is the rotor's friction law evaluated two or three times a substep. Within a
// few 1e-16 of tanh in absolute terms, and the force and its dissipation use the same
// value.
inline double TanhByExp(double y) {
  // Beyond 19.1, 2·e^(−2|y|) is below half an ulp of 1: tanh is ±1 exactly.
  if (std::abs(y) > 19.1) return std::copysign(1.0, y);
  const double e = std::exp(-2.0 * std::abs(y));
  return std::copysign((1.0 - e) / (1.0 + e), y);
}

[[noreturn, gnu::cold]] void ThrowBadStep(double dt_s) {
  throw std::invalid_argument("Plant: dt_s = " + std::to_string(dt_s) +
                              " s is outside (0, 0.01]");
}

// Inline, with the message built out of line: every tick calls it.
inline void CheckStep(double dt_s) {
  if (!(dt_s > 0.0 && dt_s <= kMaxCallStep_s)) [[unlikely]] {
    ThrowBadStep(dt_s);
  }
}

}  // namespace

double StandardNormal(std::mt19937_64* rng, bool* has_spare, double* spare) {
  if (*has_spare) {
    *has_spare = false;
    return *spare;
  }
  // Two uniforms in (0, 1] from the top 53 bits of each draw.
  constexpr double kScale = 1.0 / 9007199254740992.0;  // 2^-53
  const double u1 = (static_cast<double>((*rng)() >> 11) + 1.0) * kScale;
  const double u2 = static_cast<double>((*rng)() >> 11) * kScale;
  const double r = std::sqrt(-2.0 * std::log(u1));
  *spare = r * std::sin(kTwoPi * u2);
  *has_spare = true;
  return r * std::cos(kTwoPi * u2);
}

Plant::Plant(const PlantParams& params) : params_(params) {
  ValidatePlantParams(params_, "<in-memory>");
  Derive();
  Reset();
}

void Plant::Derive() {
  const MotorParams& m = params_.motor;
  n_ = m.gear_ratio;
  k_t_ = m.torque_constant_Nm_per_A;
  j_eff_ = m.rotor_inertia_kg_m2 * n_ * n_ + m.output_inertia_kg_m2;
  b_m_reflected_ = m.viscous_Nm_s_per_rad * n_ * n_;
  coulomb_reflected_ = m.coulomb_Nm * n_;
  coulomb_gain_ = n_ / m.coulomb_speed_rad_s;
  k_sea_ = params_.sea.Stiffness();
  bristle_relax_ =
      params_.cable.coulomb_Nm > 0.0
          ? params_.cable.bristle_stiffness_Nm_per_rad / params_.cable.coulomb_Nm
          : 0.0;
  motor_counts_per_rad_ =
      static_cast<double>(params_.sensors.motor_counts_per_rev) * n_ / kTwoPi;
  step_ = MakeConstants(params_.integration.max_step_s);
}

Plant::SubstepConstants Plant::MakeConstants(double h) const {
  const MotorParams& m = params_.motor;
  const InterfaceParams& ip = params_.interface;
  SubstepConstants k;
  k.h = h;
  k.half_h = 0.5 * h;
  k.rotor_mass = 2.0 * j_eff_ / h;
  k.cable_mass = 2.0 * params_.cable.inertia_kg_m2 / h;
  k.joint_mass = 2.0 * params_.joint.inertia_kg_m2 / h;
  const double tau_s = m.inductance_H / m.resistance_ohm;
  k.current_decay = std::exp(-h / tau_s);
  k.charge_weight = -tau_s * std::expm1(-h / tau_s);
  k.square_weight = -0.5 * tau_s * std::expm1(-2.0 * h / tau_s);
  k.charge_per_V = (h - k.charge_weight) / m.resistance_ohm;
  k.back_emf_slope = k_t_ * n_ * k_t_ * n_ * k.charge_per_V / h;
  k.torque_per_charge = k_t_ * n_ / h;
  k.contact_slope = params_.cable.contact_stiffness_Nm_per_rad * k.half_h;
  k.sea_slope = k_sea_ * k.half_h;
  if (ip.present && ip.model == InterfaceModel::kKelvinVoigt) {
    k.interface_slope = ip.stiffness_Nm_per_rad * k.half_h + ip.damping_Nm_s_per_rad;
  } else if (ip.present && ip.damping_Nm_s_per_rad > 0.0) {
    k.maxwell_beta = k.half_h * ip.maxwell_stiffness_Nm_per_rad / ip.damping_Nm_s_per_rad;
    k.interface_slope =
        k.half_h * (ip.stiffness_Nm_per_rad +
                    ip.maxwell_stiffness_Nm_per_rad / (1.0 + k.maxwell_beta));
  } else if (ip.present) {
    // The limit b → 0 of the line above: the arm's term vanishes.
    k.maxwell_free = true;
    k.interface_slope = k.half_h * ip.stiffness_Nm_per_rad;
  }
  k.joint_diagonal =
      k.joint_mass + k.sea_slope + k.interface_slope + params_.joint.viscous_Nm_s_per_rad;
  k.joint_compliance = 1.0 / k.joint_diagonal;
  k.joint_gain = k.sea_slope * k.joint_compliance;
  k.cable_diagonal = k.cable_mass + params_.cable.viscous_Nm_s_per_rad +
                     k.sea_slope * (1.0 - k.joint_gain);
  return k;
}

double Plant::InterfacePotential(const State& x) const {
  const InterfaceParams& ip = params_.interface;
  if (!ip.present) return 0.0;
  const double q = x(Index::kJointAngle);
  double u = 0.5 * ip.stiffness_Nm_per_rad * q * q + ip.preload_Nm * q;
  // A free arm (b = 0: Coefficients::maxwell_free) stores nothing.
  if (ip.model == InterfaceModel::kStandardLinearSolid && ip.damping_Nm_s_per_rad > 0.0) {
    const double d = q - x(Index::kMaxwell);
    u += 0.5 * ip.maxwell_stiffness_Nm_per_rad * d * d;
  }
  return u;
}

void Plant::Reset() {
  const CableParams& c = params_.cable;
  const InterfaceParams& ip = params_.interface;
  x_.setZero();
  // The dead band at θ_m = 0 is [−α·c_r, −α·c_l]; start in it, at 0 if possible.
  const double cable = std::clamp(0.0, -c.alpha * c.c_right_rad, -c.alpha * c.c_left_rad);
  double joint = cable;
  if (ip.present) {
    // K·(θ̃ − θ_j) = k·θ_j + τ_0 (an SLS at rest has a relaxed Maxwell arm).
    joint = (k_sea_ * cable - ip.preload_Nm) / (k_sea_ + ip.stiffness_Nm_per_rad);
  }
  x_(Index::kCableAngle) = cable;
  x_(Index::kJointAngle) = joint;
  x_(Index::kMaxwell) = joint;
  if (c.coulomb_Nm > 0.0) {
    // The bristle holds the springs' torque on the cable side.
    const double limit = c.coulomb_Nm / c.bristle_stiffness_Nm_per_rad;
    x_(Index::kBristle) = std::clamp(
        -k_sea_ * (cable - joint) / c.bristle_stiffness_Nm_per_rad, -limit, limit);
  }
  prescribed_mode_ = false;
  midpoint_.valid = false;
  interface_change_work_J_ = 0.0;
  time_s_ = 0.0;
  rng_.seed(params_.sensors.noise_seed);
  noise_next_ = kNoiseBlock;
  for (FaultSlot& slot : faults_) slot = FaultSlot{};
  has_last_joint_frame_ = false;
  last_joint_frame_ = 0;
  voltage_V_ = 0.0;
  initial_stored_J_ = 0.0;
  RefreshTruth();
  initial_stored_J_ = truth_.stored.total_J;
  truth_stale_ = true;
  SampleMotorCount();
}

bool Plant::Substep(const Drive& drive, const SubstepConstants& k, const State& in,
                    State* out, Midpoint* midpoint) const {
  const MotorParams& m = params_.motor;
  const CableParams& c = params_.cable;
  const InterfaceParams& ip = params_.interface;
  const double h = k.h;
  const double half_h = k.half_h;
  const double alpha = c.alpha;
  const double i0 = in(Index::kCurrent);
  const double motor0 = in(Index::kMotorAngle);
  const double motor_rate0 = in(Index::kMotorVelocity);
  const double cable0 = in(Index::kCableAngle);
  const double cable_rate0 = in(Index::kCableVelocity);
  const double z0 = in(Index::kBristle);
  const double joint0 = in(Index::kJointAngle);
  const double joint_rate0 = in(Index::kJointVelocity);
  const double maxwell0 = in(Index::kMaxwell);
  const double delta_r0 = alpha * (motor0 - c.c_right_rad) - cable0;
  const double delta_l0 = cable0 - alpha * (motor0 - c.c_left_rad);
  const double stretch0 = cable0 - joint0;

  // The joint's equation is linear in the midpoint speeds (springs, interface and
  // bearing): ω̄_j = joint_gain·ω̄_c − joint_rest/joint_diagonal. It is eliminated,
  // and Newton runs on the rotor and the cable side, which the contacts couple.
  double interface0 = 0.0;  // τ_if at ω̄_j = 0
  const bool kelvin_voigt = ip.present && ip.model == InterfaceModel::kKelvinVoigt;
  const bool sls = ip.present && !kelvin_voigt;
  if (kelvin_voigt) {
    interface0 = ip.stiffness_Nm_per_rad * joint0 + ip.preload_Nm;
  } else if (sls) {
    interface0 = ip.stiffness_Nm_per_rad * joint0 + ip.preload_Nm;
    if (!k.maxwell_free) {
      interface0 +=
          ip.maxwell_stiffness_Nm_per_rad * (joint0 - maxwell0) / (1.0 + k.maxwell_beta);
    }
  }
  const double joint_rest = -k.joint_mass * joint_rate0 - k_sea_ * stretch0 + interface0;
  // The cable side's equation without contacts and bristle: cable_diagonal·ω̄_c +
  // cable_rest.
  const double cable_rest =
      -k.cable_mass * cable_rate0 + k_sea_ * stretch0 + k.joint_gain * joint_rest;

  // The rotor's equation without friction and contacts: rotor_diagonal·ω̄_m +
  // rotor_rest. The winding's charge over the substep is affine in ω̄_m.
  const bool motor_free = !drive.prescribed;
  const bool driven = motor_free && drive.bridge_enabled;
  const double ke = k_t_ * n_;
  double charge_fixed = 0;
  double rotor_diagonal = k.rotor_mass + b_m_reflected_;
  if (driven) {
    charge_fixed = k.charge_weight * i0 + k.charge_per_V * drive.voltage_V;
    rotor_diagonal += k.back_emf_slope;
  }
  const double rotor_rest =
      -k.rotor_mass * motor_rate0 - k.torque_per_charge * charge_fixed;

  const bool bristle = c.coulomb_Nm > 0.0;
  const double sigma = c.bristle_stiffness_Nm_per_rad;
  const double relax = bristle_relax_;
  const double half_relax = half_h * relax;
  const double half_sigma = half_h * sigma;

  // Newton from the midpoint speeds the last substep predicts, ω̄ ≈ ω_0 + (ω_0 − ω̄_prev)
  // (its acceleration carried on): the same root, in 2.04 evaluations a substep against
  // 2.28 from the speeds at the start on a 20 s PD loop of subject 1, 2.17 against 2.22
  // on sim_fidelity's runs (where the duty changes every tick).
  double wm = drive.prescribed ? drive.pulley_velocity : motor_rate0;
  double wc = cable_rate0;
  if (midpoint->valid) {
    if (!drive.prescribed) wm = 2.0 * motor_rate0 - midpoint->motor;
    wc = 2.0 * cable_rate0 - midpoint->cable;
  }
  ContactStep right, left;
  double z = z0, coulomb = 0;
  constexpr int kMaxIterations = 12;
  // Relative to each equation's terms: rounding leaves ~1e-16, and what is left above
  // it is energy the ledgers do not see (h·residual·speed a substep). The floor is for
  // equations whose terms all vanish (at rest).
  constexpr double kTolerance = 1e-12;
  constexpr double kFloor_Nm = 1e-15;
  for (int iteration = 0;; ++iteration) {
    // The residuals first; the Jacobian only when they ask for another step (the last
    // evaluation of every substep does not).
    const double rate = alpha * wm - wc;  // the right contact closing
    right = ContactOver(delta_r0, rate, h, k.contact_slope, c);
    left = ContactOver(delta_l0, -rate, h, k.contact_slope, c);
    const double contact = right.torque - left.torque;

    double bristle_torque = 0, inv_den = 0;
    if (bristle) {
      inv_den = 1.0 / (1.0 + half_relax * std::abs(wc));
      z = (z0 + half_h * wc) * inv_den;
      bristle_torque = sigma * z;
    }
    const double cable_linear = k.cable_diagonal * wc;
    const double r_cable = cable_linear + cable_rest - contact + bristle_torque;
    const bool cable_converged =
        std::abs(r_cable) <= kTolerance * (std::abs(cable_linear) + std::abs(cable_rest) +
                                           std::abs(contact) + std::abs(bristle_torque)) +
                                 kFloor_Nm;

    double t = 0, r_rotor = 0;
    if (motor_free) {
      if (coulomb_reflected_ > 0.0) {
        t = TanhByExp(coulomb_gain_ * wm);
        coulomb = coulomb_reflected_ * t;
      }
      const double rotor_linear = rotor_diagonal * wm;
      r_rotor = rotor_linear + rotor_rest + coulomb + alpha * contact;
      if (cable_converged &&
          std::abs(r_rotor) <=
              kTolerance * (std::abs(rotor_linear) + std::abs(rotor_rest) +
                            std::abs(coulomb) + std::abs(alpha * contact)) +
                  kFloor_Nm) {
        break;
      }
    } else if (cable_converged) {
      break;
    }
    if (iteration == kMaxIterations) return false;

    const double contact_slope = right.slope + left.slope;
    double bristle_slope = 0;
    if (bristle) {
      const double z_along = wc < 0.0 ? -z : z;
      // Never below zero: a bristle carried past F_c/σ0 by a very fast substep would
      // otherwise give a falling slope.
      bristle_slope = std::max(0.0, half_sigma * (1.0 - relax * z_along) * inv_den);
    }
    const double j_cable = k.cable_diagonal + contact_slope + bristle_slope;
    if (motor_free) {
      const double coulomb_slope = coulomb_reflected_ * coulomb_gain_ * (1.0 - t * t);
      // The 2×2 symmetric Jacobian [a b; b d].
      const double a = rotor_diagonal + coulomb_slope + alpha * alpha * contact_slope;
      const double b = -alpha * contact_slope;
      const double inv_det = 1.0 / (a * j_cable - b * b);
      wm -= (j_cable * r_rotor - b * r_cable) * inv_det;
      wc -= (a * r_cable - b * r_rotor) * inv_det;
    } else {
      wc -= r_cable / j_cable;
    }
  }

  // The end of the substep, and every ledger from the same midpoint forces.
  const double wj = k.joint_gain * wc - joint_rest * k.joint_compliance;
  const double joint_mid = joint0 + half_h * wj;
  const double interface = interface0 + k.interface_slope * wj;
  double maxwell_mid = maxwell0, interface_loss_J = 0;
  if (kelvin_voigt) {
    interface_loss_J = h * ip.damping_Nm_s_per_rad * wj * wj;
  } else if (sls) {
    maxwell_mid = k.maxwell_free
                      ? joint_mid
                      : (maxwell0 + k.maxwell_beta * joint_mid) / (1.0 + k.maxwell_beta);
    // The arm's force times the dashpot's travel.
    interface_loss_J = ip.maxwell_stiffness_Nm_per_rad * (joint_mid - maxwell_mid) * 2.0 *
                       (maxwell_mid - maxwell0);
  }
  double current = 0, electrical_J = 0, resistive_J = 0, motor_friction_J = 0,
         prescribed_J = 0, motor_rate = wm;
  if (motor_free) {
    if (driven) {
      const double steady = (drive.voltage_V - ke * wm) / m.resistance_ohm;
      const double excess = i0 - steady;
      current = steady + excess * k.current_decay;
      electrical_J = drive.voltage_V * (charge_fixed - k.charge_per_V * ke * wm);
      resistive_J = m.resistance_ohm *
                    (steady * steady * h + 2.0 * steady * excess * k.charge_weight +
                     excess * excess * k.square_weight);
    }
    motor_rate = 2.0 * wm - motor_rate0;
    motor_friction_J = h * (coulomb + b_m_reflected_ * wm) * wm;
  } else {
    // The pulley's torque on the cable times its speed.
    prescribed_J = h * alpha * (right.torque - left.torque) * wm;
  }
  const double contact_J = h * (right.loss_W + left.loss_W);
  const double friction_J =
      h * (c.viscous_Nm_s_per_rad * wc * wc + sigma * relax * std::abs(wc) * z * z);
  const double joint_viscous_J = h * params_.joint.viscous_Nm_s_per_rad * wj * wj;
  const double interface_J = h * interface * wj;
  if (!std::isfinite(wm + wc + wj + z + maxwell_mid + current + electrical_J +
                     resistive_J + motor_friction_J + prescribed_J + contact_J +
                     friction_J + interface_loss_J + interface_J)) {
    return false;
  }
  *midpoint = Midpoint{true, wm, wc};
  State& x = *out;
  x(Index::kCurrent) = current;
  x(Index::kMotorAngle) = motor0 + h * wm;
  x(Index::kMotorVelocity) = motor_rate;
  x(Index::kCableAngle) = cable0 + h * wc;
  x(Index::kCableVelocity) = 2.0 * wc - cable_rate0;
  x(Index::kBristle) = 2.0 * z - z0;
  x(Index::kJointAngle) = joint0 + h * wj;
  x(Index::kJointVelocity) = 2.0 * wj - joint_rate0;
  x(Index::kMaxwell) = 2.0 * maxwell_mid - maxwell0;
  x(Index::kElectricalEnergy) = in(Index::kElectricalEnergy) + electrical_J;
  x(Index::kPrescribedWork) = in(Index::kPrescribedWork) + prescribed_J;
  x(Index::kResistiveLoss) = in(Index::kResistiveLoss) + resistive_J;
  x(Index::kMotorFrictionLoss) = in(Index::kMotorFrictionLoss) + motor_friction_J;
  x(Index::kContactLoss) = in(Index::kContactLoss) + contact_J;
  x(Index::kCableFrictionLoss) = in(Index::kCableFrictionLoss) + friction_J;
  x(Index::kJointViscousLoss) = in(Index::kJointViscousLoss) + joint_viscous_J;
  x(Index::kInterfaceLoss) = in(Index::kInterfaceLoss) + interface_loss_J;
  x(Index::kInterfaceEnergy) = in(Index::kInterfaceEnergy) + interface_J;
  return true;
}

bool Plant::Halve(const Drive& drive, const SubstepConstants& k, int depth,
                  State* x) const {
  if (depth == 0) return false;
  const SubstepConstants half = MakeConstants(0.5 * k.h);
  State y = *x;
  Midpoint midpoint;
  for (int i = 0; i < 2; ++i) {
    if (!Substep(drive, half, y, &y, &midpoint)) {
      midpoint.valid = false;
      if (!Halve(drive, half, depth - 1, &y)) return false;
    }
  }
  *x = y;
  return true;
}

void Plant::Integrate(const Drive& drive, double dt_s) {
  if (dt_s != step_dt_s_) {
    // ceil(dt / max_step) substeps, tolerant of dt being a rounded multiple of the
    // step.
    const double ratio = dt_s / params_.integration.max_step_s;
    substeps_ = std::max(1, static_cast<int>(std::ceil(ratio * (1.0 - 1e-12))));
    step_dt_s_ = dt_s;
    const double h = dt_s / substeps_;
    if (h != step_.h) {
      step_ = MakeConstants(h);
      midpoint_.valid = false;
    }
  }
  const int substeps = substeps_;
  // On a failure the plant stays where it was: nothing is lost, nothing is NaN. (A
  // failed substep leaves its state untouched, so one substep needs no copy.) A substep
  // that does not converge from the extrapolated speeds is tried again from those at
  // its start before it is halved.
  constexpr int kMaxHalvings = 8;
  const auto advance = [&](State* x) {
    if (Substep(drive, step_, *x, x, &midpoint_)) return true;
    if (midpoint_.valid) {
      midpoint_.valid = false;
      if (Substep(drive, step_, *x, x, &midpoint_)) return true;
    }
    midpoint_.valid = false;  // the halves' midpoints are not this step's
    return Halve(drive, step_, kMaxHalvings, x);
  };
  bool ok = true;
  if (substeps == 1) {
    ok = advance(&x_);
  } else {
    State next = x_;
    for (int s = 0; s < substeps && ok; ++s) ok = advance(&next);
    if (ok) x_ = next;
  }
  if (!ok) {
    throw std::runtime_error(
        "Plant: the state diverged at t = " + std::to_string(time()) +
        " s; the inputs are beyond what the model integrates");
  }
  time_s_ += dt_s;
}

void Plant::ReturnMagneticEnergy() {
  const double i = x_(Index::kCurrent);
  x_(Index::kElectricalEnergy) -= 0.5 * params_.motor.inductance_H * i * i;
  x_(Index::kCurrent) = 0.0;
}

void Plant::Step(double duty, bool bridge_enabled, double dt_s) {
  CheckStep(dt_s);
  if (!std::isfinite(duty))
    throw std::invalid_argument("Plant::Step: duty is not finite");
  if (prescribed_mode_) midpoint_.valid = false;  // the rotor is free again
  prescribed_mode_ = false;
  Drive drive;
  drive.bridge_enabled = bridge_enabled;
  if (bridge_enabled) {
    drive.voltage_V = std::clamp(duty, -1.0, 1.0) * params_.motor.supply_V;
  } else {
    ReturnMagneticEnergy();
  }
  Integrate(drive, dt_s);
  voltage_V_ = drive.voltage_V;
  truth_stale_ = true;
  SampleMotorCount();
}

void Plant::StepPrescribedMotor(double pulley_rad, double dt_s) {
  CheckStep(dt_s);
  if (!std::isfinite(pulley_rad)) {
    throw std::invalid_argument("Plant::StepPrescribedMotor: angle is not finite");
  }
  if (!prescribed_mode_) {
    ReturnMagneticEnergy();
    prescribed_mode_ = true;
    midpoint_.valid = false;
  }
  const double speed = (pulley_rad - x_(Index::kMotorAngle)) / dt_s;
  // A 30,000 rpm motor behind 100:1 turns the pulley at 31 rad/s; a faster prescribed
  // step is a jump in the caller's trajectory, and the stiff cable contact would take
  // it as an impact no fixed-step integrator resolves.
  constexpr double kMaxPrescribedSpeed = 50.0;  // rad/s at the pulley
  if (std::fabs(speed) > kMaxPrescribedSpeed) {
    throw std::invalid_argument("Plant::StepPrescribedMotor: the pulley would move at " +
                                std::to_string(speed) +
                                " rad/s (limit 50 rad/s): prescribe a continuous motion");
  }
  // The source brings the rotor to the imposed speed; that kinetic energy is its work.
  const double old_speed = x_(Index::kMotorVelocity);
  x_(Index::kPrescribedWork) += 0.5 * j_eff_ * (speed * speed - old_speed * old_speed);
  x_(Index::kMotorVelocity) = speed;
  Drive drive;
  drive.prescribed = true;
  drive.pulley_velocity = speed;
  Integrate(drive, dt_s);
  x_(Index::kMotorAngle) = pulley_rad;  // exact (the integral differs by rounding only)
  voltage_V_ = 0.0;
  truth_stale_ = true;
  SampleMotorCount();
}

void Plant::SetInterface(const InterfaceParams& interface) {
  PlantParams candidate = params_;
  candidate.interface = interface;
  ValidatePlantParams(candidate, "<SetInterface>");
  const double before = InterfacePotential(x_);
  const bool was_sls = params_.interface.present &&
                       params_.interface.model == InterfaceModel::kStandardLinearSolid;
  params_.interface = interface;
  step_ = MakeConstants(step_.h);
  if (!was_sls) x_(Index::kMaxwell) = x_(Index::kJointAngle);  // a relaxed new arm
  interface_change_work_J_ += InterfacePotential(x_) - before;
  truth_stale_ = true;
}

double Plant::InterfaceTorque(const State& x) const {
  const InterfaceParams& ip = params_.interface;
  if (!ip.present) return 0.0;
  const double joint = x(Index::kJointAngle);
  double torque = ip.stiffness_Nm_per_rad * joint + ip.preload_Nm;
  if (ip.model == InterfaceModel::kKelvinVoigt) {
    torque += ip.damping_Nm_s_per_rad * x(Index::kJointVelocity);
  } else if (ip.damping_Nm_s_per_rad > 0.0) {  // a free arm (b = 0) pulls nothing
    torque += ip.maxwell_stiffness_Nm_per_rad * (joint - x(Index::kMaxwell));
  }
  return torque;
}

double Plant::interface_power_W() const {
  return InterfaceTorque(x_) * x_(Index::kJointVelocity);
}

void Plant::RefreshTruth() const {
  const MotorParams& m = params_.motor;
  const CableParams& c = params_.cable;
  const State& x = x_;
  // The instantaneous forces at the end of the step.
  const double pulley = c.alpha * x(Index::kMotorAngle);
  const double pulley_rate = c.alpha * x(Index::kMotorVelocity);
  const double cable = x(Index::kCableAngle);
  const double cable_rate = x(Index::kCableVelocity);
  const double joint = x(Index::kJointAngle);
  const double joint_rate = x(Index::kJointVelocity);
  const double contact =
      Contact(pulley - c.alpha * c.c_right_rad - cable, pulley_rate - cable_rate, c)
          .torque -
      Contact(cable - (pulley - c.alpha * c.c_left_rad), cable_rate - pulley_rate, c)
          .torque;
  double friction = c.viscous_Nm_s_per_rad * cable_rate;
  if (c.coulomb_Nm > 0.0) friction += c.bristle_stiffness_Nm_per_rad * x(Index::kBristle);
  const double interface = InterfaceTorque(x);
  Truth& t = truth_;
  t.time_s = time_s_;
  t.motor_voltage_V = voltage_V_;
  t.motor_current_A = x(Index::kCurrent);
  t.motor_pulley_angle_rad = x(Index::kMotorAngle);
  t.motor_shaft_angle_rad = n_ * x(Index::kMotorAngle);
  t.motor_pulley_velocity_rad_s = x(Index::kMotorVelocity);
  t.cable_angle_rad = x(Index::kCableAngle);
  t.cable_velocity_rad_s = x(Index::kCableVelocity);
  t.joint_angle_rad = x(Index::kJointAngle);
  t.joint_velocity_rad_s = x(Index::kJointVelocity);
  t.sea_torque_Nm = k_sea_ * (cable - joint);
  t.contact_torque_Nm = contact;
  t.cable_friction_Nm = friction;
  t.interface_torque_Nm = interface;
  t.interface_power_W = interface * joint_rate;
  t.interface_energy_J = x(Index::kInterfaceEnergy);
  t.electrical_energy_J = x(Index::kElectricalEnergy);
  t.prescribed_work_J = x(Index::kPrescribedWork);
  t.interface_change_work_J = interface_change_work_J_;
  t.energy_in_J = t.electrical_energy_J + t.prescribed_work_J + t.interface_change_work_J;

  StoredEnergy& s = t.stored;
  const double i = x(Index::kCurrent);
  s.magnetic_J = 0.5 * m.inductance_H * i * i;
  s.kinetic_J = 0.5 * (j_eff_ * x(Index::kMotorVelocity) * x(Index::kMotorVelocity) +
                       c.inertia_kg_m2 * cable_rate * cable_rate +
                       params_.joint.inertia_kg_m2 * joint_rate * joint_rate);
  const double stretch = cable - joint;
  s.sea_spring_J = 0.5 * k_sea_ * stretch * stretch;
  const double dr = std::max(0.0, pulley - c.alpha * c.c_right_rad - cable);
  const double dl = std::max(0.0, cable - (pulley - c.alpha * c.c_left_rad));
  s.contact_spring_J = 0.5 * c.contact_stiffness_Nm_per_rad * (dr * dr + dl * dl);
  const double z = x(Index::kBristle);
  s.bristle_J = c.coulomb_Nm > 0.0 ? 0.5 * c.bristle_stiffness_Nm_per_rad * z * z : 0.0;
  s.interface_J = InterfacePotential(x);
  s.total_J = s.magnetic_J + s.kinetic_J + s.sea_spring_J + s.contact_spring_J +
              s.bristle_J + s.interface_J;

  DissipatedEnergy& d = t.dissipated;
  d.resistive_J = x(Index::kResistiveLoss);
  d.motor_friction_J = x(Index::kMotorFrictionLoss);
  d.contact_J = x(Index::kContactLoss);
  d.cable_friction_J = x(Index::kCableFrictionLoss);
  d.joint_viscous_J = x(Index::kJointViscousLoss);
  d.interface_J = x(Index::kInterfaceLoss);
  d.total_J = d.resistive_J + d.motor_friction_J + d.contact_J + d.cable_friction_J +
              d.joint_viscous_J + d.interface_J;

  t.initial_stored_J = initial_stored_J_;
  t.balance_error_J = t.energy_in_J - (s.total_J - t.initial_stored_J) - d.total_J;
  truth_stale_ = false;
}

void Plant::RefillNoise() {
  // StandardNormal's pairs, (r·cos, r·sin) of the same two draws, in its order and
  // with the same library calls, so the values are its own bit for bit. The pairs are
  // independent, so a block of them is computed at the machine's throughput rather than
  // one log, one square root and one sine and cosine in a row each second sensor read.
  constexpr double kScale = 1.0 / 9007199254740992.0;  // 2^-53
  for (int n = 0; n < kNoiseBlock; n += 2) {
    const double u1 = (static_cast<double>(rng_() >> 11) + 1.0) * kScale;
    const double u2 = static_cast<double>(rng_() >> 11) * kScale;
    const double r = std::sqrt(-2.0 * std::log(u1));
    noise_[n] = r * std::cos(kTwoPi * u2);
    noise_[n + 1] = r * std::sin(kTwoPi * u2);
  }
  noise_next_ = 0;
}

double Plant::Gaussian() {
  if (noise_next_ == kNoiseBlock) RefillNoise();
  return noise_[noise_next_++];
}

bool Plant::ConsumeFault(FaultSlot* slot) {
  if (!slot->active) return false;
  if (slot->remaining > 0 && --slot->remaining == 0) slot->active = false;
  return true;
}

void Plant::SampleMotorCount() {
  double counts = x_(Index::kMotorAngle) * motor_counts_per_rad_;
  if (params_.sensors.motor_noise_counts > 0.0) {
    counts += params_.sensors.motor_noise_counts * Gaussian();
  }
  // floor: a quadrature counter has counted every edge the shaft has passed. Exact for
  // |θ_m| < 10^9 rad; a wider angle saturates the floor.
  const std::int64_t count = FloorToInt(counts) + params_.sensors.motor_count_at_zero;
  const auto raw =
      static_cast<std::uint16_t>(static_cast<std::uint64_t>(count) & 0xFFFFu);
  FaultSlot& stuck = faults_[static_cast<int>(SensorFaultKind::kMotorStuck)];
  motor_count_ = ConsumeFault(&stuck) ? stuck_motor_count_ : raw;
}

std::uint16_t Plant::JointFrame() {
  double counts = x_(Index::kJointAngle) * kJointCountsPerRad;
  if (params_.sensors.joint_noise_counts > 0.0) {
    counts += params_.sensors.joint_noise_counts * Gaussian();
  }
  std::int64_t count = FloorToInt(counts + 0.5) + params_.sensors.joint_zero_count;
  FaultSlot& jump = faults_[static_cast<int>(SensorFaultKind::kJointJump)];
  const std::int32_t jump_counts = jump.jump_counts;
  if (ConsumeFault(&jump)) count += jump_counts;
  const auto count14 =
      static_cast<std::uint16_t>(static_cast<std::uint64_t>(count) & kFrameCountMask);
  const bool error_flag =
      ConsumeFault(&faults_[static_cast<int>(SensorFaultKind::kJointErrorFlag)]);
  std::uint16_t frame = SensorFrame(count14, error_flag);
  if (ConsumeFault(&faults_[static_cast<int>(SensorFaultKind::kJointParity)])) {
    frame = static_cast<std::uint16_t>(frame ^ kFrameParity);
  }
  if (ConsumeFault(&faults_[static_cast<int>(SensorFaultKind::kJointStuck)])) {
    frame = stuck_joint_frame_;
  }
  last_joint_frame_ = frame;
  has_last_joint_frame_ = true;
  return frame;
}

void Plant::InjectFault(const SensorFault& fault) {
  const int kind = static_cast<int>(fault.kind);
  if (kind < 0 || kind >= kFaultKinds) {
    throw std::invalid_argument("Plant::InjectFault: unknown fault kind " +
                                std::to_string(kind));
  }
  FaultSlot& slot = faults_[kind];
  slot.active = true;
  slot.remaining = fault.samples;
  slot.jump_counts = fault.jump_counts;
  if (fault.kind == SensorFaultKind::kMotorStuck) stuck_motor_count_ = motor_count_;
  if (fault.kind == SensorFaultKind::kJointStuck) {
    if (has_last_joint_frame_) {
      stuck_joint_frame_ = last_joint_frame_;
    } else {
      const std::int64_t count =
          FloorToInt(x_(Index::kJointAngle) * kJointCountsPerRad + 0.5) +
          params_.sensors.joint_zero_count;
      stuck_joint_frame_ = SensorFrame(
          static_cast<std::uint16_t>(static_cast<std::uint64_t>(count) & kFrameCountMask),
          false);
    }
  }
}

void Plant::ClearFaults() {
  for (FaultSlot& slot : faults_) slot = FaultSlot{};
}

}  // namespace mjc::plant
