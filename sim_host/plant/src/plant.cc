// The simulated joint: equations in plant.h.
#include "mjc/plant/plant.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "mjc/core/encoder.h"

namespace mjc::plant {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr double kJointCountsPerRad = kJointCountsPerRev / kTwoPi;
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

void CheckStep(double dt_s) {
  if (!(dt_s > 0.0 && dt_s <= kMaxCallStep_s)) {
    throw std::invalid_argument("Plant: dt_s = " + std::to_string(dt_s) +
                                " s is outside (0, 0.01]");
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

struct Plant::Forces {
  double tau_r = 0;           // pulley pushing the cable side positive, N·m
  double tau_l = 0;           // pulley pushing it negative, N·m
  double contact_loss = 0;    // W
  double friction = 0;        // sheath friction on the cable side, N·m
  double friction_loss = 0;   // W
  double bristle_rate = 0;    // dz/dt, rad/s
  double tau_sea = 0;         // N·m
  double tau_if = 0;          // N·m
  double interface_loss = 0;  // W
  double maxwell_rate = 0;    // dx/dt, rad/s
};

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
  motor_counts_per_rad_ =
      static_cast<double>(params_.sensors.motor_counts_per_rev) * n_ / kTwoPi;
}

double Plant::InterfacePotential(const State& x) const {
  const InterfaceParams& ip = params_.interface;
  if (!ip.present) return 0.0;
  const double q = x(Index::kJointAngle);
  double u = 0.5 * ip.stiffness_Nm_per_rad * q * q + ip.preload_Nm * q;
  if (ip.model == InterfaceModel::kStandardLinearSolid) {
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
  interface_change_work_J_ = 0.0;
  time_s_ = 0.0;
  rng_.seed(params_.sensors.noise_seed);
  has_spare_gaussian_ = false;
  for (FaultSlot& slot : faults_) slot = FaultSlot{};
  has_last_joint_frame_ = false;
  last_joint_frame_ = 0;
  truth_ = Truth{};
  UpdateTruth(0.0);
  truth_.initial_stored_J = truth_.stored.total_J;
  truth_.balance_error_J = 0.0;
  SampleMotorCount();
}

Plant::Forces Plant::ComputeForces(const State& x) const {
  const CableParams& c = params_.cable;
  const InterfaceParams& ip = params_.interface;
  Forces f;
  const double pulley = c.alpha * x(Index::kMotorAngle);
  const double pulley_rate = c.alpha * x(Index::kMotorVelocity);
  const double cable = x(Index::kCableAngle);
  const double cable_rate = x(Index::kCableVelocity);

  const ContactForce right =
      Contact(pulley - c.alpha * c.c_right_rad - cable, pulley_rate - cable_rate, c);
  const ContactForce left =
      Contact(cable - (pulley - c.alpha * c.c_left_rad), cable_rate - pulley_rate, c);
  f.tau_r = right.torque;
  f.tau_l = left.torque;
  f.contact_loss = right.loss_rate + left.loss_rate;

  const double z = x(Index::kBristle);
  const double speed = std::abs(cable_rate);
  f.friction = c.viscous_Nm_s_per_rad * cable_rate;
  f.friction_loss = c.viscous_Nm_s_per_rad * cable_rate * cable_rate;
  if (c.coulomb_Nm > 0.0) {
    const double sigma = c.bristle_stiffness_Nm_per_rad;
    f.friction += sigma * z;
    f.bristle_rate = cable_rate - sigma * speed * z / c.coulomb_Nm;
    f.friction_loss += sigma * sigma * z * z * speed / c.coulomb_Nm;
  }

  const double joint = x(Index::kJointAngle);
  const double joint_rate = x(Index::kJointVelocity);
  f.tau_sea = k_sea_ * (cable - joint);
  if (ip.present) {
    f.tau_if = ip.stiffness_Nm_per_rad * joint + ip.preload_Nm;
    if (ip.model == InterfaceModel::kKelvinVoigt) {
      f.tau_if += ip.damping_Nm_s_per_rad * joint_rate;
      f.interface_loss = ip.damping_Nm_s_per_rad * joint_rate * joint_rate;
    } else {
      const double arm = ip.maxwell_stiffness_Nm_per_rad * (joint - x(Index::kMaxwell));
      f.tau_if += arm;
      if (ip.damping_Nm_s_per_rad > 0.0) {
        f.maxwell_rate = arm / ip.damping_Nm_s_per_rad;
        f.interface_loss = arm * f.maxwell_rate;
      }
    }
  }
  return f;
}

void Plant::Derivative(const State& x, const Drive& drive, State* dx) const {
  const MotorParams& m = params_.motor;
  const CableParams& c = params_.cable;
  const JointParams& j = params_.joint;
  const Forces f = ComputeForces(x);
  State& d = *dx;
  d.setZero();

  const double omega_m = x(Index::kMotorVelocity);
  const double pulley_torque = c.alpha * (f.tau_r - f.tau_l);  // on the cable, at θ_m
  if (drive.prescribed) {
    d(Index::kMotorAngle) = drive.pulley_velocity;
    d(Index::kPrescribedWork) = pulley_torque * omega_m;
  } else {
    const double i = x(Index::kCurrent);
    if (drive.bridge_enabled) {
      d(Index::kCurrent) =
          (drive.voltage_V - m.resistance_ohm * i - k_t_ * n_ * omega_m) / m.inductance_H;
    }
    const double friction = coulomb_reflected_ * std::tanh(coulomb_gain_ * omega_m) +
                            b_m_reflected_ * omega_m;
    d(Index::kMotorAngle) = omega_m;
    d(Index::kMotorVelocity) = (n_ * k_t_ * i - friction - pulley_torque) / j_eff_;
    d(Index::kElectricalEnergy) = drive.voltage_V * i;
    d(Index::kResistiveLoss) = m.resistance_ohm * i * i;
    d(Index::kMotorFrictionLoss) = friction * omega_m;
  }

  const double cable_rate = x(Index::kCableVelocity);
  d(Index::kCableAngle) = cable_rate;
  d(Index::kCableVelocity) =
      (f.tau_r - f.tau_l - f.friction - f.tau_sea) / c.inertia_kg_m2;
  d(Index::kBristle) = f.bristle_rate;

  const double joint_rate = x(Index::kJointVelocity);
  d(Index::kJointAngle) = joint_rate;
  d(Index::kJointVelocity) =
      (f.tau_sea - f.tau_if - j.viscous_Nm_s_per_rad * joint_rate) / j.inertia_kg_m2;
  d(Index::kMaxwell) = f.maxwell_rate;

  d(Index::kContactLoss) = f.contact_loss;
  d(Index::kCableFrictionLoss) = f.friction_loss;
  d(Index::kJointViscousLoss) = j.viscous_Nm_s_per_rad * joint_rate * joint_rate;
  d(Index::kInterfaceLoss) = f.interface_loss;
  d(Index::kInterfaceEnergy) = f.tau_if * joint_rate;
}

void Plant::Integrate(const Drive& drive, double dt_s) {
  // ceil(dt / max_step) substeps, tolerant of dt being a rounded multiple of the step.
  const double ratio = dt_s / params_.integration.max_step_s;
  const int substeps = std::max(1, static_cast<int>(std::ceil(ratio * (1.0 - 1e-12))));
  const double h = dt_s / substeps;
  State k1, k2, k3, k4, probe;
  for (int s = 0; s < substeps; ++s) {
    Derivative(x_, drive, &k1);
    probe = x_ + (0.5 * h) * k1;
    Derivative(probe, drive, &k2);
    probe = x_ + (0.5 * h) * k2;
    Derivative(probe, drive, &k3);
    probe = x_ + h * k3;
    Derivative(probe, drive, &k4);
    x_ += (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
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
  prescribed_mode_ = false;
  Drive drive;
  drive.bridge_enabled = bridge_enabled;
  if (bridge_enabled) {
    drive.voltage_V = std::clamp(duty, -1.0, 1.0) * params_.motor.supply_V;
  } else {
    ReturnMagneticEnergy();
  }
  IntegrateChecked(drive, dt_s);
  UpdateTruth(drive.voltage_V);
  SampleMotorCount();
}

void Plant::IntegrateChecked(const Drive& drive, double dt_s) {
  const State before = x_;
  const double time_before = time_s_;
  Integrate(drive, dt_s);
  if (!x_.allFinite()) {
    x_ = before;  // the plant stays where it was: nothing is lost, nothing is NaN
    time_s_ = time_before;
    throw std::runtime_error(
        "Plant: the state diverged at t = " + std::to_string(time()) +
        " s; the inputs are beyond what the model integrates");
  }
}

void Plant::StepPrescribedMotor(double pulley_rad, double dt_s) {
  CheckStep(dt_s);
  if (!std::isfinite(pulley_rad)) {
    throw std::invalid_argument("Plant::StepPrescribedMotor: angle is not finite");
  }
  if (!prescribed_mode_) {
    ReturnMagneticEnergy();
    prescribed_mode_ = true;
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
  IntegrateChecked(drive, dt_s);
  x_(Index::kMotorAngle) = pulley_rad;  // exact (the integral differs by rounding only)
  UpdateTruth(0.0);
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
  if (!was_sls) x_(Index::kMaxwell) = x_(Index::kJointAngle);  // a relaxed new arm
  interface_change_work_J_ += InterfacePotential(x_) - before;
  UpdateTruth(truth_.motor_voltage_V);
}

void Plant::UpdateTruth(double voltage_V) {
  const MotorParams& m = params_.motor;
  const CableParams& c = params_.cable;
  const State& x = x_;
  const Forces f = ComputeForces(x);
  Truth& t = truth_;
  t.time_s = time_s_;
  t.motor_voltage_V = voltage_V;
  t.motor_current_A = x(Index::kCurrent);
  t.motor_pulley_angle_rad = x(Index::kMotorAngle);
  t.motor_shaft_angle_rad = n_ * x(Index::kMotorAngle);
  t.motor_pulley_velocity_rad_s = x(Index::kMotorVelocity);
  t.cable_angle_rad = x(Index::kCableAngle);
  t.cable_velocity_rad_s = x(Index::kCableVelocity);
  t.joint_angle_rad = x(Index::kJointAngle);
  t.joint_velocity_rad_s = x(Index::kJointVelocity);
  t.sea_torque_Nm = f.tau_sea;
  t.contact_torque_Nm = f.tau_r - f.tau_l;
  t.cable_friction_Nm = f.friction;
  t.interface_torque_Nm = f.tau_if;
  t.interface_power_W = f.tau_if * x(Index::kJointVelocity);
  t.interface_energy_J = x(Index::kInterfaceEnergy);
  t.electrical_energy_J = x(Index::kElectricalEnergy);
  t.prescribed_work_J = x(Index::kPrescribedWork);
  t.interface_change_work_J = interface_change_work_J_;
  t.energy_in_J = t.electrical_energy_J + t.prescribed_work_J + t.interface_change_work_J;

  StoredEnergy& s = t.stored;
  const double i = x(Index::kCurrent);
  s.magnetic_J = 0.5 * m.inductance_H * i * i;
  const double wm = x(Index::kMotorVelocity);
  const double wc = x(Index::kCableVelocity);
  const double wj = x(Index::kJointVelocity);
  s.kinetic_J = 0.5 * (j_eff_ * wm * wm + c.inertia_kg_m2 * wc * wc +
                       params_.joint.inertia_kg_m2 * wj * wj);
  const double stretch = x(Index::kCableAngle) - x(Index::kJointAngle);
  s.sea_spring_J = 0.5 * k_sea_ * stretch * stretch;
  const double pulley = c.alpha * x(Index::kMotorAngle);
  const double dr =
      std::max(0.0, pulley - c.alpha * c.c_right_rad - x(Index::kCableAngle));
  const double dl =
      std::max(0.0, x(Index::kCableAngle) - (pulley - c.alpha * c.c_left_rad));
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

  t.balance_error_J = t.energy_in_J - (s.total_J - t.initial_stored_J) - d.total_J;
}

double Plant::Gaussian() {
  return StandardNormal(&rng_, &has_spare_gaussian_, &spare_gaussian_);
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
  // floor: a quadrature counter has counted every edge the shaft has passed. The
  // int64 cast is safe for |θ_m| < 10^9 rad; a wider angle saturates the floor.
  const double floored = std::clamp(std::floor(counts), -4.0e18, 4.0e18);
  const std::int64_t count =
      static_cast<std::int64_t>(floored) + params_.sensors.motor_count_at_zero;
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
  const double rounded = std::clamp(std::floor(counts + 0.5), -4.0e18, 4.0e18);
  std::int64_t count =
      static_cast<std::int64_t>(rounded) + params_.sensors.joint_zero_count;
  FaultSlot& jump = faults_[static_cast<int>(SensorFaultKind::kJointJump)];
  const std::int32_t jump_counts = jump.jump_counts;
  if (ConsumeFault(&jump)) count += jump_counts;
  const auto count14 = static_cast<std::uint16_t>(static_cast<std::uint64_t>(count) &
                                                  kJointFrameCountMask);
  const bool error_flag =
      ConsumeFault(&faults_[static_cast<int>(SensorFaultKind::kJointErrorFlag)]);
  std::uint16_t frame = EncodeJointFrame(count14, error_flag);
  if (ConsumeFault(&faults_[static_cast<int>(SensorFaultKind::kJointParity)])) {
    frame = static_cast<std::uint16_t>(frame ^ kJointFrameParityBit);
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
      const double rounded =
          std::floor(x_(Index::kJointAngle) * kJointCountsPerRad + 0.5);
      const std::int64_t count =
          static_cast<std::int64_t>(rounded) + params_.sensors.joint_zero_count;
      stuck_joint_frame_ =
          EncodeJointFrame(static_cast<std::uint16_t>(static_cast<std::uint64_t>(count) &
                                                      kJointFrameCountMask),
                           false);
    }
  }
}

void Plant::ClearFaults() {
  for (FaultSlot& slot : faults_) slot = FaultSlot{};
}

}  // namespace mjc::plant
