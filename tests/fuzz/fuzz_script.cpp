// libFuzzer target: viewer scripts (`mbi view --script`) through mbi::viewer::parse_script
// (nothing read from disk; docs/hardening.md, seeds in tests/fuzz/script/). What it may do with
// any text: return events within the script's bounds, in frame order, or throw mbi::viewer::Error naming
// the file; every event read is written back by format() to a line that reads as the same event.
#include <mbi/viewer/script.hpp>

#include "fuzz_common.hpp"

#include <cmath>
#include <cstdint>

namespace {

using mbi::fuzz::invariant;
using mbi::viewer::Event;

bool same(const Event& a, const Event& b) {
  return a.frame == b.frame && a.kind == b.kind && a.x == b.x && a.y == b.y && a.dy == b.dy &&
         a.button == b.button && a.key == b.key;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::deque<Event> events;
  try {
    events = mbi::viewer::parse_script(mbi::fuzz::bytes(data, size), "fuzz.txt");
  } catch (const mbi::Error&) {
    return 0;
  }
  int last = 0;
  for (const Event& e : events) {
    invariant(e.frame >= last && e.frame <= mbi::viewer::kMaxScriptFrame, "frames in order and in range");
    last = e.frame;
    invariant(std::isfinite(e.x) && std::isfinite(e.y) && std::isfinite(e.dy), "finite coordinates");
    invariant(e.button >= 0 && e.button <= mbi::viewer::kMaxScriptButton, "button in range");
    invariant(e.kind != Event::Key || mbi::viewer::is_key_name(e.key), "a known key");
    const std::deque<Event> again = mbi::viewer::parse_script(mbi::viewer::format(e), "again.txt");
    invariant(again.size() == 1 && same(again.front(), e), "format() reads back as the same event");
  }
  return 0;
}
