#pragma once
// Runs the `mbi` executable as a user would, through the shell (the test target defines MBI_EXE).
#include "files.hpp"
#include "temp_dir.hpp"

#include <cstdlib>
#include <filesystem>
#include <string>
#include <sys/wait.h>

namespace mbi::test {

struct Result {
  int code = -1;  ///< exit status; -1 when mbi did not exit normally (a signal)
  std::string err, out;
};

/// `p` quoted for the shell: single quotes, a quote inside written as '\''.
inline std::string q(const std::filesystem::path& p) {
  std::string s = "'";
  for (const char c : p.string()) s += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return s + "'";
}

/// Runs `mbi <args>` (args already quoted where needed), in `cwd` when given, with optional
/// environment assignments ("NAME=value ..."); stdout and stderr go through files in `dir`.
inline Result run_mbi(const std::string& args, const TempDir& dir, const std::string& env = "",
                      const std::filesystem::path& cwd = {}) {
  const std::filesystem::path err = dir / "stderr.txt", out = dir / "stdout.txt";
  const std::string cmd = (cwd.empty() ? "" : "cd " + q(cwd) + " && ") + (env.empty() ? "" : "env " + env + " ") +
                          q(MBI_EXE) + " " + args + " > " + q(out) + " 2> " + q(err);
  const int status = std::system(cmd.c_str());
  Result r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.err = slurp(err);
  r.out = slurp(out);
  return r;
}

}  // namespace mbi::test
