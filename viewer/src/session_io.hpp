#pragma once
// A session's files (internal): the script of input events to replay, the recording of them in
// the same form, the screenshot and the per-frame report (JSON) the tests read; and the input
// events of each frame. The script format: mbi/viewer/script.hpp.
#include "interaction.hpp"

#include <mbi/io/atomic_file.hpp>
#include <mbi/viewer/script.hpp>

#include <nlohmann/json.hpp>

#include <cstdio>
#include <deque>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace mbi::viewer {

/// The files of one session under the file rules of every mbi command (io::OutputSet,
/// docs/hardening.md). Made before any work: the script (a regular file, kMaxScriptBytes at
/// most) is read, and every output (--record, --screenshot, --report) is checked and reserved:
/// never an input (by file identity), never another output, a regular file or a new name (a
/// FIFO or a device is refused), an existing file only with `force`, in a folder that exists.
/// The recording and the report are written as the session goes (memory stays bounded) into
/// their reserved files, which finish() moves into place with the screenshot. A write error is
/// an error (Error naming the option); destroyed without finish(), no output is created
/// or replaced.
class SessionFiles {
 public:
  /// Throws mbi::Error naming the option and the file.
  explicit SessionFiles(const ViewerOptions& options);
  ~SessionFiles();
  SessionFiles(const SessionFiles&) = delete;
  SessionFiles& operator=(const SessionFiles&) = delete;

  /// The script's events, in frame order (empty without --script); the first call takes them.
  std::deque<Event> take_script() { return std::move(script_); }
  /// Appends an event to the recording, if any. Never throws (GLFW's callbacks call it): a
  /// write error is reported by check().
  void record(const Event& e);
  bool reporting() const { return report_.file != nullptr; }
  /// Whether the session ends with a screenshot (--screenshot): every frame is then kept.
  bool screenshot_at_end() const { return screenshot_.has_value(); }
  /// Appends one frame to the report.
  void report(const nlohmann::json& frame);
  /// Once a frame: flushes the recording; throws Error on a write error of either file.
  void check();
  /// Writes `image` to `name` at once (the p key), under the same rules: an existing file only
  /// with `force`, never an input or an output of this session. Throws mbi::Error.
  void snapshot(const std::filesystem::path& name, const io::Image& image) const;
  /// `name` reserved under the same rules (output 0 of the set), for a file written later (a
  /// video started by a key). Throws mbi::Error.
  std::unique_ptr<io::OutputSet> reserve(const std::filesystem::path& name) const;
  /// --video: the ffmpeg found (checked when the files were made) and the staging file it
  /// writes; empty paths without --video.
  const std::filesystem::path& ffmpeg() const { return ffmpeg_; }
  std::filesystem::path video_staging() const;
  /// Writes the screenshot, ends the report, moves every output into place. Throws
  /// Error, or io::Error when an output cannot be moved into place.
  void finish(const io::Image& last_shot);

 private:
  struct Stream {
    std::FILE* file = nullptr;
    std::string option;             ///< "--record", "--report"
    std::filesystem::path target;
    int error = 0;                  ///< errno of the first failed write
  };
  void open(Stream& s, const std::string& option, std::size_t output, const char* first);
  void write(Stream& s, const std::string& text);
  void close(Stream& s);
  [[noreturn]] void fail(const Stream& s) const;

  std::vector<std::filesystem::path> inputs_;
  bool force_ = false;
  std::unique_ptr<io::OutputSet> outputs_;
  std::vector<std::filesystem::path> targets_;
  std::optional<std::size_t> screenshot_, video_;
  std::filesystem::path ffmpeg_;
  std::deque<Event> script_;
  Stream record_, report_;
  bool report_empty_ = true, finished_ = false;
};

/// The input events of each frame: the window's and a script's, recorded as they happen.
class Inputs {
 public:
  /// Takes the script of `files` and records into it.
  void open(SessionFiles& files);
  /// An event from the window.
  void push(const Event& e);
  /// The events to handle at `frame`, oldest first: the window's so far and the script's that
  /// are due (replayed events are recorded too, at this frame).
  std::deque<Event> take(int frame);

 private:
  std::deque<Event> script_, queue_;
  SessionFiles* files_ = nullptr;
};

/// One frame of the report: frame number, direct mode, method and alpha, finiteness, phase
/// times, largest displacement, energies, the poke, the handles, the camera and the process's
/// resident memory (Linux). With `controls_on_screen`, also where the control vertices are in
/// the window (last view; X3 their drawn positions), for scripts.
nlohmann::json frame_report(const Stage& stage, const Interaction& in, const FrameTimes& times,
                            const Eigen::MatrixXd& X3, const Camera& camera, const WindowSize& window,
                            bool controls_on_screen);

}  // namespace mbi::viewer
