// mbi: one executable, one subcommand per stage (deform, cage, run, ...).
//
// Every error is one line on stderr, "mbi <sub>: error: <what>" (or "mbi: error: <what>" before
// a subcommand is known), and exit code 2; --help and --version exit 0.
#include "commands.hpp"
#include "signals.hpp"

#include <algorithm>
#include <cstdio>
#include <exception>
#include <map>
#include <new>
#include <string>
#include <vector>

namespace mbi::cli {
std::vector<Command>& registry() {
  static std::vector<Command> commands;
  return commands;
}

namespace {

// Levenshtein distance (for "did you mean").
std::size_t distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diag = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diag = up;
    }
  }
  return row[b.size()];
}

// The message on one line (the error line of the command-line contract).
std::string clean(std::string what) {
  std::replace(what.begin(), what.end(), '\n', ' ');
  while (!what.empty() && what.back() == ' ') what.pop_back();
  return what;
}

std::string names(const std::vector<Command>& commands) {
  std::string s;
  for (const auto& c : commands) s += (s.empty() ? "" : ", ") + c.name;
  return s;
}

}  // namespace
}  // namespace mbi::cli

int main(int argc, char** argv) {
  using namespace mbi::cli;
  // from the first instruction a signal removes this process's temporaries (none yet) and ends
  // it with 128 + signal; run and deform's frames then take it as "stop after this frame"
  handle_interrupts(nullptr);
  CLI::App app{"mbi: physics-driven deformation of dense meshes with modified barycentric "
               "interpolation"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "mbi 0.1.0");
  auto commands = registry();
  std::sort(commands.begin(), commands.end(),
            [](const Command& a, const Command& b) { return a.name < b.name; });
  std::map<CLI::App*, Action> actions;
  for (auto& c : commands) {
    CLI::App* sub = app.add_subcommand(c.name, c.description);
    actions[sub] = c.setup(*sub);
  }
  // The subcommand named on the command line (the first argument that is not an option).
  std::string sub_name;
  if (argc > 1 && argv[1][0] != '-') {
    sub_name = argv[1];
    const bool known = std::any_of(commands.begin(), commands.end(),
                                   [&](const Command& c) { return c.name == sub_name; });
    if (!known) {
      std::string best;
      std::size_t best_d = 3;  // at most 2 edits, or a prefix
      for (const auto& c : commands) {
        const std::size_t d = c.name.rfind(sub_name, 0) == 0 ? 0 : distance(sub_name, c.name);
        if (d < best_d) best_d = d, best = c.name;
      }
      std::fprintf(stderr, "mbi: error: unknown subcommand '%s' (%s%s)\n", sub_name.c_str(),
                   best.empty() ? "known: " : "did you mean '",
                   best.empty() ? names(commands).c_str() : (best + "'?").c_str());
      return 2;
    }
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success)) return app.exit(e);
    if (sub_name.empty()) {
      const std::string what = argc <= 1 ? "a subcommand is required: " + names(commands)
                                         : clean(e.what());
      std::fprintf(stderr, "mbi: error: %s (see mbi --help)\n", what.c_str());
    } else {
      std::fprintf(stderr, "mbi %s: error: %s (see mbi %s --help)\n", sub_name.c_str(),
                   clean(e.what()).c_str(), sub_name.c_str());
    }
    return 2;
  }
  for (auto& [sub, action] : actions) {
    if (!sub->parsed()) continue;
    try {
      return action();
    } catch (const std::bad_alloc&) {
      std::fprintf(stderr, "mbi %s: error: out of memory (the inputs need more than this process may take)\n",
                   sub->get_name().c_str());
      return 2;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "mbi %s: error: %s\n", sub->get_name().c_str(), clean(e.what()).c_str());
      return 2;
    }
  }
  return 2;
}
