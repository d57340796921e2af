#pragma once
// Subcommands of the mbi executable. Each app/cmd_*.cpp registers one subcommand with a static
// Registrar; main.cpp builds the CLI11 app from the registry. A subcommand reports bad input by
// throwing any std::exception: main prints "mbi <sub>: error: <message>" on one line and exits 2.
#include <mbi/base/names.hpp>
#include <mbi/error.hpp>
#include <mbi/interp/threads.hpp>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <cmath>
#include <stdexcept>

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

/// Throws naming the key if `j` holds a number that is not finite (nlohmann writes those as
/// null, silently): a result that overflows is an error, never a quiet null in a file.
inline void check_finite(const nlohmann::json& j, const std::string& file, const std::string& key = "") {
  if (j.is_number_float() && !std::isfinite(j.get<double>()))
    throw std::runtime_error(file + ": " + (key.empty() ? "a value" : key) + " is not a finite number (" +
                             std::to_string(j.get<double>()) + ")");
  if (j.is_object())
    for (auto it = j.begin(); it != j.end(); ++it)
      check_finite(*it, file, key.empty() ? it.key() : key + "." + it.key());
  if (j.is_array())
    for (std::size_t i = 0; i < j.size(); ++i) check_finite(j[i], file, key + "[" + std::to_string(i) + "]");
}

/// An option whose values are the names of an enum's table (mbi/base/names.hpp): --help and
/// errors list them, and `value` (an E, or a std::optional<E>) gets the value named.
template <typename E, std::size_t N, typename T>
CLI::Option* add_choice(CLI::App& sub, const std::string& name, T& value, const NameTable<E, N>& names,
                        const std::string& description) {
  auto set = [&value, names, name](const std::string& s) { value = names.parse(s, name); };
  return sub.add_option_function<std::string>(name, set, description)->check(CLI::IsMember(names.names()));
}

/// Runs the check of the layer that owns an option's value (interp's alpha, threads, ...): its
/// mbi::Error becomes an error naming the option, so the command fails before any work.
template <typename Check>
void check_option(const std::string& option, Check&& check) {
  try {
    check();
  } catch (const mbi::Error& e) {
    throw std::runtime_error(option + ": " + e.what());
  }
}

/// --threads N: how many threads the command's computations run on (mbi::interp::set_threads,
/// which checks the count, set when the option is parsed, before the command runs); 0, the
/// default: the cores this process may run on. Every subcommand takes it.
inline CLI::Option* add_threads_option(CLI::App& sub) {
  // decimal digits only: CLI11 would take 0x10 as 16 and 010 as 8
  auto set = [](const std::string& s) {
    const bool digits = !s.empty() && s.size() <= 5 && s.find_first_not_of("0123456789") == std::string::npos;
    if (!digits) throw CLI::ValidationError("--threads " + s + ": give a whole number of threads in decimal digits");
    try {
      interp::set_threads(std::stoi(s));
    } catch (const mbi::Error& e) {
      throw CLI::ValidationError("--threads " + s + ": " + e.what());
    }
  };
  return sub.add_option_function<std::string>("--threads", set,
                                              "threads to compute on, the calling one included (default 0: the cores this process may run on)");
}

struct Registrar {
  Registrar(std::string name, std::string description, Setup setup) {
    registry().push_back({std::move(name), std::move(description), std::move(setup)});
  }
};

}  // namespace mbi::cli
