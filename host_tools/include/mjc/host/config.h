// mjc's defaults from the environment and a small config file, so a lab that works on
// can0 with one board need not say so in every command. The command line wins over
// MJC_IFACE, which wins over the file.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <string_view>

#include "mjc/gpio/line_spec.h"

namespace mjc::host {

struct ToolConfig {
  std::optional<std::string> iface;  // a CAN interface's name
  std::optional<int> node;           // 1..8
  // The lab's GPIO lines (README: GPIO lines), each CHIP:LINE.
  std::optional<gpio::LineSpec> estop_line;   // the emergency-stop button
  std::optional<bool> estop_active_low;       // its active level ("estop_active")
  std::optional<gpio::LineSpec> sync_line;    // the trigger to other instruments
  std::map<int, gpio::LineSpec> reset_lines;  // each board's NRST, by node id
  // The hand file --joint looks in when no --hand is given ("hand"), its path taken
  // from the config file's folder (hands/README.md).
  std::optional<std::string> hand;
  std::string source;  // where it came from, for messages ("" = nowhere)
};

// The keys of the config file; more will come (lines of a hand, the lab's robots).
inline constexpr std::string_view kConfigKeys[] = {
    "iface", "node", "estop_line", "estop_active", "sync_line", "reset_lines", "hand"};

// The config file's text: a JSON object with optional "iface" (an interface name, 1 to
// 15 characters of [A-Za-z0-9_.-], as Linux allows), "node" (an integer 1..8),
// "estop_line" and "sync_line" (CHIP:LINE, gpio::ParseLineSpec), "estop_active"
// ("high" or "low"), "reset_lines" (an object from node ids "1".."8" to CHIP:LINE) and
// "hand" (a non-empty path of a hand file, relative to `source`'s folder: ToolConfig's
// hand holds it joined to that folder; the file is read when a command uses it).
// nullopt with *why naming `source` and the key when it is not JSON, holds an unknown
// key (named with the nearest known one) or a value out of range.
std::optional<ToolConfig> ParseToolConfig(std::string_view text, std::string_view source,
                                          std::string* why);

// The defaults in force: the file $MJC_CONFIG names (an error when it is missing),
// else ~/.config/mjc/config.json when it exists (none: no defaults), then MJC_IFACE over
// its interface. nullopt with *why when the file cannot be read or is refused, or
// MJC_IFACE is not an interface name.
std::optional<ToolConfig> LoadToolConfig(std::string* why);

}  // namespace mjc::host
