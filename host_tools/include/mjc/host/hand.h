// A hand: one JSON file (hands/*.json at the repository root, hands/README.md gives the
// format) saying which joint board drives which joint of one exoskeleton, with which
// robot description (robots/*.json), and the limits of the subject who wears it. The
// tools address a joint by its name through it (mjc --hand FILE --joint NAME) and
// `mjc list --hand FILE` checks the bus against it (CheckHand below).
//
// The subject's limits are read and checked against the joint's description here; no
// tool sends them to a board yet (the board enforces the description's limits, which
// `mjc calibrate --robot` and `mjc trial --robot` send).
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "mjc/host/bus_scan.h"
#include "mjc/host/robot_description.h"

namespace mjc::host {

// The subject's limits for one joint: what this person's joint may be moved through and
// carry, each within the robot's (its description's "limits").
struct SubjectLimits {
  double extension_deg = 0.0;         // < 0, ≥ the description's extension_deg
  double flexion_deg = 0.0;           // > 0, ≤ the description's flexion_deg
  double torque_Nm = 0.0;             // > 0, ≤ the description's torque_Nm
  double energy_per_window_mJ = 0.0;  // > 0, ≤ torque_Nm × the range in rad × 1000
};

struct HandJoint {
  std::string name;        // [a-z0-9_], 1-32, unique in the hand ("index_mcp")
  int node = 0;            // protocol::kMinNode..kMaxNode, unique in the hand
  std::string robot;       // the description's path as the file gives it
  std::string robot_path;  // the same, from the hand file's folder (for opening)
  RobotDescription description;
  SubjectLimits subject;
};

struct Hand {
  std::string name;                  // [A-Za-z0-9_.-], 1-64
  std::string description;           // free text, optional
  std::optional<std::string> iface;  // the CAN interface it is wired to, optional
  std::vector<HandJoint> joints;     // as the file lists them, 1..kMaxNode of them
  std::string source;                // the file it came from

  // The joint named `name`; null when there is none.
  const HandJoint* Find(std::string_view name) const;
  // The joint on `node`; null when there is none.
  const HandJoint* AtNode(int node) const;
  // "thumb_cmc, thumb_mcp, ..." in the file's order.
  std::string JointNames() const;
};

inline constexpr std::string_view kHandKeys[] = {"name", "description", "iface",
                                                 "joints"};
inline constexpr std::string_view kHandJointKeys[] = {"name", "node", "robot", "subject"};
inline constexpr std::string_view kSubjectLimitKeys[] = {
    "extension_deg", "flexion_deg", "torque_Nm", "energy_per_window_mJ"};

// Reads a hand from JSON text; `source` names it in messages and `folder` is where the
// joints' robot paths are taken from (the hand file's folder). nullopt with one line in
// *why naming the source, the joint (by name, or "joints[i]" before its name is read)
// and the reason: malformed JSON, a key given twice, an unknown key (with the nearest
// known one), a missing field or one of the wrong type, a name or node id out of range,
// a node id or joint name given to two joints, a description that does not load (its
// own refusal quoted), subject limits looser than the description's or not limits at
// all. Never throws.
std::optional<Hand> ParseHand(std::string_view json_text, std::string_view source,
                              const std::string& folder, std::string* why);

// The same from a file; its robot paths are taken from the file's folder.
std::optional<Hand> LoadHand(const std::string& path, std::string* why);

// A hand against what a bus scan heard (mjc list --hand).
struct HandCheck {
  struct Joint {
    const HandJoint* joint = nullptr;
    bool present = false;        // a board answers on its node
    bool ambiguous = false;      // two boards answer on its node
    bool in_bootloader = false;  // the board there runs its bootloader
  };
  std::vector<Joint> joints;           // the hand's, in its order
  std::vector<int> extra;              // nodes heard that no joint of the hand names
  std::vector<int> wrong_build;        // nodes whose build differs from the others'
  std::optional<std::uint32_t> build;  // the build most boards run (ties: the lowest)
  bool Complete() const;               // every joint present, one board each
  std::vector<std::string> Missing() const;  // the joints absent, by name
};

// Compares `hand` with what `scan` heard. A board's build is its BoardInfo's commit; the
// build most of the application boards heard run is taken as the hand's, and the others
// are named wrong_build (two builds with as many boards each: the lowest is the
// reference, so both sides are shown). Boards without a BoardInfo, two boards behind one
// id and boards in their bootloader (another image) are not judged.
HandCheck CheckHand(const Hand& hand, const BusScan& scan);

// mjc list --hand's lines for people: one per joint ("index_mcp  node 4  present",
// "missing", "present, in its bootloader", "two boards"), then one per extra board
// ("node 6: extra, not a joint of maestro-right") and per wrong build ("node 3: wrong
// build 1958ba84, most boards run 77aa0c12"), and the verdict ("maestro-right: complete,
// 8 of 8 joints" or "maestro-right: incomplete, 6 of 8 joints: missing thumb_ip,
// index_mcp").
std::vector<std::string> DescribeHandCheck(const Hand& hand, const HandCheck& check,
                                           const BusScan& scan);

}  // namespace mjc::host
