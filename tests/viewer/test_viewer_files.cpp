// The viewer's files and hostile input: the script reader (headless: every event round trips,
// errors name file and line, bounds, the fuzz corpus replayed), the camera under moves of any
// size; then `mbi view` under Xvfb: drags of +-1e308 pixels, a p screenshot that cannot be
// written, a recording onto a full disk. The refusals themselves are bad-input cases
// (tests/data/bad/viewer.cases).
#include <catch2/catch.hpp>

#include <mbi/viewer/camera.hpp>
#include <mbi/viewer/script.hpp>

#include "common/skip.hpp"
#include "viewer_run.hpp"

#include <cmath>
#include <limits>
#include <sstream>

namespace fs = std::filesystem;
using mbi::test::quoted;
using mbi::test::source_dir;
using mbi::test::TempDir;
using mbi::test::view;
using namespace mbi::viewer;

namespace {

std::string error_of(const std::string& text) {
  try {
    parse_script(text, "s.txt");
  } catch (const mbi::viewer::Error& e) {
    return e.what();
  }
  return "";
}

std::string corpus_scene() { return quoted(source_dir() / "tests" / "data" / "bad" / "viewer" / "view.toml"); }

bool finite_camera(const nlohmann::json& c) {
  for (const auto& v : {c["radius"], c["yaw"], c["pitch"], c["target"][0], c["target"][1], c["target"][2]})
    if (!v.is_number() || !std::isfinite(v.get<double>())) return false;
  return true;
}

}  // namespace

TEST_CASE("viewer scripts: every event reads back as written, and comments, CR LF and a BOM read like plain text",
          "[viewer][script]") {
  const std::deque<Event> events = parse_script(
      "\xEF\xBB\xBF# a recording\r\n\r\n3 key [   # alpha / 2\r\n1 press 1036.7346938775 -262.5 0\r\n"
      "\t2\tmove 1e308 -1.7976931348623157e308\r2 release 5 6 7\n4 scroll -0.125\n5 key escape",
      "s.txt");
  REQUIRE(events.size() == 6);
  CHECK(events[0].frame == 1);  // in frame order, file order within a frame
  CHECK(events[1].kind == Event::Move);
  CHECK(events[1].y == -std::numeric_limits<double>::max());
  CHECK(events[2].button == 7);
  CHECK(events[3].key == "[");
  for (const Event& e : events) {
    const std::deque<Event> again = parse_script(format(e), "again.txt");
    REQUIRE(again.size() == 1);
    CHECK(format(again.front()) == format(e));
    CHECK(again.front().x == e.x);
    CHECK(again.front().y == e.y);
    CHECK(again.front().dy == e.dy);
  }
}

TEST_CASE("viewer scripts: unknown events and keys, trailing junk and bad fields are errors naming file and line",
          "[viewer][script]") {
  CHECK(error_of("# keys\n0 key zz\n") == "s.txt:2: unknown key 'zz' (space, escape, ?, [, ], a-z, 0-9)");
  CHECK(error_of("1 press 1 2 0 junk\n") == "s.txt:1: unexpected 'junk' after the event");
  CHECK(error_of("1 key a b\n") == "s.txt:1: unexpected 'b' after the event");
  CHECK(error_of("0 jump 1 2\n") == "s.txt:1: unknown event 'jump' (press, move, release, scroll, key, drop)");
  CHECK(error_of("4 press 10 20\n") == "s.txt:1: 'press' takes X Y BUTTON");
  CHECK(error_of("4 press 10 20 8\n") == "s.txt:1: 'press': BUTTON '8' is not 0 to 7");
  CHECK(error_of("4 press 10 20 0.5\n") == "s.txt:1: 'press': BUTTON '0.5' is not 0 to 7");
  CHECK(error_of("2 move nan 1\n") == "s.txt:1: 'move': X 'nan' is not a finite number");
  CHECK(error_of("2 move 1 1e309\n") == "s.txt:1: 'move': Y '1e309' is not a finite number");
  CHECK(error_of("2 scroll 0x10\n") == "s.txt:1: 'scroll': DY '0x10' is not a finite number");
  CHECK(error_of("-1 key a\n") == "s.txt:1: frame '-1' is not a whole number from 0 to 100000000");
  CHECK(error_of("100000001 key a\n") == "s.txt:1: frame '100000001' is not a whole number from 0 to 100000000");
  CHECK(error_of("1.5 key a\n") == "s.txt:1: frame '1.5' is not a whole number from 0 to 100000000");
  CHECK(error_of("7\n") == "s.txt:1: expected FRAME EVENT ...");
  CHECK(error_of("1 key h\n#" + std::string(kMaxScriptLine, 'x') + "\n") ==
        "s.txt:2: line of 1025 bytes is longer than the 1024 bytes a script line may have");
  CHECK(error_of("1 key h\n#" + std::string(kMaxScriptLine - 1, 'x') + "\n").empty());  // at the bound
  // a large text: refused before any line is read
  const std::string big(kMaxScriptBytes + 1, '\n');
  CHECK_THAT(error_of(big), Catch::StartsWith("s.txt: script of 16777217 bytes is larger than the 16777216"));
}

TEST_CASE("viewer scripts: only regular files of at most 16 MiB are read, without blocking", "[viewer][script]") {
  TempDir dir("script");
  const fs::path big = dir / "big.txt";
  std::ofstream(big) << "1 key h\n";
  fs::resize_file(big, kMaxScriptBytes + 1);  // sparse: no 16 MiB written
  CHECK_THROWS_WITH(read_script(big), Catch::Contains("big.txt: script of 16777217 bytes is larger than"));
  CHECK_THROWS_WITH(read_script(dir.path()), Catch::Contains("is a directory, not a regular file"));
  CHECK_THROWS_WITH(read_script("/dev/zero"), Catch::Contains("/dev/zero: is a character device"));
  REQUIRE(std::system(("mkfifo " + quoted(dir / "fifo")).c_str()) == 0);
  CHECK_THROWS_WITH(read_script(dir / "fifo"), Catch::Contains("is a FIFO (named pipe)"));
}

TEST_CASE("viewer script fuzz corpus replayed: events within the bounds or a mbi::viewer::Error", "[viewer][script][fuzz]") {
  int files = 0, read = 0;
  for (const auto& e : fs::directory_iterator(source_dir() / "tests" / "fuzz" / "script")) {
    INFO(e.path());
    const std::string text = mbi::test::slurp(e.path());
    ++files;
    try {
      for (const Event& ev : parse_script(text, "fuzz.txt")) {
        REQUIRE(std::isfinite(ev.x));
        REQUIRE(parse_script(format(ev), "again.txt").size() == 1);
      }
      ++read;
    } catch (const mbi::viewer::Error& err) {
      REQUIRE_THAT(err.what(), Catch::StartsWith("fuzz.txt"));
    }
  }
  CHECK(files >= 8);
  CHECK(read >= 6);
}

TEST_CASE("viewer camera: moves of any size, inf and NaN leave it finite", "[viewer]") {
  Camera cam;
  cam.frame(Eigen::Vector3d::Zero(), Eigen::Vector3d(1, 2, 3));
  const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
  for (double d : {1e308, -1e308, inf, -inf, nan}) {
    cam.orbit(d, -d);
    cam.pan(d, d, 720);
    cam.pan(-d, d, 0);
    cam.zoom(d);
    INFO(d);
    REQUIRE(cam.target.allFinite());
    REQUIRE(std::isfinite(cam.yaw));
    REQUIRE(std::abs(cam.yaw) <= std::acos(-1.0));
    REQUIRE(std::abs(cam.pitch) <= 1.5);
    REQUIRE(std::isfinite(cam.radius));
    REQUIRE(cam.direction().allFinite());
    REQUIRE(cam.view_projection(1.5).allFinite());
    REQUIRE((cam.target - cam.home).norm() <= Camera::kMaxPan * cam.depth * (1 + 1e-12));
  }
  cam.frame(Eigen::Vector3d::Zero(), Eigen::Vector3d(1, 2, 3));  // f frames it again
  CHECK(cam.target.isApprox(Eigen::Vector3d(0.5, 1, 1.5)));
}

TEST_CASE("mbi view: drags of +-1e308 pixels keep the camera finite and the model in the picture", "[viewer][xvfb]") {
  TempDir dir("view");
  // orbit (left button on the background) and pan (right) by +-1e308 and the largest double
  std::ofstream(dir / "huge.txt") << "1 press 5 5 0\n2 move 1e308 -1e308\n3 move -1e308 1e308\n"
                                     "4 move 1.7976931348623157e308 -1.7976931348623157e308\n5 release 0 0 0\n"
                                     "6 press 5 5 1\n7 move 1e308 -1e308\n8 move -1e308 1e308\n9 release 0 0 1\n";
  const mbi::test::ViewRun r = view(corpus_scene() + " --frames 12 --no-panel --script " + quoted(dir / "huge.txt") +
                                        " --report " + quoted(dir / "r.json") + " --screenshot " + quoted(dir / "s.png"),
                                    dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
  const nlohmann::json rep = mbi::test::read_report(dir / "r.json");
  REQUIRE(rep.size() == 12);
  for (const auto& fr : rep) REQUIRE(finite_camera(fr["camera"]));
  CHECK(rep.back()["camera"]["yaw"].get<double>() != rep.front()["camera"]["yaw"].get<double>());  // it orbited
  CHECK(mbi::test::non_background(mbi::io::read_png(dir / "s.png")) > 0.01);  // not blank
}

TEST_CASE("mbi view: a p screenshot that cannot be written is said, and the session goes on", "[viewer][xvfb]") {
  TempDir dir("view");
  fs::create_directory(dir / "mbi-screenshot-0003.png");  // in the way: a folder of that name
  std::ofstream(dir / "p.txt") << "3 key p\n5 key p\n";
  const mbi::test::ViewRun r =
      view(corpus_scene() + " --frames 8 --no-panel --script p.txt --report r.json --screenshot last.png", dir, true,
           dir.path());
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK_THAT(r.err, Catch::Contains("mbi view: screenshot not written: mbi-screenshot-0003.png: is a folder"));
  const nlohmann::json rep = mbi::test::read_report(dir / "r.json");
  REQUIRE(rep.size() == 8);  // every frame after it too
  CHECK_THAT(rep[4]["message"].get<std::string>(), Catch::StartsWith("screenshot not written"));
  CHECK(rep[7]["message"].get<std::string>() == "screenshot: mbi-screenshot-0005.png");
  CHECK(fs::is_regular_file(dir / "mbi-screenshot-0005.png"));
  CHECK(fs::is_regular_file(dir / "last.png"));
}

TEST_CASE("mbi view: a recording onto a full disk is an error, and no output is left", "[viewer][xvfb]") {
  TempDir dir("view");
  const fs::path full = dir / "full";
  fs::create_directory(full);
  // a 64 KiB tmpfs, filled (root only; elsewhere the bad-input case record-disk-full covers
  // the write error with a file-size limit)
  if (std::system(("mount -t tmpfs -o size=64k tmpfs " + quoted(full) + " 2>/dev/null").c_str()) != 0)
    mbi::test::skip("cannot mount a small tmpfs here (not root)");
  struct Unmount {
    fs::path p;
    ~Unmount() { (void)std::system(("umount " + quoted(p)).c_str()); }
  } unmount{full};
  (void)std::system(("dd if=/dev/zero of=" + quoted(full / "fill") + " bs=1k count=64 2>/dev/null").c_str());
  std::ofstream(dir / "keys.txt") << "1 key h\n2 key h\n";
  const mbi::test::ViewRun r = view(corpus_scene() + " --frames 5 --no-panel --script " + quoted(dir / "keys.txt") +
                                        " --record " + quoted(full / "rec.txt") + " --report " + quoted(dir / "r.json"),
                                    dir);
  INFO(r.err);
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::StartsWith("mbi view: error: --record ") &&
                        Catch::Contains("rec.txt: write error (No space left on device)"));
  CHECK_FALSE(fs::exists(dir / "r.json"));
  int left = 0;
  for (const auto& e : fs::directory_iterator(full)) left += e.path().filename() != "fill";
  CHECK(left == 0);  // no recording, no temporary
}
