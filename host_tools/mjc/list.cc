// mjc list: every board on the bus, heard without asking anything: node id, image
// (application or bootloader), build (and whether it is this mjc's), state (a
// bootloader's: ready, receiving, committed, and why it stays), calibration, latched
// fault, reset cause, record pages the board could not read (a save cut by a power loss:
// named under the table), and two boards answering with one node id. It listens until
// each node heard has shown every board behind its id (host::BusScan: a BoardInfo period
// and a tenth of the boards' own time), or the bus has been silent for --silence-ms.
// With --hand FILE it then checks the bus against the hand (host::CheckHand): each joint
// present or missing, boards the hand does not have, builds other than most boards';
// a joint missing exits 3 (hands/README.md).
#include <cstdio>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <utility>

#include "commands.h"
#include "mjc/build_id.h"
#include "mjc/host/bus_scan.h"
#include "mjc/host/describe.h"
#include "mjc/host/hand.h"

namespace mjc::cli {
namespace {

// The record pages a BoardInfo names unreadable, by name ("" when none).
std::string UnreadablePages(std::uint8_t bits) {
  namespace u = protocol::flash_unreadable;
  std::string out;
  for (const auto& [bit, name] : {std::pair{u::kIdentityA, "identity page A"},
                                  std::pair{u::kIdentityB, "identity page B"},
                                  std::pair{u::kCalibrationA, "calibration page A"},
                                  std::pair{u::kCalibrationB, "calibration page B"}}) {
    if (bits & bit) out += (out.empty() ? "" : ", ") + std::string(name);
  }
  return out;
}

std::string Hex4(std::uint16_t v) {
  char out[8];
  std::snprintf(out, sizeof out, "%04x", v);
  return out;
}

// "= mjc", "≠ mjc", or "commit = mjc, dirty": how a board's build compares with this
// tool's. The same commit built from a dirty tree is not known to be the same code.
std::string BuildMatch(const protocol::BoardInfo& info) {
  if (info.build != build::kCommit) return "differs from mjc";
  if (info.dirty || build::kDirty) return "mjc's commit, dirty";
  return "= mjc";
}

nlohmann::json NodeJson(int node, const host::ScannedNode& n) {
  nlohmann::json j = {{"node", node}, {"ambiguous", n.identity.ambiguous()}};
  nlohmann::json instances = nlohmann::json::array();
  for (const std::uint16_t i : n.identity.instances()) instances.push_back(Hex4(i));
  j["instances"] = instances;
  if (n.identity.ambiguous()) j["message"] = n.identity.Message(node);
  if (const auto& info = n.identity.info()) {
    j["image"] = host::ImageName(info->image);
    j["build"] = host::BuildName(info->build, false);
    j["dirty"] = info->dirty;
    j["build_matches_mjc"] =
        info->build == build::kCommit && !info->dirty && !build::kDirty;
    j["reset_cause"] = host::ResetCauseName(info->reset_cause);
    j["instance"] = Hex4(info->instance);
    j["flash_unreadable"] = UnreadablePages(info->flash_unreadable);
  } else {
    for (const char* key : {"image", "build", "dirty", "build_matches_mjc", "reset_cause",
                            "instance", "flash_unreadable"}) {
      j[key] = nullptr;
    }
  }
  if (n.in_bootloader() && n.boot_status) {
    const protocol::BootStatus& b = *n.boot_status;
    j["state"] = host::DescribeBootStatus(b);
    j["calibrated"] = nullptr;
    j["fault"] = nullptr;
    j["boot"] = {{"state", host::BootStateName(b.state)},
                 {"reason", host::StayReasonName(b.reason)},
                 {"error", host::BootErrorName(b.error)},
                 {"progress_permille", b.progress_permille}};
  } else if (const auto& h = n.heartbeat) {
    j["state"] = host::StateName(h->state);
    j["calibrated"] = h->calibrated;
    j["fault"] = h->fault == Fault::kNone
                     ? nlohmann::json(nullptr)
                     : nlohmann::json{{"code", static_cast<int>(h->fault)},
                                      {"name", host::FaultName(h->fault)}};
  } else {
    j["state"] = nullptr;
    j["calibrated"] = nullptr;
    j["fault"] = nullptr;
  }
  if (n.chip) {
    char optr[16];
    std::snprintf(optr, sizeof optr, "0x%08x", n.chip->option_bytes);
    nlohmann::json warnings = nlohmann::json::array();
    for (const std::string& w : host::ChipWarnings(*n.chip)) warnings.push_back(w);
    j["chip"] = {{"option_bytes", optr},
                 {"boots_from_pin", protocol::BootsFromPin(n.chip->option_bytes)},
                 {"clock", host::ClockSourceName(n.chip->clock)},
                 {"clock_fault", static_cast<int>(n.chip->clock_fault)},
                 {"hse_ready", n.chip->hse_ready},
                 {"reset_flags", n.chip->reset_flags},
                 {"warnings", warnings}};
  }
  return j;
}

}  // namespace

void AddList(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "list", "Every board on the bus: node, image, build, state, calibration, fault");
  static std::string iface;
  static int silence_ms = 3000;
  static bool json = false;
  static std::string hand_path;
  AddIfaceOption(cmd, &iface);
  cmd->add_option("--silence-ms", silence_ms,
                  "Give up after this long without a single frame (an empty bus)")
      ->check(InRange(100, 60000, "ms"))
      ->capture_default_str();
  cmd->add_flag("--json", json, "One JSON object per node and line");
  cmd->add_option("--hand", hand_path,
                  "Check the bus against this hand file (hands/*.json): each joint "
                  "present or missing, boards not in the hand, builds that differ; "
                  "exit 3 when a joint is missing. Its \"iface\" is the default --iface");
  cmd->callback([cmd] {
    if (hand_path.empty()) return ListBoards(iface, silence_ms, json);
    std::string why;
    const auto hand = host::LoadHand(hand_path, &why);
    if (!hand) throw Failure("hand refused: " + why);
    const NodeTargets& t = TargetsOf(cmd);
    const bool iface_given = t.iface_option != nullptr && t.iface_option->count() > 0;
    ListBoards(hand->iface && !iface_given ? *hand->iface : iface, silence_ms, json,
               &*hand);
  });
}

namespace {

// The hand's part of mjc list: its lines (or one JSON object), then a Failure when a
// joint is missing.
void ReportHand(const host::Hand& hand, const host::BusScan& scan, bool json) {
  const host::HandCheck check = host::CheckHand(hand, scan);
  if (json) {
    nlohmann::json joints = nlohmann::json::array();
    for (const auto& j : check.joints) {
      joints.push_back({{"joint", j.joint->name},
                        {"node", j.joint->node},
                        {"present", j.present},
                        {"ambiguous", j.ambiguous},
                        {"in_bootloader", j.in_bootloader}});
    }
    nlohmann::json wrong = nlohmann::json::array();
    for (const int node : check.wrong_build) wrong.push_back(node);
    std::printf(
        "%s\n",
        nlohmann::json{
            {"hand", hand.name},
            {"file", hand.source},
            {"complete", check.Complete()},
            {"joints", joints},
            {"extra", check.extra},
            {"wrong_build", wrong},
            {"build", check.build ? nlohmann::json(host::BuildName(*check.build, false))
                                  : nlohmann::json(nullptr)}}
            .dump()
            .c_str());
  } else {
    std::printf("hand %s (%s):\n", hand.name.c_str(), hand.source.c_str());
    for (const std::string& line : host::DescribeHandCheck(hand, check, scan)) {
      std::printf("  %s\n", line.c_str());
    }
  }
  const auto missing = check.Missing();
  if (missing.empty()) return;
  std::string names;
  for (const std::string& name : missing) {
    names += (names.empty() ? "" : ", ") + name + " (node " +
             std::to_string(hand.Find(name)->node) + ")";
  }
  throw Failure(Exit::kNoAnswer,
                hand.name + " is incomplete: no board answers for " + names);
}

}  // namespace

void ListBoards(const std::string& iface, int silence_ms, bool json,
                const host::Hand* hand) {
  auto link = OpenLink(iface);
  const std::atomic<bool>& stop = StopOnSignals();
  host::BusScan scan;
  if (hand != nullptr) {
    // Every joint's board gets its chance to speak before it is called missing.
    std::set<int> nodes;
    for (const host::HandJoint& j : hand->joints) nodes.insert(j.node);
    scan.Expect(std::move(nodes));
  }
  std::string why;
  const host::ScanEnd end =
      host::ScanBus(*link, &scan, std::chrono::milliseconds(silence_ms), &stop, &why);
  if (end == host::ScanEnd::kLinkFailed) throw Failure(why);
  if (end == host::ScanEnd::kInterrupted) throw Failure(Exit::kStopped, "interrupted");
  if (scan.nodes().empty()) {
    if (hand != nullptr) {
      try {
        ReportHand(*hand, scan, json);
      } catch (const Failure&) {  // every joint missing: said as an empty bus below
      }
    }
    throw Failure(Exit::kNoAnswer,
                  "no board on " + iface + " (nothing heard for " +
                      std::to_string(silence_ms) +
                      " ms: are the boards powered, and the interface up at the "
                      "bus's bitrate?)");
  }
  std::string ambiguous;
  std::string unreadable;  // per node, printed under the table
  if (!json) {
    std::printf("%-4s  %-11s  %-14s  %-18s  %-11s  %-10s  %-9s  %-8s  %s\n", "node",
                "image", "build", "", "state", "calibrated", "reset", "instance",
                "fault");
  }
  for (const auto& [node, n] : scan.nodes()) {
    if (n.identity.ambiguous()) {
      ambiguous += (ambiguous.empty() ? "" : "; ") + n.identity.Message(node);
    }
    if (json) {
      std::printf("%s\n", NodeJson(node, n).dump().c_str());
      continue;
    }
    if (n.identity.ambiguous()) {
      std::printf("%4d  TWO BOARDS: %s\n", node, n.identity.Message(node).c_str());
      continue;
    }
    const auto& info = n.identity.info();
    if (info && info->flash_unreadable != 0) {
      unreadable += "warning: node " + std::to_string(node) + " could not read its " +
                    UnreadablePages(info->flash_unreadable) +
                    " (a save cut by a power loss left an ECC error): the other page's "
                    "record is in use, and the next save erases the bad page\n";
    }
    if (n.in_bootloader()) {
      // Its state, and why it stays where the application's fault would be.
      const auto& b = n.boot_status;
      std::string state = b ? std::string(host::BootStateName(b->state)) : "?";
      std::string stays = "-";
      if (b && b->state == protocol::BootState::kReceiving) {
        state += " " + std::to_string(b->progress_permille / 10) + "%";
      } else if (b && b->state == protocol::BootState::kReady) {
        stays = "stays: " + std::string(host::StayReasonName(b->reason));
        if (b->error != protocol::BootError::kNone) {
          stays += " (" + std::string(host::BootErrorName(b->error)) + ")";
        }
      }
      std::printf("%4d  %-11s  %-14s  %-18s  %-11s  %-10s  %-9s  %-8s  %s\n", node,
                  "bootloader", host::BuildName(info->build, info->dirty).c_str(),
                  BuildMatch(*info).c_str(), state.c_str(), "-",
                  std::string(host::ResetCauseName(info->reset_cause)).c_str(),
                  Hex4(info->instance).c_str(), stays.c_str());
      if (n.chip) {
        std::printf("      option bytes 0x%08x, clock: %s\n", n.chip->option_bytes,
                    std::string(host::ClockSourceName(n.chip->clock)).c_str());
        for (const std::string& w : host::ChipWarnings(*n.chip)) {
          std::printf("      warning: %s\n", w.c_str());
        }
      }
      continue;
    }
    const auto& h = n.heartbeat;
    std::printf(
        "%4d  %-11s  %-14s  %-18s  %-11s  %-10s  %-9s  %-8s  %s\n", node,
        info ? std::string(host::ImageName(info->image)).c_str() : "?",
        info ? host::BuildName(info->build, info->dirty).c_str() : "no BoardInfo",
        info ? BuildMatch(*info).c_str() : "(older image?)",
        h ? std::string(host::StateName(h->state)).c_str() : "?",
        h ? (h->calibrated ? "yes" : "no") : "?",
        info ? std::string(host::ResetCauseName(info->reset_cause)).c_str() : "?",
        info ? Hex4(info->instance).c_str() : "?",
        h && h->fault != Fault::kNone ? host::DescribeFault(h->fault).c_str() : "-");
  }
  if (!json) {
    std::printf("this mjc: %s\n", host::BuildName(build::kCommit, build::kDirty).c_str());
    std::fputs(unreadable.c_str(), stdout);
  }
  if (!ambiguous.empty()) {
    if (hand != nullptr) {
      try {
        ReportHand(*hand, scan, json);
      } catch (const Failure&) {  // two boards on one id come first (exit 7)
      }
    }
    throw Failure(Exit::kAmbiguous, ambiguous);
  }
  if (hand != nullptr) ReportHand(*hand, scan, json);
}

}  // namespace mjc::cli
