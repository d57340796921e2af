#pragma once
// Viewer scripts: the input events of a session, one a line, replayed by `mbi view --script`
// and written by `--record`. No window and no GL here: the fuzz target (tests/fuzz/fuzz_script)
// builds this alone.
//
//   FRAME press X Y BUTTON | FRAME move X Y | FRAME release X Y BUTTON | FRAME scroll DY |
//   FRAME key NAME | FRAME drop PATH
//
// X, Y in window coordinates (logical pixels, y down; any finite value: a drag may leave the
// window), BUTTON 0 to 7 (GLFW's numbers: 0 left, 1 right, 2 middle), NAME one of kKeyNames,
// PATH a model file dropped on the window: the rest of the line, spaces included (no '#').
// Empty lines and lines starting with '#' are skipped; a '#' after an event starts a comment.
// Anything else is an error naming the file and line: an unknown event or key, a missing,
// malformed or out-of-range field, or anything after the event (trailing junk).
#include <mbi/viewer/error.hpp>

#include <cstdint>
#include <deque>
#include <filesystem>
#include <string>
#include <string_view>

namespace mbi::viewer {

/// Largest script read: 16 MiB (about 700,000 events; a recording of hours of dragging).
inline constexpr std::uintmax_t kMaxScriptBytes = std::uintmax_t{16} << 20;
/// Longest script line, comments included: 1024 bytes (an event needs under 80).
inline constexpr std::size_t kMaxScriptLine = 1024;
/// Largest frame number of an event (the largest --frames).
inline constexpr int kMaxScriptFrame = 100000000;
/// Largest mouse button number (GLFW_MOUSE_BUTTON_LAST).
inline constexpr int kMaxScriptButton = 7;

struct Event {
  int frame = 0;
  enum Kind { Press, Move, Release, Scroll, Key, Drop } kind = Move;
  double x = 0, y = 0, dy = 0;
  int button = 0;
  std::string key;
  std::string path;  ///< Drop
};

/// Whether `name` is a key a script may press: space, escape, ?, [, ], a-z, 0-9.
bool is_key_name(std::string_view name);

/// One script line (without the newline); parse_script reads it back.
std::string format(const Event& e);

/// The events of a script's text, in frame order (file order within a frame). `name` names it
/// in messages only. A UTF-8 byte-order mark and CR LF line ends are read like the plain text.
/// Throws Error "<name>:<line>: <what>"; text over kMaxScriptBytes is refused.
std::deque<Event> parse_script(std::string_view text, const std::filesystem::path& name);

/// parse_script on a file: a regular file only (a folder, FIFO or device is refused without
/// blocking, as every reader of mbi does), at most kMaxScriptBytes. Throws Error.
std::deque<Event> read_script(const std::filesystem::path& file);

}  // namespace mbi::viewer
