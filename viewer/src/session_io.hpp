#pragma once
// A session's input and output files (internal): scripts of input events to replay, recordings
// of them in the same form, and the per-frame report (JSON) the tests read.
//
// Script and recording lines: "FRAME EVENT ARGS" in window coordinates (y down):
//   FRAME press X Y BUTTON | FRAME move X Y | FRAME release X Y BUTTON | FRAME scroll DY |
//   FRAME key NAME
#include "interaction.hpp"

#include <nlohmann/json.hpp>

#include <deque>
#include <filesystem>
#include <fstream>
#include <string>

namespace mbi::viewer {

struct Event {
  int frame = 0;
  enum Kind { Press, Move, Release, Scroll, Key } kind = Move;
  double x = 0, y = 0, dy = 0;
  int button = 0;
  std::string key;
};

/// One script line (without the newline).
std::string format(const Event& e);
/// The events of a script file, in frame order. Throws ViewerError naming the file and line.
std::deque<Event> read_script(const std::filesystem::path& file);

/// The input events of each frame: the window's and a script's, recorded as they happen.
class Inputs {
 public:
  /// Reads `script` and opens `record` (either may be empty). Throws ViewerError.
  void open(const std::filesystem::path& script, const std::filesystem::path& record);
  /// An event from the window.
  void push(const Event& e);
  /// The events to handle at `frame`, oldest first: the window's so far and the script's that
  /// are due (replayed events are recorded too, at this frame).
  std::deque<Event> take(int frame);

 private:
  std::deque<Event> script_, queue_;
  std::ofstream record_;
};

/// One frame of the report: frame number, direct mode, finiteness, phase times, largest
/// displacement, energies, the poke and the handles. With `controls_on_screen`, also where the
/// control vertices are in the window (last view; X3 their drawn positions), for scripts.
nlohmann::json frame_report(const Stage& stage, const Interaction& in, const FrameTimes& times,
                            const Eigen::MatrixXd& X3, const Camera& camera, const WindowSize& window,
                            bool controls_on_screen);

}  // namespace mbi::viewer
