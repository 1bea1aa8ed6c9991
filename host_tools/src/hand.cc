#include "mjc/host/hand.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <stdexcept>

#include "mjc/host/report.h"
#include "mjc/protocol/can_frame.h"
#include "mjc/strict_json.h"

namespace mjc::host {
namespace {

using Json = nlohmann::json;
using Reader = strict::FieldReader<Json>;

std::string Number(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", v);
  return text;
}

bool NameOf(std::string_view name, std::size_t most, bool lower_only) {
  if (name.empty() || name.size() > most) return false;
  return std::all_of(name.begin(), name.end(), [lower_only](char c) {
    const bool lower = (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
    return lower || (!lower_only && ((c >= 'A' && c <= 'Z') || c == '-' || c == '.'));
  });
}

// A Linux interface name, as the config file's "iface" (IFNAMSIZ - 1 characters).
bool InterfaceName(std::string_view name) { return NameOf(name, 15, false); }

// A subject's limit: a finite number, > 0 (or < 0 for the extension).
double Limit(const Reader& r, const Json& subject, std::string_view key, bool negative) {
  const double v = r.Double(subject, "subject", key);
  if (!std::isfinite(v) || (negative ? v >= 0.0 : v <= 0.0)) {
    r.Fail(strict::FieldName("subject", key),
           "= " + Number(v) + " must be " + (negative ? "below" : "above") + " 0");
  }
  return v;
}

HandJoint ParseJoint(const Json& item, std::size_t index, const std::string& source,
                     const std::string& folder) {
  const std::string at = source + ": joints[" + std::to_string(index) + "]";
  if (!item.is_object()) throw std::runtime_error(at + " must be an object");
  HandJoint joint;
  {
    const Reader r(at);
    r.CheckKnown(item, "", kHandJointKeys);
    joint.name = r.String(item, "", "name");
    if (!NameOf(joint.name, 32, true)) {
      r.Fail("name", "= \"" + joint.name + "\" is not 1-32 of [a-z0-9_]");
    }
  }
  const std::string who = source + ": joint '" + joint.name + "'";
  const Reader r(who);
  joint.node = static_cast<int>(
      r.Integer(item, "", "node", protocol::kMinNode, protocol::kMaxNode));
  joint.robot = r.String(item, "", "robot");
  if (joint.robot.empty()) r.Fail("robot", "is empty: give the description's path");
  joint.robot_path =
      (std::filesystem::path(folder) / joint.robot).lexically_normal().string();
  std::string why;
  const auto description = LoadRobotDescription(joint.robot_path, &why);
  if (!description) throw std::runtime_error(who + ": robot description refused: " + why);
  const RobotDescription& d = *description;
  joint.description = d;

  const Json& subject = r.Value(item, "", "subject");
  if (!subject.is_object()) r.Fail("subject", "must be an object");
  r.CheckKnown(subject, "subject.", kSubjectLimitKeys);
  SubjectLimits& s = joint.subject;
  s.extension_deg = Limit(r, subject, "extension_deg", true);
  s.flexion_deg = Limit(r, subject, "flexion_deg", false);
  s.torque_Nm = Limit(r, subject, "torque_Nm", false);
  s.energy_per_window_mJ = Limit(r, subject, "energy_per_window_mJ", false);
  const std::string of = " of its robot description " + d.name + " (" + joint.robot + ")";
  if (s.extension_deg < d.extension_limit_deg) {
    r.Fail("subject.extension_deg", "= " + Number(s.extension_deg) +
                                        "° is beyond the extension limit " +
                                        Number(d.extension_limit_deg) + "°" + of);
  }
  if (s.flexion_deg > d.flexion_limit_deg) {
    r.Fail("subject.flexion_deg", "= " + Number(s.flexion_deg) +
                                      "° is beyond the flexion limit " +
                                      Number(d.flexion_limit_deg) + "°" + of);
  }
  if (s.torque_Nm > d.torque_limit_Nm) {
    r.Fail("subject.torque_Nm", "= " + Number(s.torque_Nm) +
                                    " N·m is above the torque limit " +
                                    Number(d.torque_limit_Nm) + " N·m" + of);
  }
  // A window (half a cycle) moves the joint one way through at most the subject's
  // range, at most at the subject's torque: a larger energy could never be reached,
  // so it would limit nothing.
  const double range_rad = (s.flexion_deg - s.extension_deg) * std::numbers::pi / 180.0;
  const double most_mJ = s.torque_Nm * range_rad * 1000.0;
  if (s.energy_per_window_mJ > most_mJ) {
    r.Fail("subject.energy_per_window_mJ",
           "= " + Number(s.energy_per_window_mJ) +
               " mJ is more than a window can carry within the subject's limits (" +
               Number(s.torque_Nm) + " N·m over " + Number(s.flexion_deg) + "° − (" +
               Number(s.extension_deg) + "°) = " + Number(most_mJ) + " mJ)");
  }
  return joint;
}

Hand Parse(std::string_view text, std::string_view source, const std::string& folder) {
  const std::string where(source);
  const Json root = strict::ParseObject<Json>(text, where);
  const Reader r(where);
  r.CheckKnown(root, "", kHandKeys);
  Hand hand;
  hand.source = where;
  hand.name = r.String(root, "", "name");
  if (!NameOf(hand.name, 64, false)) {
    r.Fail("name", "= \"" + hand.name + "\" is not 1-64 of [A-Za-z0-9_.-]");
  }
  if (root.contains("description")) hand.description = r.String(root, "", "description");
  if (root.contains("iface")) {
    hand.iface = r.String(root, "", "iface");
    if (!InterfaceName(*hand.iface)) {
      r.Fail("iface", "= \"" + *hand.iface +
                          "\" is not an interface name (1-15 of [A-Za-z0-9_.-])");
    }
  }
  const Json& joints = r.Value(root, "", "joints");
  if (!joints.is_array()) r.Fail("joints", "must be an array of joints");
  if (joints.empty() || joints.size() > protocol::kMaxNode) {
    r.Fail("joints", "holds " + std::to_string(joints.size()) +
                         " joints: a hand has 1 to " +
                         std::to_string(protocol::kMaxNode) + " (one per node id)");
  }
  for (std::size_t i = 0; i < joints.size(); ++i) {
    HandJoint joint = ParseJoint(joints[i], i, where, folder);
    const std::string who = where + ": joint '" + joint.name + "'";
    if (hand.Find(joint.name) != nullptr) {
      throw std::runtime_error(who + ": the name is given to two joints");
    }
    if (const HandJoint* other = hand.AtNode(joint.node)) {
      throw std::runtime_error(who + ": node " + std::to_string(joint.node) +
                               " is joint '" + other->name +
                               "' already (one board, one joint)");
    }
    hand.joints.push_back(std::move(joint));
  }
  return hand;
}

}  // namespace

const HandJoint* Hand::Find(std::string_view joint) const {
  for (const HandJoint& j : joints) {
    if (j.name == joint) return &j;
  }
  return nullptr;
}

const HandJoint* Hand::AtNode(int node) const {
  for (const HandJoint& j : joints) {
    if (j.node == node) return &j;
  }
  return nullptr;
}

std::string Hand::JointNames() const {
  std::string out;
  for (const HandJoint& j : joints) out += (out.empty() ? "" : ", ") + j.name;
  return out;
}

std::optional<Hand> ParseHand(std::string_view json_text, std::string_view source,
                              const std::string& folder, std::string* why) {
  try {
    return Parse(json_text, source, folder);
  } catch (const std::exception& e) {
    *why = e.what();
    return std::nullopt;
  }
}

std::optional<Hand> LoadHand(const std::string& path, std::string* why) {
  const std::optional<std::string> text = ReadFileText(path);
  if (!text) {
    *why = path + ": cannot open the hand file";
    return std::nullopt;
  }
  return ParseHand(*text, path, std::filesystem::path(path).parent_path().string(), why);
}

bool HandCheck::Complete() const {
  return std::all_of(joints.begin(), joints.end(),
                     [](const Joint& j) { return j.present && !j.ambiguous; });
}

std::vector<std::string> HandCheck::Missing() const {
  std::vector<std::string> out;
  for (const Joint& j : joints) {
    if (!j.present) out.push_back(j.joint->name);
  }
  return out;
}

HandCheck CheckHand(const Hand& hand, const BusScan& scan) {
  HandCheck check;
  for (const HandJoint& joint : hand.joints) {
    HandCheck::Joint j;
    j.joint = &joint;
    const auto it = scan.nodes().find(joint.node);
    if (it != scan.nodes().end()) {
      j.present = true;
      j.ambiguous = it->second.identity.ambiguous();
      j.in_bootloader = it->second.in_bootloader();
    }
    check.joints.push_back(j);
  }
  std::map<std::uint32_t, int> builds;  // application boards per build
  const auto judged = [](const ScannedNode& n) {
    return n.identity.info() && !n.identity.ambiguous() && !n.in_bootloader();
  };
  for (const auto& [node, n] : scan.nodes()) {
    if (hand.AtNode(node) == nullptr) check.extra.push_back(node);
    if (judged(n)) ++builds[n.identity.info()->build];
  }
  for (const auto& [build, count] : builds) {
    if (!check.build || count > builds[*check.build]) check.build = build;
  }
  for (const auto& [node, n] : scan.nodes()) {
    if (judged(n) && n.identity.info()->build != *check.build) {
      check.wrong_build.push_back(node);
    }
  }
  return check;
}

std::vector<std::string> DescribeHandCheck(const Hand& hand, const HandCheck& check,
                                           const BusScan& scan) {
  std::vector<std::string> lines;
  char text[200];
  int present = 0;
  for (const HandCheck::Joint& j : check.joints) {
    const char* state = !j.present        ? "missing"
                        : j.ambiguous     ? "present, but two boards answer on its id"
                        : j.in_bootloader ? "present, in its bootloader"
                                          : "present";
    present += j.present ? 1 : 0;
    std::snprintf(text, sizeof text, "%-16s node %d  %s", j.joint->name.c_str(),
                  j.joint->node, state);
    lines.emplace_back(text);
  }
  for (const int node : check.extra) {
    lines.push_back("node " + std::to_string(node) + ": extra, not a joint of " +
                    hand.name);
  }
  for (const int node : check.wrong_build) {
    const auto& info = scan.nodes().at(node).identity.info();
    std::snprintf(text, sizeof text, "node %d: wrong build %08x, most boards run %08x",
                  node, info->build, *check.build);
    lines.emplace_back(text);
  }
  std::string verdict = hand.name + ": ";
  if (check.Complete()) {
    verdict += "complete, " + std::to_string(present) + " of " +
               std::to_string(check.joints.size()) + " joints";
  } else {
    std::string missing;
    for (const std::string& name : check.Missing()) {
      missing += (missing.empty() ? "" : ", ") + name;
    }
    verdict += "incomplete, " + std::to_string(present) + " of " +
               std::to_string(check.joints.size()) + " joints" +
               (missing.empty() ? "" : ": missing " + missing);
  }
  lines.push_back(verdict);
  return lines;
}

}  // namespace mjc::host
