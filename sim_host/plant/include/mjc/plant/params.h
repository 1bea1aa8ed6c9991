// Parameters of the simulated joint: motor and gearbox, Bowden cable with slack and
// sheath friction, SEA springs, joint, attachment interface to the grounded hand,
// sensors, integration step. Loaded from named JSON files in sim_host/params
// (README.md there gives every value and where it came from).
//
// Every physical quantity is a double in SI units with the unit in its name. The member
// initialisers are the "default" set (the robot alone, no human) with the sensor noise
// off; params/default.json holds the same values (noise on) and a test checks that
// they agree.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace mjc::plant {

// Brushed DC motor with gearhead. Numbers: Faulhaber 1331T012SR datasheet (see
// params/README.md). k_t is used for both torque (N·m/A) and back-EMF (V·s/rad): in SI
// they are the same constant, and using one keeps the model's energy exact.
struct MotorParams {
  double supply_V = 12.0;                    // bridge supply, (0, 60]
  double resistance_ohm = 13.7;              // terminal resistance R, [0.1, 1000]
  double inductance_H = 310e-6;              // rotor inductance L, [1e-6, 0.1]
  double torque_constant_Nm_per_A = 0.0114;  // k_t = k_e, [1e-4, 1]
  double rotor_inertia_kg_m2 = 1.0e-7;       // J_m at the shaft, [1e-9, 1e-3]
  double viscous_Nm_s_per_rad = 1.0e-8;      // b_m at the shaft, [0, 1e-3]
  // Coulomb friction of brushes, bearings and gearhead at the shaft, regularised as
  // T_f·tanh(ω_shaft/ω_f). [0, 0.1] N·m and (0, 1000] rad/s.
  double coulomb_Nm = 2.0e-4;            // T_f
  double coulomb_speed_rad_s = 2.0;      // ω_f
  double gear_ratio = 100.0;             // N, shaft turns per pulley turn, [1, 1e4]
  double output_inertia_kg_m2 = 2.0e-6;  // pulley + gear output, at the pulley, [0, 1e-2]
};

// Bowden cable between the motor pulley and the SEA springs' input (the cable side θ̃).
// Angles and torques are in joint coordinates (rad and N·m at the joint pulley); the
// motor pulley appears as α·θ_m.
struct CableParams {
  double alpha = 1.0;           // r_m / r_j, (0, 8)
  double c_right_rad = 0.0192;  // c_r: pushes positive when α(θ_m − c_r) ≥ θ̃, [-0.5, 0.5]
  double c_left_rad = -0.0157;  // c_l: pushes negative when α(θ_m − c_l) ≤ θ̃, [-0.5, c_r]
  // Penalty contact at the dead band's edges (a stiff cable): torque
  // max(0, k_c·δ + c_c·min(δ/δ_r, 1)·δ̇) for penetration δ > 0.
  double contact_stiffness_Nm_per_rad = 1000.0;  // k_c, [1, 1e6]
  double contact_damping_Nm_s_per_rad = 0.08;    // c_c, [0, 10]
  double contact_damping_ramp_rad = 1e-4;        // δ_r, (0, 0.01]
  // Sheath friction on the cable side: Dahl bristle (Coulomb level F_c, stiffness σ0)
  // plus viscous b_f. F_c = 0 leaves only the viscous part.
  double coulomb_Nm = 0.3;                       // F_c, [0, 10]
  double bristle_stiffness_Nm_per_rad = 1000.0;  // σ0, [1, 1e6]
  double viscous_Nm_s_per_rad = 0.02;            // b_f, [0, 10]
  double inertia_kg_m2 = 2.0e-6;  // J_c of cable and spring carriages, [1e-9, 1e-2]
};

// The two preloaded springs: joint torque K·(θ̃ − θ_j), K = 2·k·r_j².
struct SeaParams {
  double spring_rate_N_per_m = 3150.0;  // k of one spring, (0, 1e6]
  double joint_pulley_radius_m = 0.01;  // r_j, (0, 0.1]
  double Stiffness() const {            // K, N·m/rad
    return 2.0 * spring_rate_N_per_m * joint_pulley_radius_m * joint_pulley_radius_m;
  }
};

// The exoskeleton link about the MCP axis.
struct JointParams {
  double inertia_kg_m2 = 1.5e-5;       // J_j, [1e-8, 0.1]
  double viscous_Nm_s_per_rad = 1e-3;  // b_j (bearings), [0, 10]
};

enum class InterfaceModel : std::uint8_t {
  // τ_if = k·θ_j + b·θ̇_j + τ_0
  kKelvinVoigt = 0,
  // τ_if = k·θ_j + k_2·(θ_j − x) + τ_0, b·ẋ = k_2·(θ_j − x): a spring k in parallel
  // with a Maxwell arm (spring k_2 in series with dashpot b); x is the internal node.
  kStandardLinearSolid = 1,
};

// The attachment (dorsal plate, straps, soft tissue) between the joint and the
// grounded hand. With present = false the joint moves freely (the robot alone, as in
// the calibration sweep).
struct InterfaceParams {
  bool present = false;
  InterfaceModel model = InterfaceModel::kKelvinVoigt;
  double stiffness_Nm_per_rad = 0.0;          // k (SLS: the parallel spring), [0, 1000]
  double damping_Nm_s_per_rad = 0.0;          // b (SLS: the Maxwell dashpot), [0, 100]
  double maxwell_stiffness_Nm_per_rad = 0.0;  // k_2, SLS only, [0, 1000]
  // τ_0: constant torque of the strap preload on the joint, N·m, [-1, 1]. Positive
  // pushes the joint toward extension (negative θ_j).
  double preload_Nm = 0.0;
};

struct SensorParams {
  // Quadrature edges per MOTOR-SHAFT revolution; must match the firmware's
  // MotorEncoderConfig (2048 edges, 100:1 gear). [1, 2^20]
  std::int32_t motor_counts_per_rev = 2048;
  // Timer count at θ_m = 0, [0, 65535].
  std::uint16_t motor_count_at_zero = 0;
  // Gaussian jitter on the motor shaft angle before quantisation, counts rms, [0, 100].
  double motor_noise_counts = 0.0;
  // The 14-bit count at θ_j = 0, [0, 16383].
  std::uint16_t joint_zero_count = 0;
  // Gaussian noise on the joint angle before quantisation, counts rms, [0, 100].
  double joint_noise_counts = 0.0;
  // Seed of the noise generator (std::mt19937_64); Reset() restarts the sequence.
  std::uint64_t noise_seed = 1;
};

struct IntegrationParams {
  // Longest substep, s, [1e-7, 1e-3]: a Step of dt runs ceil(dt / max_step_s) equal
  // substeps (100 µs: one a 10 kHz tick; the scheme is in plant.h).
  double max_step_s = 1e-4;
};

struct PlantParams {
  std::string name = "default";
  std::string description;
  MotorParams motor;
  CableParams cable;
  SeaParams sea;
  JointParams joint;
  InterfaceParams interface;
  SensorParams sensors;
  IntegrationParams integration;
};

// Loads MJC_PARAMS_DIR/<name>.json ("default", "subject1", "subject2", "subject3"; a
// name is [a-z0-9_-]+). Throws std::runtime_error naming the file and the field when
// the file is missing or unreadable, the JSON is malformed, a field is missing, has
// the wrong type, is out of range, or is unknown (a misspelt field is an error, not a
// silently ignored value).
PlantParams LoadPlantParams(std::string_view name);

// The same from an explicit path.
PlantParams LoadPlantParamsFile(const std::string& path);

// The same from JSON text; `source` names it in error messages.
PlantParams ParsePlantParams(std::string_view json_text, std::string_view source);

// JSON text of a parameter set (the file format above, every field).
std::string PlantParamsToJson(const PlantParams& params);

// Throws std::runtime_error("<source>: field '<section.field>' ...") if any value is out
// of its documented range or the substep cannot resolve a mode the sensors follow.
void ValidatePlantParams(const PlantParams& params, std::string_view source);

// Re-donning: the same subject with the exoskeleton taken off and put on again (the
// straps re-tensioned, the plate a few mm elsewhere). Seeded (std::mt19937_64 and our
// own Box–Muller, so the same on every platform) multiplicative log-normal factors,
// each clipped at ±3σ:
//   interface stiffness (and the SLS Maxwell spring, by the same factor)  σ = 7 %
//   interface damping                                                     σ = 8.5 %
//   strap preload                                                         σ = 25 %
// On the shipped subjects this spreads η at 25° by ≈ 2.8 points (std), as between the
// paper's re-donned trials (Table I: 42.1–48.9 %, 3.0 points overall). Everything else
// is copied; the name gets "+redon<seed>". Same seed → same result.
PlantParams Redon(const PlantParams& params, std::uint64_t seed);

}  // namespace mjc::plant
