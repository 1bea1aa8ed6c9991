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
#include "mjc/gpio/reset_line.h"
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
    case host::UpdateEnd::kGoneCommitted:
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
      "which waits for an image: run mjc flash again (exit 8).\n\n"
      "--reset-line (one board) or --reset (each board's line from the config file's "
      "reset_lines) pulses the board's NRST right after the first BootHold: the board "
      "restarts whatever its application does (a hanging one, an image that does not "
      "know BootHold) and the holds catch its bootloader in its 200 ms hold window. A "
      "board heard running a motion is refused all the same.");
  static std::string iface, image_path, reset_name;
  static std::vector<int> nodes;
  static bool all = false, info = false, json = false, reset = false;
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
  auto* reset_line_option =
      cmd->add_option("--reset-line", reset_name,
                      "The board's NRST, CHIP:LINE: pulsed after the first BootHold, so "
                      "the holds catch the board in its bootloader (one --node)")
          ->check(LineSpecCheck(false));
  cmd->add_flag("--reset", reset,
                "Pulse each board's NRST after its first BootHold, its line from the "
                "config file's \"reset_lines\"")
      ->excludes(reset_line_option);
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
    if (!reset_name.empty() && (all || nodes.size() != 1)) {
      throw Failure(Exit::kUsage,
                    "--reset-line is one board's NRST: give one --node (for several, "
                    "--reset takes each board's line from the config file's "
                    "\"reset_lines\")");
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
    // The reset lines, each held from now on (a missing or busy one refused before
    // anything is sent).
    std::map<int, std::unique_ptr<gpio::OutputLine>> reset_lines;
    for (const int node : targets) {
      std::optional<gpio::LineSpec> spec = LineOf(reset_name);
      if (reset) {
        const auto& lines = Defaults().reset_lines;
        if (!lines.contains(node)) {
          throw Failure(Exit::kUsage,
                        "--reset: the config file has no reset line for "
                        "node " +
                            std::to_string(node) + " (\"reset_lines\": {\"" +
                            std::to_string(node) + "\": \"CHIP:LINE\"})");
        }
        spec = lines.at(node);
      }
      if (!spec) continue;
      reset_lines[node] = gpio::OpenResetLine(*spec, "mjc flash", &why);
      if (!reset_lines[node])
        throw Failure("reset line of node " + std::to_string(node) + ": " + why);
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
      // A reset would stop a motion as surely as a BootHold is refused during one.
      const auto nrst = reset_lines.find(node);
      if (nrst != reset_lines.end() && scanned != scan.nodes().end() &&
          scanned->second.heartbeat &&
          (scanned->second.heartbeat->state == protocol::BoardState::kRunning ||
           scanned->second.heartbeat->state == protocol::BoardState::kCalibrating)) {
        outcome[node] = Exit::kRefused;
        messages[node] = "node " + std::to_string(node) +
                         " is running a motion: stop it first (mjc stop --node " +
                         std::to_string(node) +
                         "); nothing was done (its reset line would stop it mid-motion)";
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
      // The reset line's pulse once the first hold is on the bus: the holds that follow
      // catch the restarted board's bootloader in its hold window, whatever the
      // application does. A pulse that fails leaves the holds to do what they can.
      if (nrst != reset_lines.end()) {
        options.after_first_hold = [node, line = nrst->second.get()] {
          std::string failed;
          EndProgress();
          if (gpio::PulseReset(*line, &failed)) {
            std::fprintf(stderr, "mjc flash: node %d: %s pulsed low %lld ms\n", node,
                         line->name().c_str(),
                         static_cast<long long>(gpio::kResetPulse.count()));
          } else {
            std::fprintf(stderr, "mjc flash: node %d: no reset: %s\n", node,
                         failed.c_str());
          }
        };
      }
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
