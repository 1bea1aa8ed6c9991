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
