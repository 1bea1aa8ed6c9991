#include "mjc/host/config.h"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "mjc/strict_json.h"

namespace mjc::host {
namespace {

bool InterfaceName(std::string_view name) {
  if (name.empty() || name.size() > 15) return false;  // IFNAMSIZ - 1
  for (const char c : name) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') ||
                    (c >= '0' && c <= '9') || c == '_' || c == '.' || c == '-';
    if (!ok) return false;
  }
  return true;
}

}  // namespace

std::optional<ToolConfig> ParseToolConfig(std::string_view text, std::string_view source,
                                          std::string* why) {
  const std::string where(source);
  nlohmann::json j;
  try {
    j = strict::ParseObject<nlohmann::json>(text, where);  // no key twice
  } catch (const std::exception& e) {
    *why = e.what();
    return std::nullopt;
  }
  if (const auto unknown = strict::UnknownKey(j, kConfigKeys)) {
    *why = where + ": " + *unknown;
    return std::nullopt;
  }
  ToolConfig config;
  config.source = where;
  if (j.contains("iface")) {
    if (!j["iface"].is_string() || !InterfaceName(j["iface"].get<std::string>())) {
      *why = where + ": 'iface' must be an interface name (1-15 characters of " +
             "A-Z a-z 0-9 _ . -), e.g. \"can0\"";
      return std::nullopt;
    }
    config.iface = j["iface"].get<std::string>();
  }
  if (j.contains("node")) {
    const auto& n = j["node"];
    if (!n.is_number_integer() || n.get<std::int64_t>() < 1 ||
        n.get<std::int64_t>() > 8) {
      *why = where + ": 'node' must be an integer in 1..8, not " + n.dump();
      return std::nullopt;
    }
    config.node = static_cast<int>(n.get<std::int64_t>());
  }
  // A line: CHIP:LINE, checked for its form (the chip and line are found when used).
  const auto line = [&](const nlohmann::json& v,
                        const std::string& key) -> std::optional<gpio::LineSpec> {
    std::string form;
    if (!v.is_string()) {
      *why = where + ": '" + key + "' must be a GPIO line as a string, CHIP:LINE (e.g. " +
             "\"gpiochip0:17\"), not " + v.dump();
      return std::nullopt;
    }
    auto spec = gpio::ParseLineSpec(v.get<std::string>(), &form);
    if (!spec) *why = where + ": '" + key + "': " + form;
    return spec;
  };
  for (const char* key : {"estop_line", "sync_line"}) {
    if (!j.contains(key)) continue;
    auto spec = line(j[key], key);
    if (!spec) return std::nullopt;
    (std::string_view(key) == "estop_line" ? config.estop_line : config.sync_line) =
        *spec;
  }
  if (j.contains("estop_active")) {
    const auto& a = j["estop_active"];
    if (a != "high" && a != "low") {
      *why = where + ": 'estop_active' must be \"high\" or \"low\", not " + a.dump();
      return std::nullopt;
    }
    config.estop_active_low = a == "low";
  }
  if (j.contains("reset_lines")) {
    const auto& r = j["reset_lines"];
    if (!r.is_object()) {
      *why = where + ": 'reset_lines' must be an object from node ids to GPIO lines " +
             "(e.g. {\"1\": \"gpiochip0:20\"})";
      return std::nullopt;
    }
    for (const auto& [node, value] : r.items()) {
      if (node.size() != 1 || node[0] < '1' || node[0] > '8') {
        *why = where + ": 'reset_lines': '" + node + "' is not a node id 1..8";
        return std::nullopt;
      }
      auto spec = line(value, "reset_lines." + node);
      if (!spec) return std::nullopt;
      config.reset_lines[node[0] - '0'] = *spec;
    }
  }
  if (j.contains("hand")) {
    const auto& h = j["hand"];
    if (!h.is_string() || h.get<std::string>().empty()) {
      *why = where + ": 'hand' must be the path of a hand file (hands/*.json), not " +
             h.dump();
      return std::nullopt;
    }
    config.hand = (std::filesystem::path(where).parent_path() / h.get<std::string>())
                      .lexically_normal()
                      .string();
  }
  return config;
}

std::optional<ToolConfig> LoadToolConfig(std::string* why) {
  std::filesystem::path path;
  bool required = false;
  if (const char* named = std::getenv("MJC_CONFIG"); named != nullptr && *named != '\0') {
    path = named;
    required = true;
  } else if (const char* home = std::getenv("HOME"); home != nullptr && *home != '\0') {
    path = std::filesystem::path(home) / ".config/mjc/config.json";
  }
  ToolConfig config;
  std::error_code error;
  if (!path.empty() && (required || std::filesystem::exists(path, error))) {
    std::ifstream in(path);
    if (!in) {
      *why = path.string() + ": cannot read the config file" +
             (required ? " (named by MJC_CONFIG)" : "");
      return std::nullopt;
    }
    std::ostringstream text;
    text << in.rdbuf();
    const auto parsed = ParseToolConfig(text.str(), path.string(), why);
    if (!parsed) return std::nullopt;
    config = *parsed;
  }
  if (const char* iface = std::getenv("MJC_IFACE"); iface != nullptr && *iface != '\0') {
    if (!InterfaceName(iface)) {
      *why = std::string("MJC_IFACE='") + iface + "' is not an interface name";
      return std::nullopt;
    }
    config.iface = iface;
  }
  return config;
}

}  // namespace mjc::host
