#pragma once
// `mbi view` end to end under Xvfb (xvfb-run, Mesa llvmpipe; no GPU needed), and what the tests
// read back: its per-frame report and its pictures.
#include "common/files.hpp"
#include "common/temp_dir.hpp"

#include <mbi/io/image.hpp>

#include <nlohmann/json.hpp>

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace mbi::test {

struct ViewRun {
  int code = -1;
  std::string err;
};

inline std::string quoted(const std::filesystem::path& p) { return "\"" + p.string() + "\""; }

/// `mbi view <args>` under a fresh Xvfb server (without a display when `display` is false), in
/// `cwd` when given, behind `prefix` (e.g. "timeout 120"); stderr goes through a file in `dir`.
/// The exit code is mbi's own, written by the script xvfb-run runs: xvfb-run's own cleanup can
/// fail (exit 5) after mbi has finished.
inline ViewRun view(const std::string& args, const TempDir& dir, bool display = true,
                    const std::filesystem::path& cwd = {}, const std::string& prefix = "") {
  const std::filesystem::path err = dir / "stderr.txt", code = dir / "exit-code.txt", script = dir / "view.sh";
  std::filesystem::remove(code);
  write_text(script, (cwd.empty() ? "" : "cd " + quoted(cwd) + " || exit 1\n") + prefix + " \"" + MBI_EXE + "\" view " + args +
                         " > /dev/null 2> " + quoted(err) + "\necho $? > " + quoted(code) + "\n");
  const std::string cmd = (display ? "xvfb-run -a -s '-screen 0 1400x900x24' " : "env -u DISPLAY ") + std::string("sh ") +
                          quoted(script) + " > /dev/null 2>&1";
  const int status = std::system(cmd.c_str());
  ViewRun r;
  r.err = slurp(err);
  const std::string written = slurp(code);
  if (!written.empty()) {
    r.code = std::stoi(written);
  } else {  // the script did not finish: xvfb-run's failure, said in the error text
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.err += "(harness: no exit code written; xvfb-run or sh exited with " + std::to_string(r.code) + ")\n";
  }
  return r;
}

inline nlohmann::json read_report(const std::filesystem::path& file) {
  std::ifstream in(file);
  REQUIRE(in);
  return nlohmann::json::parse(in);
}

/// Fraction of pixels that are not the white background.
inline double non_background(const io::Image& a) {
  long long n = 0;
  for (size_t i = 0; i < a.rgb.size(); i += 3) n += !(a.rgb[i] == 255 && a.rgb[i + 1] == 255 && a.rgb[i + 2] == 255);
  return double(n) / (a.width * a.height);
}

}  // namespace mbi::test
