// mjc reset: pulses a board's NRST through a GPIO line of the host (open drain, active
// low: held low for --low-ms, then released to the board's pull-up). The line is the
// one given, else the config file's "reset_lines" entry for the node. The board starts
// anew (BoardInfo's reset cause: pin); mjc list shows it back.
#include <chrono>
#include <cstdio>
#include <string>

#include "commands.h"
#include "mjc/gpio/reset_line.h"

namespace mjc::cli {

void AddReset(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "reset", "Reset a board through its NRST line (a GPIO line of this host)");
  static int node = 1;
  static std::string line_name;
  static int low_ms = static_cast<int>(gpio::kResetPulse.count());
  AddNodeOption(cmd, &node, "Node id (picks its line from the config's \"reset_lines\")");
  cmd->add_option("--line", line_name,
                  "The board's NRST line, CHIP:LINE (default: the config file's "
                  "\"reset_lines\" entry for --node)")
      ->check(LineSpecCheck(false));
  cmd->add_option("--low-ms", low_ms, "How long NRST is held low")
      ->check(InRange(1, 1000, "ms"))
      ->capture_default_str();
  cmd->callback([] {
    std::optional<gpio::LineSpec> spec = LineOf(line_name);
    if (!spec) {
      const auto& lines = Defaults().reset_lines;
      const auto it = lines.find(node);
      if (it == lines.end()) {
        throw Failure(Exit::kUsage, "no reset line for node " + std::to_string(node) +
                                        ": give --line CHIP:LINE, or \"reset_lines\": "
                                        "{\"" +
                                        std::to_string(node) +
                                        "\": \"CHIP:LINE\"} in the config file");
      }
      spec = it->second;
    }
    std::string why;
    const auto line = gpio::OpenResetLine(*spec, "mjc reset", &why);
    if (!line) throw Failure(why);
    if (!gpio::PulseReset(*line, &why, std::chrono::milliseconds(low_ms))) {
      throw Failure(why);
    }
    std::printf("node %d reset: %s held low %d ms, then released\n", node,
                line->name().c_str(), low_ms);
  });
}

}  // namespace mjc::cli
