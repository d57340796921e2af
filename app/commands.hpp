#pragma once
// Subcommands of the mbi executable. Each cli/cmd_*.cpp registers one subcommand with a static
// Registrar; main.cpp builds the CLI11 app from the registry. A subcommand reports bad input by
// throwing any std::exception: main prints "mbi <sub>: error: <message>" on one line and exits 2.
#include <CLI/CLI.hpp>

#include <functional>
#include <string>
#include <vector>

namespace mbi::cli {

/// The action of a parsed subcommand; returns the process exit code.
using Action = std::function<int()>;
/// Adds options to `sub` and returns the action that runs it (called after parsing).
using Setup = std::function<Action(CLI::App& sub)>;

struct Command {
  std::string name, description;
  Setup setup;
};

std::vector<Command>& registry();

struct Registrar {
  Registrar(std::string name, std::string description, Setup setup) {
    registry().push_back({std::move(name), std::move(description), std::move(setup)});
  }
};

}  // namespace mbi::cli
