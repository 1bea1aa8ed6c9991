// mjc flash: updates the joint boards' firmware over the bus, one board after the other
// (host::FirmwareUpdate: caught, the image sent and checked by the board, started, its
// new build confirmed), or lists what each board runs (--info, mjc list's table). The
// image file is checked before anything is sent; a board answered by two is left
// alone; a board that fails is named, and says where it was left — usually its
// bootloader, which keeps waiting for an image — and the others still go through.
#include <algorithm>
#include <cinttypes>
#include <cstdio>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "commands.h"
#include "mjc/host/bus_scan.h"
#include "mjc/host/describe.h"
#include "mjc/host/firmware_update.h"

namespace mjc::cli {
namespace {

// How long an empty bus is listened to before mjc flash knows who is on it.
constexpr int kScanSilenceMs = 3000;

Exit ExitOf(host::UpdateEnd end) {
  switch (end) {
    case host::UpdateEnd::kUpdated:
      return Exit::kOk;
    case host::UpdateEnd::kMotionRunning:
    case host::UpdateEnd::kRefused:
      return Exit::kRefused;
    case host::UpdateEnd::kSilent:
    case host::UpdateEnd::kNotEntering:
      return Exit::kNoAnswer;
    case host::UpdateEnd::kFailed:
      return Exit::kNotUpdated;
    case host::UpdateEnd::kLinkFailed:
      return Exit::kFailure;
    case host::UpdateEnd::kInterrupted:
      return Exit::kStopped;
  }
  return Exit::kFailure;
}

std::string Kilobytes(std::uint32_t bytes) {
  char out[32];
  std::snprintf(out, sizeof out, "%.1f KB", bytes / 1024.0);
  return out;
}

// "[node 2] uploading [#########...........]  45%  28.8 of 64.0 KB"
std::string ProgressLine(int node, const host::UpdateProgress& p) {
  using Phase = host::UpdateProgress::Phase;
  const char* what = "catching";
  switch (p.phase) {
    case Phase::kCatching:
      return "[node " + std::to_string(node) + "] catching it in its bootloader";
    case Phase::kUploading:
      what = "uploading";
      break;
    case Phase::kCommitting:
      what = "committing";
      break;
    case Phase::kBooting:
      what = "starting";
      break;
  }
  constexpr std::size_t kWidth = 20;
  const std::size_t filled =
      p.total == 0
          ? 0
          : static_cast<std::size_t>(std::uint64_t{p.programmed} * kWidth / p.total);
  const unsigned percent =
      p.total == 0 ? 0u
                   : static_cast<unsigned>(std::uint64_t{p.programmed} * 100 / p.total);
  char tail[64];
  std::snprintf(tail, sizeof tail, "] %3u%%  %s of %s", percent,
                Kilobytes(p.programmed).c_str(), Kilobytes(p.total).c_str());
  return "[node " + std::to_string(node) + "] " + what + " [" + std::string(filled, '#') +
         std::string(kWidth - filled, '.') + tail;
}

}  // namespace

void AddFlash(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "flash",
      "Update the boards' firmware over the bus (--node N... or --all IMAGE), or list "
      "what each board runs (--info)");
  cmd->footer(
      std::string(kExitStatusHelp) +
      "\n\nIMAGE is a packed application (the build writes maestro-jc-g474-app.bin; "
      "mjc-image show checks one). It is checked before anything is sent: its header, "
      "length and CRC-32, and that it is built for the joint board. Each board is "
      "caught in its bootloader (a running application is asked to enter it and "
      "refuses while a trial or calibration runs), takes the image in chunks, checks its "
      "CRC in flash, starts it and must report its build. Its node id and calibration "
      "are never touched. A board that fails is named and stays in its bootloader, "
      "which waits for an image: run mjc flash again (exit 8).");
  static std::string iface, image_path;
  static std::vector<int> nodes;
  static bool all = false, info = false, json = false;
  AddIfaceOption(cmd, &iface);
  auto* node_option =
      cmd->add_option("--node", nodes, "A board to update (repeat for several)")
          ->allow_extra_args(false)  // one value each: IMAGE follows
          ->check(InRange(protocol::kMinNode, protocol::kMaxNode));
  cmd->add_flag("--all", all, "Update every board heard on the bus")
      ->excludes(node_option);
  cmd->add_flag("--info", info,
                "List every board: node, application or bootloader, build (mjc list's "
                "table)");
  cmd->add_flag("--json", json, "With --info: one JSON object per node and line");
  cmd->add_option("IMAGE", image_path, "The packed image file (maestro-jc-g474-app.bin)");
  cmd->callback([] {
    if (info) {
      if (!image_path.empty() || !nodes.empty() || all) {
        throw Failure(Exit::kUsage,
                      "--info lists every board; it takes no IMAGE, --node "
                      "or --all (see mjc flash --help)");
      }
      ListBoards(iface, kScanSilenceMs, json);
      return;
    }
    if (json)
      throw Failure(Exit::kUsage, "--json goes with --info (see mjc flash --help)");
    if (image_path.empty()) {
      throw Failure(
          Exit::kUsage,
          "an IMAGE file is required, e.g. build/cm4/firmware/boards/g474_joint/"
          "maestro-jc-g474-app.bin (see mjc flash --help)");
    }
    if (nodes.empty() && !all) {
      throw Failure(Exit::kUsage,
                    "say which boards: --node N (repeat for several) or --all (see mjc "
                    "flash --help)");
    }
    // The file first: nothing goes on the bus for a file that does not check out.
    std::string why;
    const auto image = host::LoadFirmwareImage(image_path, &why);
    if (!image) throw Failure(why);
    auto link = OpenLink(iface);
    const std::atomic<bool>& stop = StopOnSignals();

    // Who is on the bus, heard without asking: every node for --all, and two boards
    // behind one node id, which are left alone.
    host::BusScan scan;
    const host::ScanEnd end = host::ScanBus(
        *link, &scan, std::chrono::milliseconds(kScanSilenceMs), &stop, &why);
    if (end == host::ScanEnd::kLinkFailed) throw Failure(why);
    if (end == host::ScanEnd::kInterrupted) {
      throw Failure(Exit::kStopped, "interrupted before anything was done");
    }
    std::set<int> targets(nodes.begin(), nodes.end());
    if (all) {
      for (const auto& [node, n] : scan.nodes()) targets.insert(node);
      if (targets.empty()) {
        throw Failure(Exit::kNoAnswer, "no board on " + iface + " (nothing heard for " +
                                           std::to_string(kScanSilenceMs) +
                                           " ms: are the boards powered?)");
      }
    }
    std::fprintf(stderr, "mjc flash: %s: %s, %s, CRC-32 0x%08" PRIX32 "\n",
                 image->name.c_str(), image->BuildText().c_str(),
                 Kilobytes(image->header.length).c_str(), image->header.image_crc);

    std::map<int, Exit> outcome;
    std::map<int, std::string> messages;
    for (const int node : targets) {
      if (stop) break;
      const auto scanned = scan.nodes().find(node);
      if (scanned != scan.nodes().end() && scanned->second.identity.ambiguous()) {
        outcome[node] = Exit::kAmbiguous;
        messages[node] = scanned->second.identity.Message(node) + "; nothing was done";
        if (targets.size() > 1)
          std::fprintf(stderr, "mjc flash: %s\n", messages[node].c_str());
        continue;
      }
      auto transport =
          host::OpenKernelBootTransport(iface, static_cast<std::uint8_t>(node), &why);
      if (!transport) throw Failure(why);
      host::UpdateOptions options;
      options.interrupt = &stop;
      // The line is rewritten when it changes: each phase, each percent.
      options.progress = [node,
                          last = std::string()](const host::UpdateProgress& p) mutable {
        std::string line = ProgressLine(node, p);
        if (line.substr(0, line.find("%")) == last.substr(0, last.find("%"))) return;
        last = line;
        Progress(line);
      };
      options.hint = [](const std::string& hint) {
        EndProgress();
        std::fprintf(stderr, "mjc flash: %s\n", hint.c_str());
      };
      // A reset line's pulse would go in options.after_first_hold (host_tools/gpio):
      // the holds are then on the bus before the board restarts, and catch its
      // bootloader in the hold window whatever the application does.
      host::FirmwareUpdate update(link.get(), transport.get(),
                                  static_cast<std::uint8_t>(node), *image, options);
      const host::UpdateResult r = update.Run();
      EndProgress();
      outcome[node] = ExitOf(r.end);
      messages[node] = r.message;
      if (r.end == host::UpdateEnd::kUpdated) {
        std::printf(
            "node %d: updated to %s in %.1f s: %s sent in %.1f s (%.1f KB/s), its CRC-32 "
            "0x%08" PRIX32 " checked by the board in its flash%s\n",
            node, image->BuildText().c_str(), r.total_s,
            Kilobytes(image->header.length).c_str(), r.upload_s,
            r.upload_s > 0 ? image->header.length / 1024.0 / r.upload_s : 0.0,
            image->header.image_crc,
            r.chunks_resent + r.restarts == 0
                ? ""
                : (", " + std::to_string(r.chunks_resent) + " chunks sent again, " +
                   std::to_string(r.restarts) + " restarts")
                      .c_str());
        std::fflush(stdout);
      } else if (targets.size() > 1) {
        std::fprintf(stderr, "mjc flash: %s\n", r.message.c_str());
      }
    }
    for (const int node : targets) {
      if (!outcome.contains(node)) {
        outcome[node] = Exit::kStopped;
        messages[node] = "node " + std::to_string(node) + " not begun (interrupted)";
      }
    }

    // The exit status: 8 when a board was left without its new image (it needs
    // attention), else the first board's failure, else 0.
    std::vector<int> failed;
    Exit status = Exit::kOk;
    for (const auto& [node, e] : outcome) {
      if (e == Exit::kOk) continue;
      failed.push_back(node);
      if (status == Exit::kOk || e == Exit::kNotUpdated) status = e;
    }
    if (failed.empty()) return;
    if (targets.size() == 1) throw Failure(status, messages.begin()->second);
    std::string names;
    for (const int node : failed) {
      names += (names.empty() ? "node " : ", ") + std::to_string(node);
    }
    throw Failure(
        status,
        std::to_string(failed.size()) + " of " + std::to_string(targets.size()) +
            " boards not updated (" + names + "; see above)" +
            (failed.size() < targets.size() ? ", the others run " + image->BuildText()
                                            : ""));
  });
}

}  // namespace mjc::cli
