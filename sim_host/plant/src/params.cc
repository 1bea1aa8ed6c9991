// Parameter sets: JSON in and out, range checks, re-donning.
#include "mjc/plant/params.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <span>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

#include "mjc/plant/plant.h"
#include "mjc/strict_json.h"

#ifndef MJC_PARAMS_DIR
#error "MJC_PARAMS_DIR must name the directory of the parameter sets"
#endif

namespace mjc::plant {
namespace {

using Json = nlohmann::ordered_json;

std::string Quote(std::string_view s) { return "'" + std::string(s) + "'"; }

[[noreturn]] void FieldError(std::string_view source, std::string_view field,
                             const std::string& what) {
  throw std::runtime_error(std::string(source) + ": field " + Quote(field) + " " + what);
}

std::string Number(double v) {
  std::ostringstream out;
  out.precision(17);
  out << v;
  return out.str();
}

// ---------------------------------------------------------------------------------------
// Reading
// ---------------------------------------------------------------------------------------

// The fields' reader every strict loader shares (mjc/strict_json.h); its messages are
// FieldError's.
using Reader = strict::FieldReader<Json>;

const char* ModelName(InterfaceModel model) {
  return model == InterfaceModel::kKelvinVoigt ? "kelvin_voigt" : "standard_linear_solid";
}

// An integer field and the range the file may give it (the field's type's, or tighter).
template <class T>
struct Ranged {
  T& field;
  std::int64_t lo, hi;
};
template <class T>
Ranged<T> InRange(T& field, std::int64_t lo, std::int64_t hi) {
  return {field, lo, hi};
}

// Every field of a parameter set below its name and description, once, in file order:
// f(section, key, field). The reader and the writer both walk it, so a field added here
// is read, checked for, and written.
template <class P, class F>
void VisitFields(P& p, F&& f) {
  f("motor", "supply_V", p.motor.supply_V);
  f("motor", "resistance_ohm", p.motor.resistance_ohm);
  f("motor", "inductance_H", p.motor.inductance_H);
  f("motor", "torque_constant_Nm_per_A", p.motor.torque_constant_Nm_per_A);
  f("motor", "rotor_inertia_kg_m2", p.motor.rotor_inertia_kg_m2);
  f("motor", "viscous_Nm_s_per_rad", p.motor.viscous_Nm_s_per_rad);
  f("motor", "coulomb_Nm", p.motor.coulomb_Nm);
  f("motor", "coulomb_speed_rad_s", p.motor.coulomb_speed_rad_s);
  f("motor", "gear_ratio", p.motor.gear_ratio);
  f("motor", "output_inertia_kg_m2", p.motor.output_inertia_kg_m2);
  f("cable", "alpha", p.cable.alpha);
  f("cable", "c_right_rad", p.cable.c_right_rad);
  f("cable", "c_left_rad", p.cable.c_left_rad);
  f("cable", "contact_stiffness_Nm_per_rad", p.cable.contact_stiffness_Nm_per_rad);
  f("cable", "contact_damping_Nm_s_per_rad", p.cable.contact_damping_Nm_s_per_rad);
  f("cable", "contact_damping_ramp_rad", p.cable.contact_damping_ramp_rad);
  f("cable", "coulomb_Nm", p.cable.coulomb_Nm);
  f("cable", "bristle_stiffness_Nm_per_rad", p.cable.bristle_stiffness_Nm_per_rad);
  f("cable", "viscous_Nm_s_per_rad", p.cable.viscous_Nm_s_per_rad);
  f("cable", "inertia_kg_m2", p.cable.inertia_kg_m2);
  f("sea", "spring_rate_N_per_m", p.sea.spring_rate_N_per_m);
  f("sea", "joint_pulley_radius_m", p.sea.joint_pulley_radius_m);
  f("joint", "inertia_kg_m2", p.joint.inertia_kg_m2);
  f("joint", "viscous_Nm_s_per_rad", p.joint.viscous_Nm_s_per_rad);
  f("interface", "present", p.interface.present);
  f("interface", "model", p.interface.model);
  f("interface", "stiffness_Nm_per_rad", p.interface.stiffness_Nm_per_rad);
  f("interface", "damping_Nm_s_per_rad", p.interface.damping_Nm_s_per_rad);
  f("interface", "maxwell_stiffness_Nm_per_rad",
    p.interface.maxwell_stiffness_Nm_per_rad);
  f("interface", "preload_Nm", p.interface.preload_Nm);
  f("sensors", "motor_counts_per_rev",
    InRange(p.sensors.motor_counts_per_rev, 1, std::int64_t{1} << 20));
  f("sensors", "motor_count_at_zero", InRange(p.sensors.motor_count_at_zero, 0, 65535));
  f("sensors", "motor_noise_counts", p.sensors.motor_noise_counts);
  f("sensors", "joint_zero_count", InRange(p.sensors.joint_zero_count, 0, 16383));
  f("sensors", "joint_noise_counts", p.sensors.joint_noise_counts);
  f("sensors", "noise_seed", p.sensors.noise_seed);
  f("integration", "max_step_s", p.integration.max_step_s);
}

// The sections in file order, each with its keys.
std::vector<std::pair<std::string_view, std::vector<std::string_view>>> Sections() {
  std::vector<std::pair<std::string_view, std::vector<std::string_view>>> out;
  const PlantParams p;
  VisitFields(p, [&out](std::string_view section, std::string_view key, const auto&) {
    if (out.empty() || out.back().first != section) out.push_back({section, {}});
    out.back().second.push_back(key);
  });
  return out;
}

// ---------------------------------------------------------------------------------------
// Validation
// ---------------------------------------------------------------------------------------

class Checker {
 public:
  explicit Checker(std::string_view source) : source_(source) {}

  // v in [lo, hi] (or (lo, hi] with open_low), finite.
  void Range(double v, std::string_view field, double lo, double hi,
             bool open_low = false) const {
    const bool ok = std::isfinite(v) && (open_low ? v > lo : v >= lo) && v <= hi;
    if (!ok) {
      FieldError(source_, field,
                 "= " + Number(v) + " is outside " + (open_low ? "(" : "[") + Number(lo) +
                     ", " + Number(hi) + "]");
    }
  }

 private:
  std::string_view source_;
};

double Clip3(double g) { return std::clamp(g, -3.0, 3.0); }

}  // namespace

void ValidatePlantParams(const PlantParams& p, std::string_view source) {
  const Checker c(source);
  const MotorParams& m = p.motor;
  c.Range(m.supply_V, "motor.supply_V", 0.0, 60.0, true);
  c.Range(m.resistance_ohm, "motor.resistance_ohm", 0.1, 1000.0);
  c.Range(m.inductance_H, "motor.inductance_H", 1e-6, 0.1);
  c.Range(m.torque_constant_Nm_per_A, "motor.torque_constant_Nm_per_A", 1e-4, 1.0);
  c.Range(m.rotor_inertia_kg_m2, "motor.rotor_inertia_kg_m2", 1e-9, 1e-3);
  c.Range(m.viscous_Nm_s_per_rad, "motor.viscous_Nm_s_per_rad", 0.0, 1e-3);
  c.Range(m.coulomb_Nm, "motor.coulomb_Nm", 0.0, 0.1);
  c.Range(m.coulomb_speed_rad_s, "motor.coulomb_speed_rad_s", 0.0, 1000.0, true);
  c.Range(m.gear_ratio, "motor.gear_ratio", 1.0, 1e4);
  c.Range(m.output_inertia_kg_m2, "motor.output_inertia_kg_m2", 0.0, 1e-2);

  const CableParams& k = p.cable;
  c.Range(k.alpha, "cable.alpha", 0.0, 8.0, true);
  if (!(k.alpha < 8.0)) FieldError(source, "cable.alpha", "must be below 8");
  c.Range(k.c_right_rad, "cable.c_right_rad", -0.5, 0.5);
  c.Range(k.c_left_rad, "cable.c_left_rad", -0.5, 0.5);
  if (k.c_left_rad > k.c_right_rad) {
    FieldError(source, "cable.c_left_rad",
               "= " + Number(k.c_left_rad) + " is above cable.c_right_rad = " +
                   Number(k.c_right_rad) + " (the dead band needs c_l <= c_r)");
  }
  c.Range(k.contact_stiffness_Nm_per_rad, "cable.contact_stiffness_Nm_per_rad", 1.0, 1e6);
  c.Range(k.contact_damping_Nm_s_per_rad, "cable.contact_damping_Nm_s_per_rad", 0.0,
          10.0);
  c.Range(k.contact_damping_ramp_rad, "cable.contact_damping_ramp_rad", 0.0, 0.01, true);
  c.Range(k.coulomb_Nm, "cable.coulomb_Nm", 0.0, 10.0);
  c.Range(k.bristle_stiffness_Nm_per_rad, "cable.bristle_stiffness_Nm_per_rad", 1.0, 1e6);
  c.Range(k.viscous_Nm_s_per_rad, "cable.viscous_Nm_s_per_rad", 0.0, 10.0);
  c.Range(k.inertia_kg_m2, "cable.inertia_kg_m2", 1e-9, 1e-2);

  c.Range(p.sea.spring_rate_N_per_m, "sea.spring_rate_N_per_m", 0.0, 1e6, true);
  c.Range(p.sea.joint_pulley_radius_m, "sea.joint_pulley_radius_m", 0.0, 0.1, true);
  c.Range(p.joint.inertia_kg_m2, "joint.inertia_kg_m2", 1e-8, 0.1);
  c.Range(p.joint.viscous_Nm_s_per_rad, "joint.viscous_Nm_s_per_rad", 0.0, 10.0);

  const InterfaceParams& ip = p.interface;
  if (ip.model != InterfaceModel::kKelvinVoigt &&
      ip.model != InterfaceModel::kStandardLinearSolid) {
    FieldError(source, "interface.model", "is not a known model");
  }
  c.Range(ip.stiffness_Nm_per_rad, "interface.stiffness_Nm_per_rad", 0.0, 1000.0);
  c.Range(ip.damping_Nm_s_per_rad, "interface.damping_Nm_s_per_rad", 0.0, 100.0);
  c.Range(ip.maxwell_stiffness_Nm_per_rad, "interface.maxwell_stiffness_Nm_per_rad", 0.0,
          1000.0);
  c.Range(ip.preload_Nm, "interface.preload_Nm", -1.0, 1.0);

  const SensorParams& s = p.sensors;
  if (s.motor_counts_per_rev < 1 || s.motor_counts_per_rev > (1 << 20)) {
    FieldError(
        source, "sensors.motor_counts_per_rev",
        "= " + std::to_string(s.motor_counts_per_rev) + " is outside [1, 1048576]");
  }
  c.Range(s.motor_noise_counts, "sensors.motor_noise_counts", 0.0, 100.0);
  if (s.joint_zero_count > 16383) {
    FieldError(source, "sensors.joint_zero_count",
               "= " + std::to_string(s.joint_zero_count) + " is outside [0, 16383]");
  }
  c.Range(s.joint_noise_counts, "sensors.joint_noise_counts", 0.0, 100.0);
  c.Range(p.integration.max_step_s, "integration.max_step_s", 1e-7, 1e-3);

  // The substep is implicit where the model is stiff (the current in closed form, the
  // mechanics implicit midpoint: plant.h), so what bounds it is accuracy on the modes
  // the sensors and the interface follow. Midpoint's relative phase error on a mode
  // of rate ω is (ω·h)²/12: ω·h ≤ 0.2 keeps it at 0.33 %. |λ| of a body of inertia J
  // on stiffness k with damping b is at most max(√(k/J), b/J); the damping rates of
  // the joint and the cable side are left out (midpoint damps them, and their speed
  // is not what the sensors read).
  const double k_sea = p.sea.Stiffness();
  const double j_eff =
      m.rotor_inertia_kg_m2 * m.gear_ratio * m.gear_ratio + m.output_inertia_kg_m2;
  const double k_if =
      ip.present ? ip.stiffness_Nm_per_rad + ip.maxwell_stiffness_Nm_per_rad : 0.0;
  struct Mode {
    const char* what;
    double rate;
  };
  const Mode modes[] = {
      {"rotor on the contact and its friction",
       std::max(std::sqrt(k.contact_stiffness_Nm_per_rad * k.alpha * k.alpha / j_eff),
                (m.coulomb_Nm / m.coulomb_speed_rad_s + m.viscous_Nm_s_per_rad) *
                    m.gear_ratio * m.gear_ratio / j_eff)},
      {"joint on springs and interface",
       std::sqrt((k_sea + k_if) / p.joint.inertia_kg_m2)},
      {"interface Maxwell arm k_2/b",
       ip.present && ip.model == InterfaceModel::kStandardLinearSolid &&
               ip.damping_Nm_s_per_rad > 0.0
           ? ip.maxwell_stiffness_Nm_per_rad / ip.damping_Nm_s_per_rad
           : 0.0},
  };
  for (const Mode& mode : modes) {
    constexpr double kMaxRateStep = 0.2;
    if (mode.rate * p.integration.max_step_s > kMaxRateStep) {
      FieldError(source, "integration.max_step_s",
                 "= " + Number(p.integration.max_step_s) + " s is too long for the " +
                     mode.what + " (" + Number(mode.rate) + " 1/s): it must be at most " +
                     Number(kMaxRateStep / mode.rate) + " s");
    }
  }
}

PlantParams ParsePlantParams(std::string_view json_text, std::string_view source) {
  const Json root = strict::ParseObject<Json>(json_text, source);
  const Reader r(source);
  const auto sections = Sections();
  std::vector<std::string_view> top = {"name", "description"};
  for (const auto& [section, keys] : sections) top.push_back(section);
  r.CheckKnown(root, "", top);
  PlantParams p;
  p.name = r.String(root, "", "name");
  p.description = root.contains("description") ? r.String(root, "", "description") : "";
  // A section is checked (an object, no unknown key) before its first field is read.
  std::size_t next_section = 0;
  const Json* s = nullptr;
  VisitFields(p, [&](std::string_view section, std::string_view key, auto&& field) {
    if (s == nullptr || sections[next_section - 1].first != section) {
      s = &r.Section(root, section, sections[next_section++].second);
    }
    using T = std::remove_cvref_t<decltype(field)>;
    if constexpr (std::is_same_v<T, double>) {
      field = r.Double(*s, section, key);
    } else if constexpr (std::is_same_v<T, bool>) {
      field = r.Bool(*s, section, key);
    } else if constexpr (std::is_same_v<T, std::uint64_t>) {
      field = r.Unsigned64(*s, section, key);
    } else if constexpr (std::is_same_v<T, InterfaceModel>) {
      const std::string model = r.String(*s, section, key);
      if (model == ModelName(InterfaceModel::kKelvinVoigt)) {
        field = InterfaceModel::kKelvinVoigt;
      } else if (model == ModelName(InterfaceModel::kStandardLinearSolid)) {
        field = InterfaceModel::kStandardLinearSolid;
      } else {
        FieldError(
            source, "interface.model",
            "= \"" + model + "\" is not \"kelvin_voigt\" or \"standard_linear_solid\"");
      }
    } else {  // Ranged<integer>
      using Integer = std::remove_cvref_t<decltype(field.field)>;
      field.field = static_cast<Integer>(r.Integer(*s, section, key, field.lo, field.hi));
    }
  });

  ValidatePlantParams(p, source);
  return p;
}

PlantParams LoadPlantParamsFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open the parameter file");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw std::runtime_error(path + ": read error");
  return ParsePlantParams(text.str(), path);
}

PlantParams LoadPlantParams(std::string_view name) {
  const bool valid = !name.empty() && std::all_of(name.begin(), name.end(), [](char ch) {
    return (ch >= 'a' && ch <= 'z') || (ch >= '0' && ch <= '9') || ch == '_' || ch == '-';
  });
  if (!valid) {
    throw std::runtime_error("parameter set name " + Quote(name) +
                             " is not [a-z0-9_-]+ (use LoadPlantParamsFile for a path)");
  }
  return LoadPlantParamsFile(std::string(MJC_PARAMS_DIR) + "/" + std::string(name) +
                             ".json");
}

std::string PlantParamsToJson(const PlantParams& p) {
  Json root;
  root["name"] = p.name;
  root["description"] = p.description;
  VisitFields(p,
              [&root](std::string_view section, std::string_view key, const auto& field) {
                using T = std::remove_cvref_t<decltype(field)>;
                Json& value = root[std::string(section)][std::string(key)];
                if constexpr (std::is_same_v<T, InterfaceModel>) {
                  value = ModelName(field);
                } else if constexpr (requires { field.field; }) {
                  value = field.field;
                } else {
                  value = field;
                }
              });
  return root.dump(2) + "\n";
}

PlantParams Redon(const PlantParams& params, std::uint64_t seed) {
  // Spreads (log-normal σ) chosen so the shipped subjects' η varies between re-donnings
  // about as much as Table I of the paper (3 points std overall); params/README.md.
  constexpr double kStiffnessSigma = 0.07;
  constexpr double kDampingSigma = 0.085;
  constexpr double kPreloadSigma = 0.25;
  std::mt19937_64 rng(seed);
  bool has_spare = false;
  double spare = 0.0;
  const double g_stiffness = Clip3(StandardNormal(&rng, &has_spare, &spare));
  const double g_damping = Clip3(StandardNormal(&rng, &has_spare, &spare));
  const double g_preload = Clip3(StandardNormal(&rng, &has_spare, &spare));
  PlantParams p = params;
  const double stiffness_factor = std::exp(kStiffnessSigma * g_stiffness);
  p.interface.stiffness_Nm_per_rad *= stiffness_factor;
  p.interface.maxwell_stiffness_Nm_per_rad *= stiffness_factor;
  p.interface.damping_Nm_s_per_rad *= std::exp(kDampingSigma * g_damping);
  p.interface.preload_Nm =
      std::clamp(p.interface.preload_Nm * std::exp(kPreloadSigma * g_preload), -1.0, 1.0);
  p.interface.stiffness_Nm_per_rad = std::min(p.interface.stiffness_Nm_per_rad, 1000.0);
  p.interface.maxwell_stiffness_Nm_per_rad =
      std::min(p.interface.maxwell_stiffness_Nm_per_rad, 1000.0);
  p.interface.damping_Nm_s_per_rad = std::min(p.interface.damping_Nm_s_per_rad, 100.0);
  p.name = params.name + "+redon" + std::to_string(seed);
  return p;
}

}  // namespace mjc::plant
