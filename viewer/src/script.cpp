#include <mbi/io/parse.hpp>
#include <mbi/viewer/script.hpp>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <vector>

namespace mbi::viewer {
namespace {

[[noreturn]] void fail(const std::filesystem::path& name, long long line, const std::string& what) {
  throw Error(name.string() + (line > 0 ? ":" + std::to_string(line) : "") + ": " + what);
}

// The words of a line before any '#' comment (separated by spaces and tabs).
std::vector<std::string_view> words(std::string_view line) {
  line = line.substr(0, line.find('#'));
  std::vector<std::string_view> w;
  std::size_t i = 0;
  while (i < line.size()) {
    if (line[i] == ' ' || line[i] == '\t') {
      ++i;
      continue;
    }
    const std::size_t end = std::min(line.find_first_of(" \t", i), line.size());
    w.push_back(line.substr(i, end - i));
    i = end;
  }
  return w;
}

template <typename T>
bool whole_word(std::string_view w, T& value) {
  const auto [end, ec] = std::from_chars(w.data(), w.data() + w.size(), value);
  return ec == std::errc() && end == w.data() + w.size();
}

// A drop's PATH: the line after the event's word, without a comment and outer blanks.
std::string drop_path(std::string_view line) {
  line = line.substr(0, line.find('#'));
  const std::size_t at = line.find("drop") + 4;
  const std::size_t first = line.find_first_not_of(" \t", at);
  if (first == std::string_view::npos) return {};
  const std::size_t last = line.find_last_not_of(" \t");
  return std::string(line.substr(first, last + 1 - first));
}

// One event line of at least two words; throws naming the line.
Event parse_event(const std::vector<std::string_view>& w, const std::filesystem::path& name, long long line) {
  Event e;
  if (!whole_word(w[0], e.frame) || e.frame < 0 || e.frame > kMaxScriptFrame)
    fail(name, line, "frame '" + std::string(w[0]) + "' is not a whole number from 0 to " + std::to_string(kMaxScriptFrame));
  const std::string_view kind = w[1];
  std::size_t fields = 0;  // after FRAME EVENT
  const char* usage = "";
  if (kind == "press") e.kind = Event::Press, fields = 3, usage = "X Y BUTTON";
  else if (kind == "release") e.kind = Event::Release, fields = 3, usage = "X Y BUTTON";
  else if (kind == "move") e.kind = Event::Move, fields = 2, usage = "X Y";
  else if (kind == "scroll") e.kind = Event::Scroll, fields = 1, usage = "DY";
  else if (kind == "key") e.kind = Event::Key, fields = 1, usage = "NAME";
  else if (kind == "drop") e.kind = Event::Drop, fields = w.size() - 2, usage = "PATH";
  else fail(name, line, "unknown event '" + std::string(kind) + "' (press, move, release, scroll, key, drop)");
  const std::string what = "'" + std::string(kind) + "'";
  if (w.size() < 2 + fields || (e.kind == Event::Drop && fields == 0)) fail(name, line, what + " takes " + usage);
  if (w.size() > 2 + fields) fail(name, line, "unexpected '" + std::string(w[2 + fields]) + "' after the event");
  const auto number = [&](std::size_t i, const char* field) {
    double v = 0;
    if (!whole_word(w[i], v) || !std::isfinite(v))
      fail(name, line, what + ": " + field + " '" + std::string(w[i]) + "' is not a finite number");
    return v;
  };
  if (e.kind == Event::Scroll) e.dy = number(2, "DY");
  if (e.kind == Event::Key) {
    if (!is_key_name(w[2]))
      fail(name, line, "unknown key '" + std::string(w[2]) + "' (space, escape, ?, [, ], a-z, 0-9)");
    e.key = w[2];
  }
  if (e.kind == Event::Drop) return e;  // its PATH is the rest of the line (parse_script)
  if (fields >= 2) e.x = number(2, "X"), e.y = number(3, "Y");
  if (fields == 3 && (!whole_word(w[4], e.button) || e.button < 0 || e.button > kMaxScriptButton))
    fail(name, line, what + ": BUTTON '" + std::string(w[4]) + "' is not 0 to " + std::to_string(kMaxScriptButton));
  return e;
}

std::string shortest(double v) {
  std::array<char, 32> buf{};
  const auto r = std::to_chars(buf.data(), buf.data() + buf.size(), v);
  return std::string(buf.data(), r.ptr);
}

}  // namespace

bool is_key_name(std::string_view k) {
  if (k == "space" || k == "escape") return true;
  if (k.size() != 1) return false;
  const char c = k[0];
  return c == '?' || c == '[' || c == ']' || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9');
}

std::string format(const Event& e) {
  std::string s = std::to_string(e.frame) + " ";
  const std::string xy = shortest(e.x) + " " + shortest(e.y);
  switch (e.kind) {
    case Event::Press: return s + "press " + xy + " " + std::to_string(e.button);
    case Event::Move: return s + "move " + xy;
    case Event::Release: return s + "release " + xy + " " + std::to_string(e.button);
    case Event::Scroll: return s + "scroll " + shortest(e.dy);
    case Event::Key: return s + "key " + e.key;
    case Event::Drop: return s + "drop " + e.path;
  }
  return s;
}

std::deque<Event> parse_script(std::string_view text, const std::filesystem::path& name) {
  if (text.size() > kMaxScriptBytes)
    fail(name, 0, "script of " + std::to_string(text.size()) + " bytes is larger than the " +
                      std::to_string(kMaxScriptBytes) + " bytes a script may have");
  if (text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);
  std::deque<Event> events;
  long long number = 0;
  std::size_t pos = 0;
  while (pos < text.size()) {
    ++number;
    const std::size_t end = std::min(text.find_first_of("\r\n", pos), text.size());
    const std::string_view line = text.substr(pos, end - pos);
    pos = end + (end + 1 < text.size() && text[end] == '\r' && text[end + 1] == '\n' ? 2 : 1);
    if (line.size() > kMaxScriptLine)
      fail(name, number, "line of " + std::to_string(line.size()) + " bytes is longer than the " +
                             std::to_string(kMaxScriptLine) + " bytes a script line may have");
    const std::vector<std::string_view> w = words(line);
    if (w.empty()) continue;
    if (w.size() < 2) fail(name, number, "expected FRAME EVENT ...");
    events.push_back(parse_event(w, name, number));
    if (events.back().kind == Event::Drop) events.back().path = drop_path(line);
  }
  std::stable_sort(events.begin(), events.end(), [](const Event& a, const Event& b) { return a.frame < b.frame; });
  return events;
}

std::deque<Event> read_script(const std::filesystem::path& file) {
  std::error_code ec;
  // read_bytes refuses what is not a regular file without opening it; a large one is refused
  // here first, before it is read
  const auto st = std::filesystem::status(file, ec);
  if (std::filesystem::is_regular_file(st)) {
    const std::uintmax_t size = std::filesystem::file_size(file, ec);
    if (!ec && size > kMaxScriptBytes)
      fail(file, 0, "script of " + std::to_string(size) + " bytes is larger than the " +
                        std::to_string(kMaxScriptBytes) + " bytes a script may have");
  }
  try {
    return parse_script(io::read_bytes(file), file);
  } catch (const io::Error& e) {
    throw Error(e.what());
  }
}

}  // namespace mbi::viewer
