// libFuzzer target: scene files (TOML) through the scene parser and validator,
// mbi::scenes::parse_scene (no run, nothing read from disk: a mesh collider's file is named, not
// read; docs/hardening.md, seeds in tests/fuzz/scene/). What it may do with any text: return a
// scene or throw an mbi::Error (mbi::scenes::Error) naming the file; anything else (another
// exception, a crash, a stack overflow in the TOML parser) is reported by libFuzzer.
#include <mbi/scenes/scene.hpp>

#include <cstdint>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view in(reinterpret_cast<const char*>(data), size);
  try {
    (void)mbi::scenes::parse_scene(in, "/nonexistent/fuzz.toml");
  } catch (const mbi::Error&) {
  }
  return 0;
}
