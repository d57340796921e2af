// mbi: one executable, one subcommand per stage (deform, cage, run, ...).
#include "commands.hpp"

#include <algorithm>
#include <cstdio>
#include <exception>
#include <map>

namespace mbi::cli {
std::vector<Command>& registry() {
  static std::vector<Command> commands;
  return commands;
}
}  // namespace mbi::cli

int main(int argc, char** argv) {
  using namespace mbi::cli;
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
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }
  for (auto& [sub, action] : actions) {
    if (!sub->parsed()) continue;
    try {
      return action();
    } catch (const std::exception& e) {
      std::fprintf(stderr, "mbi %s: error: %s\n", sub->get_name().c_str(), e.what());
      return 2;
    }
  }
  return 2;
}
