// The simulated Maestro joint: a physical model of one Bowden-cable SEA joint pushing
// on a grounded hand, with the sensors the board reads and the ground truth it never
// sees. It is NOT the firmware's model run backwards: the play operator, the SEA torque
// and the interface power the firmware estimates emerge here from contact, friction
// and inertia.
//
// ── Model (joint coordinates: angles in rad and torques in N·m at the joint pulley;
//    the motor pulley appears as α·θ_m, α = r_m/r_j) ──────────────────────────────────
//
// Motor and gearbox (θ_m, ω_m: motor-PULLEY angle and speed; shaft = N·θ_m):
//   L·di/dt      = V − R·i − k_t·N·ω_m
//   J_eff·dω_m/dt = N·k_t·i − N·T_f·tanh(N·ω_m/ω_f) − b_m·N²·ω_m − α·(τ_r − τ_l),
//   J_eff = J_m·N² + J_out  (ideal gear; brush, bearing and gearhead losses are the
//   Coulomb T_f and viscous b_m at the shaft)
//   V = duty·V_supply with the bridge enabled (average-voltage PWM, |duty| ≤ 1).
//   Bridge disabled: the terminals are open. The freewheel diodes carry the current
//   back to the supply and it reaches zero in L·|i|/V_supply (≤ 30 µs here), far below
//   a control tick, so it is taken as instantaneous: at the first disabled step i is
//   set to 0 and its ½·L·i² is booked as energy returned to the supply. While disabled
//   i ≡ 0: no motor torque, the rotor coasts against its friction and the cable. (Valid
//   while the back-EMF stays below V_supply, i.e. below the no-load speed.)
//
// Cable slack (penalty contacts at the dead band's edges, penetrations δ ≥ 0):
//   δ_r = α(θ_m − c_r) − θ̃   (pulley pushes the cable side positive when δ_r > 0)
//   δ_l = θ̃ − α(θ_m − c_l)   (pulley pushes it negative when δ_l > 0),   c_l ≤ c_r
//   τ_{r,l} = max(0, k_c·δ + c_c·min(δ/δ_ramp, 1)·δ̇) for δ > 0, else 0
//   The damping ramps in over δ_ramp so the force is continuous at touch-down; the
//   clamp keeps a contact from pulling. Dissipation (τ − k_c·δ)·δ̇ ≥ 0 in every case.
//
// Sheath friction on the cable side (Dahl bristle model + viscous):
//   F = σ0·z + b_f·ω̃,   dz/dt = ω̃ − σ0·|ω̃|·z / F_c
//   |z| ≤ F_c/σ0 is the pre-sliding deflection; sliding saturates at F = ±F_c + b_f·ω̃.
//   Inside the dead band the bristle holds θ̃ against the springs (this is what makes
//   the real system a play operator); dissipation σ0²·z²·|ω̃|/F_c + b_f·ω̃² ≥ 0.
//   Why not tanh-regularised Coulomb here: on the light cable side (J_c ≈ 2e-6 kg·m²)
//   a tanh law integrable at 10 µs needs a regularisation speed ≳ 0.1 rad/s, and the
//   cable would creep out of the dead band under the spring torque. The bristle holds
//   it with a finite stiffness instead and never creeps at rest. F_c = 0: viscous only.
//   (The rotor, 1e-3 kg·m² at the pulley, can use tanh: T_f above.)
//
// Cable side, springs, joint, interface:
//   J_c·dω̃/dt  = τ_r − τ_l − F − τ_sea,            τ_sea = K·(θ̃ − θ_j),  K = 2k·r_j²
//   J_j·dω_j/dt = τ_sea − τ_if − b_j·ω_j
//   Kelvin–Voigt:      τ_if = k·θ_j + b·ω_j + τ_0
//   Standard linear solid: τ_if = k·θ_j + k_2·(θ_j − x) + τ_0,  b·dx/dt = k_2·(θ_j − x)
//   No human: τ_if = 0.
//   The hand is grounded, so the interface power τ_if·ω_j is the whole of the joint's
//   output power (paper eq. 3 with P_out,human = 0). Positive: robot → interface.
//
// Energy: electrical energy ∫V·i dt, the work of a prescribed pulley, the interface
// energy ∫τ_if·ω_j dt and every dissipation are ledgers booked from the same forces
// that move the state (below), so  energy in = Δ(stored) + dissipated  holds to the
// Newton tolerance (measured ~1e-14 of the dissipation). Stored = ½Li² + kinetic
// (rotor, cable side, joint) + ½K(θ̃−θ_j)² + contact springs + bristle ½σ0·z² +
// interface potential (½kθ_j² [+ ½k_2(θ_j−x)²] + τ_0·θ_j).
//
// Integration: ceil(dt / max_step_s) equal substeps per Step (100 µs in the parameter
// files: one a 10 kHz tick). The fast parts are stiff (the electrical pole R/L =
// 44,000 1/s; the cable side on its contact and bristle ≈ 30,000 rad/s; the joint on
// the interface damper b/J_j ≈ 19,000 1/s), and a substep treats them as such:
//   Current: in closed form over the substep, with ω_m held at its midpoint value ω̄_m
//   (the winding's time constant L/R = 23 µs against the rotor's ≥ 1 ms):
//     i(t) = i_∞ + (i_0 − i_∞)·e^(−tR/L),  i_∞ = (V − k_t·N·ω̄_m)/R,
//   so the charge Q = ∫i dt, ∫R·i² dt and i at the end are exact for that ω̄_m, and
//   V·Q − k_t·N·ω̄_m·Q = Δ(½Li²) + ∫R·i² dt. The rotor takes the torque k_t·N·Q/h.
//   Mechanics: implicit midpoint (A-stable) on the rotor, cable side and joint; the
//   unknowns are the three midpoint speeds ω̄, and θ_1 = θ_0 + h·ω̄, ω_1 = 2ω̄ − ω_0.
//   The bristle (dz/dt is linear in z for a given ω̄) and the Maxwell node (linear
//   in θ_j) are midpoint too, in closed form. Each contact spring is a discrete
//   gradient: its torque over the substep is ΔU/Δδ of U = ½k_c·max(0, δ)² between the
//   substep's ends, so a touch-down or lift-off inside a substep stores exactly the
//   work it takes; its damper acts at the midpoint. Every ledger then books
//   h·(midpoint force)·(midpoint speed), and the change of each stored energy equals
//   the work of its conservative force identically: the balance is a property of the
//   discretisation, not of a small step.
//   The joint's equation is linear and is eliminated; the rotor's and the cable
//   side's (coupled by the contacts) are solved by Newton's method to a residual of
//   1e-12 of each equation's terms, from the midpoint speeds the previous substep
//   extrapolates (ω̄ ≈ 2ω_0 − ω̄_prev; the speeds at the start after a reset, a change
//   of drive mode or a halving): 2.17 evaluations a substep over sim_fidelity's runs
//   (2.22 from the speeds at the start; the third is the rotor's tanh). A substep whose
//   iteration does not converge in 12 is tried again from the speeds at its start,
//   then halved (recursively, up to 2^-8).
//   What h must still resolve are the modes the sensors follow: the rotor on the
//   contact (√(k_c·α²/J_eff) = 1000 rad/s) and on its Coulomb regularisation (1000
//   1/s), the joint on the springs and interface (√((K+k)/J_j) ≤ 640 rad/s).
//   ValidatePlantParams refuses h·rate > 0.2 for these (midpoint's phase error
//   (h·ω)²/12 ≤ 0.33 %). The cable side's fast modes are quasi-static for everything
//   the sensors and the interface see: at 100 µs the board's window energies agree
//   with 10 µs (where those modes are resolved) within 0.2 %, and the plant's with the
//   earlier fixed-step RK4 at 2.5 µs within 3e-6 (tests/sim). The exception is the
//   contact dampers' own ledger (8 % low at 100 µs; 3e-5 of the dissipation).
// State: Eigen::Matrix<double, 18, 1>; nothing is allocated after construction.
//
// Sensors (sampled at the end of each step for the motor; at each JointFrame() read for
// the joint):
//   Motor: 16-bit wrapping timer count = floor(N·θ_m·cpr/2π + noise) + count_at_zero,
//   so the firmware's default MotorEncoderConfig reads θ_m = count·2π/(cpr·N).
//   Joint: AS5047P-class 16-bit frame (mjc::EncodeJointFrame) of the 14-bit count
//   round(θ_j·16384/2π + noise) + zero_count mod 16384. Round-to-nearest, so the
//   firmware's count·2π/16384 is within half a count of θ_j.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <random>

#include "mjc/plant/params.h"

namespace mjc::plant {

// Injectable sensor faults. Stable numbers (test logs refer to them).
enum class SensorFaultKind : std::uint8_t {
  kJointParity = 0,     // joint frame with its parity bit flipped (odd parity)
  kJointErrorFlag = 1,  // joint frame with EF set (parity valid)
  kJointStuck = 2,      // joint frame frozen at the last frame read before the fault
  kJointJump = 3,       // joint count offset by jump_counts (an implausible jump)
  kMotorStuck = 4,      // motor count frozen at its value when the fault was injected
};

struct SensorFault {
  SensorFaultKind kind = SensorFaultKind::kJointParity;
  // How many samples the fault lasts: joint faults count JointFrame() reads, the motor
  // fault counts steps. 0 = until ClearFaults().
  std::uint32_t samples = 1;
  // kJointJump only: counts added to the 14-bit joint count (wraps mod 16384).
  std::int32_t jump_counts = 0;
};

// Energies in J, since construction or the last Reset().
struct StoredEnergy {
  double magnetic_J = 0;        // ½Li²
  double kinetic_J = 0;         // rotor (reflected to the pulley), cable side, joint
  double sea_spring_J = 0;      // ½K(θ̃ − θ_j)²
  double contact_spring_J = 0;  // ½k_c·δ² at the slack's edges
  double bristle_J = 0;         // ½σ0·z²
  double interface_J = 0;       // interface springs + preload potential τ_0·θ_j
  double total_J = 0;
};

struct DissipatedEnergy {
  double resistive_J = 0;       // ∫R·i²
  double motor_friction_J = 0;  // Coulomb + viscous at the shaft (not while prescribed)
  double contact_J = 0;         // contact dampers
  double cable_friction_J = 0;  // sheath friction (bristle + viscous)
  double joint_viscous_J = 0;   // ∫b_j·ω_j²
  double interface_J = 0;       // interface dashpot
  double total_J = 0;
};

// Ground truth for tests and reports; the firmware never sees it.
struct Truth {
  double time_s = 0;
  double motor_voltage_V = 0;  // applied terminal voltage (0 when disabled)
  double motor_current_A = 0;
  double motor_shaft_angle_rad = 0;   // N·θ_m
  double motor_pulley_angle_rad = 0;  // θ_m
  double motor_pulley_velocity_rad_s = 0;
  double cable_angle_rad = 0;  // θ̃ (joint coordinates)
  double cable_velocity_rad_s = 0;
  double joint_angle_rad = 0;  // θ_j
  double joint_velocity_rad_s = 0;
  double sea_torque_Nm = 0;            // K(θ̃ − θ_j), the torque on the joint
  double contact_torque_Nm = 0;        // τ_r − τ_l, pulley on the cable side
  double cable_friction_Nm = 0;        // sheath friction F on the cable side
  double interface_torque_Nm = 0;      // τ_if, robot on the interface
  double interface_power_W = 0;        // τ_if·θ̇_j, > 0 robot → interface
  double interface_energy_J = 0;       // ∫τ_if·θ̇_j dt
  double electrical_energy_J = 0;      // ∫V·i dt, net of current returned at disable
  double prescribed_work_J = 0;        // work of the prescribed pulley (incl. rotor KE)
  double interface_change_work_J = 0;  // ΔU_if booked by SetInterface()
  double energy_in_J = 0;              // the three above
  StoredEnergy stored;
  double initial_stored_J = 0;  // stored.total_J at Reset()
  DissipatedEnergy dissipated;
  // energy_in − (stored − initial_stored) − dissipated: zero up to integration error.
  double balance_error_J = 0;
};

// Link through the mjc_plant CMake target: it carries mjc_eigen's definitions
// (EIGEN_NO_MALLOC, EIGEN_DONT_VECTORIZE, …), which the layout of State depends on.
class Plant {
 public:
  static constexpr int kStateSize = 18;
  using State = Eigen::Matrix<double, kStateSize, 1>;

  // Indices into State.
  struct Index {
    static constexpr int kCurrent = 0;        // i, A
    static constexpr int kMotorAngle = 1;     // θ_m, rad (pulley)
    static constexpr int kMotorVelocity = 2;  // ω_m, rad/s (pulley)
    static constexpr int kCableAngle = 3;     // θ̃, rad
    static constexpr int kCableVelocity = 4;  // rad/s
    static constexpr int kBristle = 5;        // z, rad
    static constexpr int kJointAngle = 6;     // θ_j, rad
    static constexpr int kJointVelocity = 7;  // rad/s
    static constexpr int kMaxwell = 8;        // x (SLS internal node), rad
    static constexpr int kElectricalEnergy = 9;
    static constexpr int kPrescribedWork = 10;
    static constexpr int kResistiveLoss = 11;
    static constexpr int kMotorFrictionLoss = 12;
    static constexpr int kContactLoss = 13;
    static constexpr int kCableFrictionLoss = 14;
    static constexpr int kJointViscousLoss = 15;
    static constexpr int kInterfaceLoss = 16;
    static constexpr int kInterfaceEnergy = 17;  // all energies in J
  };

  // Validates (ValidatePlantParams, source "<in-memory>") and Reset()s. Throws
  // std::runtime_error on invalid parameters.
  explicit Plant(const PlantParams& params);

  // Static equilibrium at θ_m = 0: current 0, everything at rest, the cable side at 0
  // clamped into the dead band [−α·c_r, −α·c_l] (so 0 when c_l ≤ 0 ≤ c_r), the joint
  // where springs, interface and preload balance, the bristle holding the spring torque.
  // Time 0, energy ledgers 0, faults cleared, noise sequence restarted.
  void Reset();

  // Advances by dt_s ∈ (0, 0.01] s with the motor driven by the bridge: terminal
  // voltage duty·V_supply if bridge_enabled (duty saturated to [-1, 1]); open terminals
  // otherwise (see the model above). Throws std::invalid_argument for a dt_s outside
  // its range or a non-finite duty.
  void Step(double duty, bool bridge_enabled, double dt_s);

  // Advances by dt_s with the motor pulley moved kinematically from its present angle
  // to pulley_rad at constant speed (the motor model is bypassed: no current, no
  // motor losses; the source supplies whatever torque it takes). Everything downstream
  // stays dynamic. The work done (on the cable, plus the rotor's kinetic energy at the
  // imposed speed) is booked in prescribed_work_J. Throws like Step().
  void StepPrescribedMotor(double pulley_rad, double dt_s);

  // Replaces the interface (re-donning mid-run) keeping the mechanical state; the
  // jump in interface potential energy is booked in interface_change_work_J. Throws
  // std::runtime_error if the interface parameters are invalid.
  void SetInterface(const InterfaceParams& interface);

  // The motor timer count sampled at the end of the last step (faults applied).
  std::uint16_t MotorCount() const { return motor_count_; }

  // One SPI read of the joint encoder now: 16-bit AS5047P read frame, with noise
  // (a fresh draw each read) and any active joint fault.
  std::uint16_t JointFrame();

  // Starts a fault; a fault of the same kind already active is replaced.
  void InjectFault(const SensorFault& fault);
  void ClearFaults();

  // Filled in on the first call after a step (a step does not pay for it).
  const Truth& truth() const {
    if (truth_stale_) RefreshTruth();
    return truth_;
  }
  double time() const { return time_s_; }
  // truth().interface_energy_J and .interface_power_W alone, for a caller that records
  // them every tick.
  double interface_energy_J() const { return x_(Index::kInterfaceEnergy); }
  double interface_power_W() const;
  const PlantParams& params() const { return params_; }
  const State& state() const { return x_; }

 private:
  struct Drive {
    bool prescribed = false;
    bool bridge_enabled = false;  // motor mode
    double voltage_V = 0;         // motor mode
    double pulley_velocity = 0;   // prescribed mode, rad/s
  };
  // What a substep of length h needs beyond the parameters (recomputed when h or the
  // interface changes).
  struct SubstepConstants {
    double h = 0;
    double half_h = 0;
    double rotor_mass = 0;     // 2·J_eff/h, N·m·s/rad
    double cable_mass = 0;     // 2·J_c/h
    double joint_mass = 0;     // 2·J_j/h
    double current_decay = 0;  // e^(−hR/L)
    double charge_weight = 0;  // ∫₀ʰ e^(−tR/L) dt, s
    double square_weight = 0;  // ∫₀ʰ e^(−2tR/L) dt, s
    double charge_per_V = 0;  // (h − charge_weight)/R: charge per volt of R·i_∞, s/Ω
    double back_emf_slope = 0;     // (k_t·N)²·charge_per_V/h: the winding's damping
    double torque_per_charge = 0;  // k_t·N/h, N·m per coulomb over the substep
    double contact_slope = 0;      // k_c·h/2
    double sea_slope = 0;          // K·h/2: the SEA torque per rad/s of midpoint speed
    double maxwell_beta = 0;       // SLS: h·k_2/(2b), x̄ = (x_0 + β·θ̄_j)/(1 + β)
    // SLS with b = 0 (β infinite): a dashpot that resists nothing lets its arm follow
    // the joint, so the arm carries no force and the attachment is k alone.
    bool maxwell_free = false;
    double interface_slope = 0;   // dτ_if/dω̄_j
    double joint_diagonal = 0;    // d(joint equation)/dω̄_j
    double joint_gain = 0;        // K·h/2 / joint_diagonal: dω̄_j/dω̄_c
    double joint_compliance = 0;  // 1 / joint_diagonal
    double cable_diagonal = 0;    // d(cable equation)/dω̄_c with the joint eliminated,
                                  // viscous sheath friction included
  };

  // The midpoint speeds ω̄_m, ω̄_c of the last substep: Newton's starting point for the
  // next one of the same length.
  struct Midpoint {
    bool valid = false;
    double motor = 0;
    double cable = 0;
  };

  void Derive();
  SubstepConstants MakeConstants(double h) const;
  // One substep from `in` under drive, written to *out (which may be &in); false, and
  // *out untouched, if the Newton iteration does not converge. Newton starts from the
  // speeds extrapolated from *midpoint if it is valid (the previous substep, of length
  // k.h), else from the speeds at the start; *midpoint receives this substep's.
  bool Substep(const Drive& drive, const SubstepConstants& k, const State& in, State* out,
               Midpoint* midpoint) const;
  // The substep k as two halves, each halved again (up to `depth` times) where it does
  // not converge; false, and *x untouched, if even that fails.
  bool Halve(const Drive& drive, const SubstepConstants& k, int depth, State* x) const;
  void Integrate(const Drive& drive, double dt_s);
  void ReturnMagneticEnergy();
  double InterfacePotential(const State& x) const;
  double InterfaceTorque(const State& x) const;
  void RefreshTruth() const;
  void SampleMotorCount();
  // The next N(0, 1) value of the sensors' noise: StandardNormal's sequence for the
  // seed (to 1 ulp), computed a block at a time.
  double Gaussian();
  void RefillNoise();

  struct FaultSlot {
    bool active = false;
    std::uint32_t remaining = 0;  // 0 with active: until cleared
    std::int32_t jump_counts = 0;
  };
  static constexpr int kFaultKinds = 5;
  bool ConsumeFault(FaultSlot* slot);

  PlantParams params_;
  // Derived constants (Derive()).
  double n_ = 0, k_t_ = 0, j_eff_ = 0, b_m_reflected_ = 0, k_sea_ = 0;
  double coulomb_reflected_ = 0;     // N·T_f, N·m at the pulley
  double coulomb_gain_ = 0;          // N/ω_f, per pulley rad/s
  double bristle_relax_ = 0;         // σ0/F_c, per rad of cable travel (0: no bristle)
  double motor_counts_per_rad_ = 0;  // motor counts per pulley radian
  SubstepConstants step_;            // for the last substep length used
  Midpoint midpoint_;                // of the last substep of length step_.h
  double step_dt_s_ = 0;             // the last Step's dt, and its substeps
  int substeps_ = 1;

  State x_ = State::Zero();
  bool prescribed_mode_ = false;
  double interface_change_work_J_ = 0;
  double time_s_ = 0;
  double voltage_V_ = 0;  // applied over the last step
  double initial_stored_J_ = 0;
  mutable Truth truth_;
  mutable bool truth_stale_ = true;

  std::mt19937_64 rng_;
  static constexpr int kNoiseBlock = 64;  // values, an even number
  double noise_[kNoiseBlock] = {};
  int noise_next_ = kNoiseBlock;  // the next value to use; kNoiseBlock: none left

  std::uint16_t motor_count_ = 0;
  std::uint16_t last_joint_frame_ = 0;
  bool has_last_joint_frame_ = false;
  FaultSlot faults_[kFaultKinds];
  std::uint16_t stuck_motor_count_ = 0;
  std::uint16_t stuck_joint_frame_ = 0;
};

// A Gaussian N(0, 1) draw from raw mt19937_64 output (Box–Muller on 53-bit uniforms),
// identical on every standard library, unlike std::normal_distribution. *spare holds
// the second value of a pair between calls.
double StandardNormal(std::mt19937_64* rng, bool* has_spare, double* spare);

}  // namespace mjc::plant
