// mjc: the Maestro joint boards' host tool, over SocketCAN. `mjc --help` lists the
// subcommands; each has its own --help. Every failure (bad flags, bad files, missing
// interfaces, silent nodes) is one line on stderr, "mjc <subcommand>: <what>", and a
// non-zero exit status (commands.h: Exit).
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>
#include <string_view>
#include <vector>

#include "commands.h"
#include "mjc/build_id.h"
#include "mjc/strict_json.h"

namespace {

// "mjc cal download": the subcommands the command line chose.
std::string CommandName(const CLI::App& app) {
  std::string name = "mjc";
  for (const CLI::App* a = &app; !a->get_subcommands().empty();) {
    a = a->get_subcommands().front();
    name += " " + a->get_name();
  }
  return name;
}

int Fail(const std::string& who, const std::string& what, mjc::cli::Exit exit) {
  std::fprintf(stderr, "%s: %s\n", who.c_str(), what.c_str());
  return static_cast<int>(exit);
}

// The first word of the command line that should name a subcommand and does not, as
// "mjc cal: unknown command 'shwo' (did you mean 'show'?)"; empty when there is none
// (options and a leaf's own arguments are CLI11's to judge).
std::string UnknownCommand(CLI::App& app, int argc, char** argv) {
  CLI::App* level = &app;
  std::string who = "mjc";
  for (int i = 1; i < argc; ++i) {
    const std::string_view word = argv[i];
    const auto subcommands = level->get_subcommands([](CLI::App*) { return true; });
    if (subcommands.empty() || word.starts_with("-")) return "";
    std::vector<std::string_view> names;
    CLI::App* found = nullptr;
    for (CLI::App* sub : subcommands) {
      names.push_back(sub->get_name());
      if (sub->get_name() == word) found = sub;
    }
    if (found == nullptr) {
      const auto near = mjc::strict::Closest(word, names);
      return who + ": unknown command '" + std::string(word) + "'" +
             (near ? " (did you mean '" + std::string(*near) + "'?)"
                   : " (" + who + " --help lists them)");
    }
    level = found;
    who += " " + found->get_name();
  }
  return "";
}

// For "The following argument was not expected: --nod": " (did you mean '--node'?)"
// for each word that is an option misspelt, from the options of the command the line
// chose (as a misspelt subcommand gets one); empty when none is near.
std::string FlagHint(const CLI::App& app, const std::string& what) {
  const CLI::App* leaf = &app;
  while (!leaf->get_subcommands().empty()) leaf = leaf->get_subcommands().front();
  std::vector<std::string> names;
  for (const CLI::App* a = leaf; a != nullptr; a = a->get_parent()) {
    for (const CLI::Option* o : a->get_options()) {
      for (const std::string& n : o->get_lnames()) names.push_back("--" + n);
      for (const std::string& n : o->get_snames()) names.push_back("-" + n);
    }
  }
  const std::vector<std::string_view> known(names.begin(), names.end());
  std::string hint;
  const std::size_t colon = what.find(": ");
  if (colon == std::string::npos) return "";
  std::string word;
  for (std::size_t i = colon + 2; i <= what.size(); ++i) {
    if (i < what.size() && what[i] != ' ') {
      word += what[i];
      continue;
    }
    // "--nod=3": the name before '='.
    const std::string name = word.substr(0, word.find('='));
    if (name.starts_with("-")) {
      if (const auto near = mjc::strict::Closest(name, known)) {
        hint += " (did you mean '" + std::string(*near) + "'?)";
      }
    }
    word.clear();
  }
  return hint;
}

}  // namespace

int main(int argc, char** argv) {
  using mjc::cli::Exit;
  // A closed stdout or stderr (`mjc trial 2>&1 | head`) is an error on a write, never
  // the death of the process mid-motion: a progress line is lost (EPIPE), a report
  // that could not be written is said with exit 1 below.
  std::signal(SIGPIPE, SIG_IGN);
  CLI::App app{"mjc: host tool for the Maestro exoskeleton's joint boards (SocketCAN)"};
  // The defaults come first: the subcommands' options start from them. A config file
  // that cannot be used stops every command but --help and --version.
  std::string why;
  if (!mjc::cli::LoadDefaults(argc, argv, &why)) return Fail("mjc", why, Exit::kFailure);
  app.footer(mjc::cli::kExitStatusHelp);  // before the subcommands: they inherit it
  app.set_version_flag(
      "--version",
      std::string("mjc ") + mjc::build::kDescribe + " (build " +
          [] {
            char hex[16];
            std::snprintf(hex, sizeof hex, "%08x", mjc::build::kCommit);
            return std::string(hex);
          }() +
          (mjc::build::kDirty ? "+dirty" : "") + ")",
      "This mjc's build (the commit it was built from) and exit");
  app.require_subcommand(1);
  // One line, naming the command: "mjc trial: --amplitudes: 100 is outside 1..90 °".
  app.failure_message([](const CLI::App* a, const CLI::Error& e) {
    std::string what = e.what();
    if (dynamic_cast<const CLI::RequiredError*>(&e) != nullptr &&
        what.find("subcommand") != std::string::npos) {
      what = "a command is required";
    }
    if (dynamic_cast<const CLI::ExtrasError*>(&e) != nullptr) what += FlagHint(*a, what);
    return CommandName(*a) + ": " + what + " (see " + CommandName(*a) + " --help)\n";
  });
  mjc::cli::AddSim(app);
  mjc::cli::AddLog(app);
  mjc::cli::AddCal(app);
  mjc::cli::AddCalibrate(app);
  mjc::cli::AddBusload(app);
  mjc::cli::AddTrial(app);
  mjc::cli::AddReport(app);
  mjc::cli::AddMonitor(app);
  mjc::cli::AddClear(app);
  mjc::cli::AddStop(app);
  mjc::cli::AddList(app);
  mjc::cli::AddFlash(app);
  mjc::cli::AddEstop(app);
  mjc::cli::AddReset(app);
  mjc::cli::AddParam(app);
  if (const std::string unknown = UnknownCommand(app, argc, argv); !unknown.empty()) {
    std::fprintf(stderr, "%s\n", unknown.c_str());
    return static_cast<int>(Exit::kUsage);
  }
  // The subcommands' callbacks run inside parse().
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : static_cast<int>(Exit::kUsage);  // e.g. --help: 0
  } catch (const mjc::cli::Failure& e) {
    return Fail(CommandName(app), e.what(), e.exit());
  } catch (const std::exception& e) {
    return Fail(CommandName(app), e.what(), Exit::kFailure);
  }
  // Reports and tables go to stdout: a full disk or a closed pipe there is a failure.
  errno = 0;
  if (std::fflush(stdout) != 0 || std::ferror(stdout)) {
    const std::string what = std::string("error writing stdout") +
                             (errno ? ": " + std::string(std::strerror(errno)) : "");
    return Fail(CommandName(app), what, Exit::kFailure);
  }
  return static_cast<int>(Exit::kOk);
}
