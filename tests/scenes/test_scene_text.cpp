// Scene text before and around the TOML parser: nesting depth refused before toml11 recurses
// (a scene nested 100,000 deep overflowed the stack), strings and comments not counted, a
// byte-order mark and CR LF line ends accepted, and the scene fuzz corpus (tests/fuzz/scene/,
// seeds and every input a fuzzer crashed on) replayed through parse_scene.
#include <catch2/catch.hpp>

#include <mbi/scenes/scene.hpp>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace fs = std::filesystem;
using mbi::scenes::parse_scene;

namespace {

const std::string minimal_text = "[dense]\nbuiltin = \"paper-bar\"\n[control]\nbuiltin = \"paper-bar\"\n";

std::string text_error(const std::string& text) {
  try {
    parse_scene(text, "s.toml");
  } catch (const mbi::scenes::Error& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace

TEST_CASE("scene nesting: 100,000 deep is refused naming the line, not a stack overflow",
          "[scene][hardening]") {
  for (const char* open_close : {"[]", "{}"}) {
    std::string deep = minimal_text + "\n# a comment [[[[\nx = ";
    for (int i = 0; i < 100000; ++i) deep += open_close[0] == '[' ? "[" : "{a=";
    deep += "1";
    deep += std::string(100000, open_close[1]);
    INFO(open_close);
    REQUIRE_THAT(text_error(deep),
                 Catch::StartsWith("s.toml:7: arrays and inline tables nest deeper than 16 levels"));
  }
  // 16 levels pass the pre-scan (and the key is then unknown), 17 do not
  const std::string at16 = minimal_text + "x = " + std::string(16, '[') + std::string(16, ']') + "\n";
  const std::string at17 = minimal_text + "x = " + std::string(17, '[') + std::string(17, ']') + "\n";
  REQUIRE_THAT(text_error(at16), !Catch::Contains("nest deeper") && Catch::Contains("x"));
  REQUIRE_THAT(text_error(at17), Catch::Contains("s.toml:5: arrays and inline tables nest deeper"));
}

TEST_CASE("scene nesting: dotted keys and table headers of 100,000 parts are refused",
          "[scene][hardening]") {
  std::string dotted = "a";
  for (int i = 0; i < 100000; ++i) dotted += ".a";
  REQUIRE_THAT(text_error(minimal_text + dotted + " = 1\n"),
               Catch::StartsWith("s.toml:5: dotted keys nest deeper than 16 levels"));
  REQUIRE_THAT(text_error(minimal_text + "[" + dotted + "]\n"),
               Catch::StartsWith("s.toml:5: dotted keys nest deeper than 16 levels"));
  REQUIRE_THAT(text_error(minimal_text + "x = {" + dotted + " = 1}\n"),
               Catch::StartsWith("s.toml:5: dotted keys nest deeper than 16 levels"));
  // dots in values (numbers, strings) are not key parts
  std::string floats = "x = [";
  for (int i = 0; i < 100; ++i) floats += "1.5, ";
  REQUIRE_THAT(text_error(minimal_text + floats + "2.5]\ny = {a = 1.5, b = \"a.b.c.d.e.f.g.h.i.j.k.l.m.n.o.p.q.r\"}\n"),
               !Catch::Contains("nest deeper"));
}

TEST_CASE("scene nesting: brackets in strings and comments are not counted", "[scene][hardening]") {
  const std::string many = std::string(40, '[') + std::string(40, '{');
  const std::string text = "# " + many + "\n[dense]\nbuiltin = 'paper-bar'\nnote = \"" + many +
                           "\"  # " + many + "\nnote2 = '''\n" + many + "\n'''\n" +
                           "[control]\nbuiltin = \"paper-bar\"\n";
  // no nesting error: the scene is read up to its unknown key
  REQUIRE_THAT(text_error(text), !Catch::Contains("nest deeper") && Catch::Contains("note"));
  REQUIRE_THAT(text_error("[dense]\nbuiltin = 'paper-bar'\nnote = \"a\\\"[[[[[[[[[[[[[[[[[[\"\n"),
               !Catch::Contains("nest deeper") && Catch::Contains("note"));
}

TEST_CASE("scene text: byte-order mark and CR LF line ends are read", "[scene][hardening]") {
  std::string crlf;
  for (char c : minimal_text) crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
  REQUIRE_NOTHROW(parse_scene("\xEF\xBB\xBF" + crlf, "s.toml"));
}

TEST_CASE("scene text: bytes that are not UTF-8 and control characters are refused, naming the line",
          "[scene][hardening]") {
  REQUIRE_THAT(text_error(minimal_text + "name = \"\xF8\x9B\"\n"),
               Catch::StartsWith("s.toml:5: syntax error: not UTF-8 text (byte 0xF8)"));
  REQUIRE_THAT(text_error(minimal_text + "# \x1C\n"),
               Catch::StartsWith("s.toml:5: syntax error: control character (byte 0x1C)"));
  REQUIRE_THAT(text_error(minimal_text + "x = 1\ry = 2\n"),
               Catch::StartsWith("s.toml:5: syntax error: a CR not followed by LF"));
  // UTF-8 in strings and comments, and tabs, are fine: the error is the unknown key
  REQUIRE_THAT(text_error(minimal_text + "note =\t\"\xC3\xA9t\xC3\xA9 \xE2\x82\xAC \xF0\x9F\x98\x80\"  # caf\xC3\xA9\n"),
               Catch::Contains("note") && !Catch::Contains("syntax error"));
}

TEST_CASE("scene fuzz corpus replayed: a scene or a mbi::scenes::Error, nothing else", "[scene][hardening][fuzz]") {
  const char* src = std::getenv("MBI_SOURCE_DIR");
  REQUIRE(src != nullptr);
  int files = 0;
  for (const auto& e : fs::directory_iterator(fs::path(src) / "tests" / "fuzz" / "scene")) {
    std::ifstream in(e.path(), std::ios::binary);
    const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    INFO(e.path());
    try {
      parse_scene(text, "/nonexistent/fuzz.toml");
    } catch (const mbi::Error& err) {
      REQUIRE_THAT(err.what(), Catch::StartsWith("/nonexistent/fuzz.toml"));
    }
    ++files;
  }
  REQUIRE(files >= 6);
}
