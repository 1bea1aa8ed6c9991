// Defaults(): the config file's values the command lines of mjc and mjc-g474 start from.
#include <string>
#include <string_view>

#include "commands.h"

namespace mjc::cli {

host::ToolConfig& Defaults() {
  static host::ToolConfig defaults;
  return defaults;
}

bool LoadDefaults(int argc, char** argv, std::string* why) {
  if (const auto config = host::LoadToolConfig(why)) {
    Defaults() = *config;
    return true;
  }
  for (int i = 1; i < argc; ++i) {
    const std::string_view a = argv[i];
    if (a == "--help" || a == "-h" || a == "--version") return true;
  }
  return false;
}

}  // namespace mjc::cli

namespace mjc::cli {

void ResolveJoints(NodeTargets& t) {
  const bool node_given = t.node_option != nullptr && t.node_option->count() > 0;
  const bool hand_given = t.hand_option != nullptr && t.hand_option->count() > 0;
  if (!hand_given && t.joints.empty()) return;
  if (node_given) {
    throw Failure(Exit::kUsage, std::string("--node and ") +
                                    (t.joints.empty() ? "--hand" : "--joint") +
                                    " together: name the board either by its node id "
                                    "or by its joint");
  }
  std::string path = t.hand_path;
  if (!hand_given) {
    if (!Defaults().hand) {
      throw Failure(Exit::kUsage,
                    "--joint needs a hand: give --hand FILE (or \"hand\" in the config "
                    "file)");
    }
    path = *Defaults().hand;
  }
  std::string why;
  t.hand = host::LoadHand(path, &why);
  if (!t.hand) throw Failure("hand refused: " + why);
  const host::Hand& hand = *t.hand;
  t.chosen.clear();
  if (t.joints.empty()) {
    if (!t.several) {
      throw Failure(Exit::kUsage, "--hand " + path +
                                      ": name the joint too (--joint NAME; its joints: " +
                                      hand.JointNames() + ")");
    }
    t.chosen = hand.joints;
  } else {
    if (!t.several && t.joints.size() > 1) {
      throw Failure(Exit::kUsage, "one --joint: this command talks to one board");
    }
    std::vector<std::string_view> names;
    for (const host::HandJoint& j : hand.joints) names.push_back(j.name);
    for (const std::string& name : t.joints) {
      const host::HandJoint* joint = hand.Find(name);
      if (joint == nullptr) {
        const auto near = strict::Closest(name, names);
        throw Failure(Exit::kUsage,
                      "--joint " + name + ": " + path + " has no such joint" +
                          (near ? " (did you mean '" + std::string(*near) + "'?)" : "") +
                          "; its joints: " + hand.JointNames());
      }
      bool again = false;
      for (const host::HandJoint& c : t.chosen) again = again || c.name == name;
      if (!again) t.chosen.push_back(*joint);
    }
  }
  std::vector<int> nodes;
  for (const host::HandJoint& j : t.chosen) nodes.push_back(j.node);
  t.set_nodes(nodes);
  if (hand.iface && t.iface != nullptr && t.iface_option != nullptr &&
      t.iface_option->count() == 0) {
    *t.iface = *hand.iface;
  }
  if (t.robot != nullptr && t.chosen.size() == 1) {
    const host::HandJoint& joint = t.chosen.front();
    if (t.robot_option == nullptr || t.robot_option->count() == 0) {
      *t.robot = joint.robot_path;
      return;
    }
    std::error_code error;
    if (!std::filesystem::equivalent(*t.robot, joint.robot_path, error)) {
      throw Failure(Exit::kUsage, "--robot " + *t.robot +
                                      " is not the description of joint '" + joint.name +
                                      "' in " + path + " (" + joint.robot_path +
                                      "): leave --robot out, or change the hand file");
    }
  }
}

}  // namespace mjc::cli
