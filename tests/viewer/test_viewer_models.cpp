// `mbi view MODEL` under Xvfb: the built-in models, every real model ($MBI_MODELS_DIR), a multi-part
// glTF, a scene of several [[dense]] models and a
// generated flat one start paused, take a scripted poke and close cleanly; a scripted drop
// loads a model (and a bad one is said, the session going on); --video writes a video that
// ffprobe reads with the frames and size asked for, its last frame the window's last picture
// upright (so does the o key's), and is refused at once without ffmpeg.
#include <catch2/catch.hpp>

#include <mbi/io/io.hpp>
#include <mbi/viewer/script.hpp>

#include "common/sanitizers.hpp"
#include "common/skip.hpp"
#include "viewer_run.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <vector>

namespace fs = std::filesystem;
using mbi::test::source_dir;
using mbi::test::TempDir;

namespace {

fs::path cube() { return fs::path(source_dir()) / "tests" / "viewer" / "cube.obj"; }


// Plays, grabs the middle of the one view (480 x 360, no panel) and pulls up and right.
std::string poke_script() {
  std::ostringstream s;
  s << "0 key space\n2 press 240 180 0\n";
  for (int f = 3; f < 11; ++f) s << f << " move " << 240 + 5 * (f - 2) << " " << 180 - 4 * (f - 2) << "\n";
  s << "12 release 290 140 0\n";
  return s.str();
}

const std::string kSmall = " --width 480 --height 360 --no-panel --no-split --frames 16";

// `mbi view model` with the poke script; checks it closed cleanly, stayed finite, was poked
// and moved. Returns its report.
nlohmann::json view_and_poke(const std::string& model, const TempDir& dir) {
  std::ofstream(dir / "poke.txt") << poke_script();
  const fs::path rep = dir / "report.json";
  const mbi::test::ViewRun r =
      mbi::test::view(model + kSmall + " --script " + mbi::test::quoted(dir / "poke.txt") + " --report " + mbi::test::quoted(rep) + " --force", dir);
  INFO(model << ": " << r.err);
  REQUIRE(r.code == 0);
  const nlohmann::json frames = mbi::test::read_report(rep);
  REQUIRE(frames.size() == 16);
  CHECK(frames[0]["max_displacement"].get<double>() < 1e-9);  // paused until the space key
  bool poked = false;
  for (const auto& fr : frames) {
    CHECK(fr["finite"].get<bool>());
    poked = poked || fr.contains("poke");
  }
  CHECK(poked);
  CHECK(frames.back()["max_displacement"].get<double>() > 0);
  CHECK(frames.back()["looks"] == "software");  // llvmpipe: chosen automatically
  return frames;
}

// Mean absolute difference (0..255) of the window's picture `shot` and a decoded video frame
// (the window's lower left part), the frame's rows taken bottom to top when `flip`.
double video_difference(const mbi::io::Image& shot, const mbi::io::Image& frame, bool flip) {
  REQUIRE(shot.width >= frame.width);
  REQUIRE(shot.height == frame.height);
  double sum = 0;
  for (int y = 0; y < frame.height; ++y)
    for (int x = 0; x < frame.width; ++x)
      for (int c = 0; c < 3; ++c)
        sum += std::abs(int(shot.at(x, y)[c]) - int(frame.at(x, flip ? frame.height - 1 - y : y)[c]));
  return sum / (3.0 * frame.width * frame.height);
}

}  // namespace

TEST_CASE("mbi view MODEL: the built-in models start paused, are poked and close", "[viewer][xvfb]") {
  TempDir dir("view-builtin");
  // under ASan the cylinder only: a cage around tens of thousands of points takes half a minute
  for (const char* model : {"cylinder", "paper-bar", "bumpy-sphere"})
    if (!mbi::test::kSanitized || std::string(model) == "cylinder") view_and_poke(model, dir);
}

TEST_CASE("mbi view MODEL: every real model starts paused, is poked and closes", "[viewer][xvfb]") {
  const fs::path models = mbi::test::models_dir_or_skip();
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(models))
    if (mbi::io::is_surface_file(e.path())) files.push_back(e.path());
  // the smallest first; under the sanitizers the two smallest only
  std::sort(files.begin(), files.end(), [](const fs::path& a, const fs::path& b) { return fs::file_size(a) < fs::file_size(b); });
  if (mbi::test::kSanitized && files.size() > 2) files.resize(2);
  REQUIRE(!files.empty());
  TempDir dir("view-models");
  for (const fs::path& f : files) view_and_poke(mbi::test::quoted(f), dir);
}

TEST_CASE("mbi view MODEL: a flat model (a sheet) is poked in 3D", "[viewer][xvfb]") {
  TempDir dir("view-flat");
  std::ofstream obj(dir / "sheet.obj");
  const int nx = 12, ny = 8;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) obj << "v " << 2.0 * i / nx << " " << 1.0 * j / ny << " 0\n";
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int a = j * (nx + 1) + i + 1, b = a + 1, c = a + nx + 1, d = c + 1;
      obj << "f " << a << " " << b << " " << d << "\nf " << a << " " << d << " " << c << "\n";
    }
  obj.close();
  view_and_poke(mbi::test::quoted(dir / "sheet.obj"), dir);
}

TEST_CASE("mbi view: a multi-part glTF and a scene of several [[dense]] models show every part", "[viewer][xvfb]") {
  TempDir dir("view-parts");
  const fs::path data = fs::path(source_dir()) / "tests";
  fs::copy_file(data / "gltf" / "data" / "parts.glb", dir / "parts.glb");
  fs::copy_file(data / "data" / "vtu" / "sphere.obj", dir / "sphere.obj");
  const long long parts = mbi::io::read_surface(dir / "parts.glb").V.rows();
  const long long sphere = mbi::io::read_surface(dir / "sphere.obj").V.rows();
  // the glTF's parts as one model
  nlohmann::json frames = view_and_poke(mbi::test::quoted(dir / "parts.glb"), dir);
  CHECK(frames.back()["dense_points"].get<long long>() == parts);
  // both files in one control mesh, as a scene
  const std::string cage = "cd " + mbi::test::quoted(dir.path()) + " && \"" + MBI_EXE + "\" cage parts.glb sphere.obj -n 80 -o two > /dev/null";
  REQUIRE(std::system(cage.c_str()) == 0);
  std::ofstream(dir / "two.toml") << "name = \"two\"\n[[dense]]\npath = \"parts.glb\"\n[[dense]]\npath = \"sphere.obj\"\n"
                                     "[control]\npath = \"two.node\"\n[simulation]\ndt = 0.04\ngravity = [0, -9.81, 0]\n"
                                     "[[constraints]]\ntype = \"fixed\"\n"
                                     "select = { box_relative = { min = [0, 0.9, 0], max = [1, 1, 1] } }\n";
  const mbi::test::ViewRun r =
      mbi::test::view(mbi::test::quoted(dir / "two.toml") + kSmall + " --report " + mbi::test::quoted(dir / "two.json"), dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
  frames = mbi::test::read_report(dir / "two.json");
  REQUIRE(frames.size() == 16);
  CHECK(frames.back()["dense_points"].get<long long>() == parts + sphere);
  CHECK(frames.back()["finite"].get<bool>());
  CHECK(frames.back()["max_displacement"].get<double>() > 0);  // it sags under gravity
}

TEST_CASE("mbi view: a scripted drop loads the model, a bad one is said and the session goes on", "[viewer][xvfb]") {
  TempDir dir("view-drop");
  // an octahedron dropped on the cube (small models: quick under ASan too)
  std::ofstream(dir / "octahedron.obj") << "v 1 0 0\nv -1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nv 0 0 -1\n"
                                           "f 1 3 5\nf 3 2 5\nf 2 4 5\nf 4 1 5\nf 3 1 6\nf 2 3 6\nf 4 2 6\nf 1 4 6\n";
  std::ofstream(dir / "notes.txt") << "not a model\n";
  std::ofstream(dir / "drop.txt") << "2 drop " << (dir / "missing.obj").string() << "\n"
                                   << "3 drop " << (dir / "notes.txt").string() << "  # a comment\n"
                                   << "5 drop " << (dir / "octahedron.obj").string() << "\n";
  const mbi::test::ViewRun r = mbi::test::view(
      mbi::test::quoted(cube()) + kSmall + " --script " + mbi::test::quoted(dir / "drop.txt") + " --report " + mbi::test::quoted(dir / "r.json"), dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(r.err.find("missing.obj") != std::string::npos);
  CHECK(r.err.find("notes.txt: not a model") != std::string::npos);
  const nlohmann::json frames = mbi::test::read_report(dir / "r.json");
  CHECK(frames.front()["dense_points"].get<long long>() == 8);  // the cube
  CHECK(frames.back()["dense_points"].get<long long>() == 6);   // the octahedron
}

TEST_CASE("mbi view --video: ffprobe reads the frames and size asked for, and without ffmpeg no window opens", "[viewer][xvfb]") {
  TempDir dir("view-video");
  const fs::path video = dir / "out.mp4";
  const int frames = mbi::test::kSanitized ? 6 : 12;
  const mbi::test::ViewRun r = mbi::test::view(
      mbi::test::quoted(cube()) + " --width 321 --height 240 --no-panel --frames " + std::to_string(frames) + " --video " + mbi::test::quoted(video) +
          " --screenshot " + mbi::test::quoted(dir / "last.png"),
      dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(r.err.find("320 x 240 at 30 fps") != std::string::npos);  // even sizes for the codec
  const std::string probe = "ffprobe -v error -count_frames -select_streams v:0 -show_entries "
                            "stream=width,height,nb_read_frames -of csv=p=0 " + mbi::test::quoted(video) + " > " + mbi::test::quoted(dir / "probe.txt");
  REQUIRE(std::system(probe.c_str()) == 0);
  CHECK(mbi::test::slurp(dir / "probe.txt") == "320,240," + std::to_string(frames) + "\n");
  const std::string decode = "ffmpeg -v error -sseof -0.04 -i " + mbi::test::quoted(video) + " -frames:v 1 " + mbi::test::quoted(dir / "decoded.png");
  REQUIRE(std::system(decode.c_str()) == 0);
  const mbi::io::Image shot = mbi::io::read_png(dir / "last.png"), decoded = mbi::io::read_png(dir / "decoded.png");
  const double upright = video_difference(shot, decoded, false), flipped = video_difference(shot, decoded, true);
  CHECK(upright < 6);  // the codec's loss only
  CHECK(flipped > 3 * upright);
  for (const auto& e : fs::directory_iterator(dir.path())) CHECK(e.path().filename().string().rfind(".mbi-tmp", 0) != 0);
  // the o key: a video from one press to the next, in the current folder, named by the frame
  std::ofstream(dir / "o.txt") << "1 key o\n6 key o\n";
  const mbi::test::ViewRun o = mbi::test::view(
      mbi::test::quoted(cube()) + " --width 320 --height 240 --no-panel --frames 8 --script " + mbi::test::quoted(dir / "o.txt"), dir, true, dir.path());
  INFO(o.err);
  REQUIRE(o.code == 0);
  const std::string probe_o = "ffprobe -v error -count_frames -select_streams v:0 -show_entries "
                              "stream=width,height,nb_read_frames -of csv=p=0 " + mbi::test::quoted(dir / "mbi-video-0001.mp4") +
                              " > " + mbi::test::quoted(dir / "probe-o.txt");
  REQUIRE(std::system(probe_o.c_str()) == 0);
  CHECK(mbi::test::slurp(dir / "probe-o.txt") == "320,240,5\n");
  // without ffmpeg on PATH: refused before any window (no display needed), nothing written
  const std::string cmd = "env -u DISPLAY PATH=/nonexistent \"" + std::string(MBI_EXE) + "\" view " + mbi::test::quoted(cube()) + " --video " +
                          mbi::test::quoted(dir / "none.mp4") + " 2> " + mbi::test::quoted(dir / "err.txt");
  CHECK(std::system(cmd.c_str()) != 0);
  CHECK(mbi::test::slurp(dir / "err.txt").find("needs ffmpeg") != std::string::npos);
  CHECK_FALSE(fs::exists(dir / "none.mp4"));
}

TEST_CASE("mbi view --video: an ffmpeg that never reads its input is an error after 10 s, not a hang", "[viewer][xvfb]") {
  TempDir dir("view-video");
  fs::create_directory(dir / "bin");
  std::ofstream(dir / "bin" / "ffmpeg") << "#!/bin/sh\nexec sleep 300\n";  // holds its input open, reads nothing
  fs::permissions(dir / "bin" / "ffmpeg", fs::perms::owner_all);
  const mbi::test::ViewRun r = mbi::test::view(
      mbi::test::quoted(cube()) + " --width 640 --height 480 --no-panel --frames 3 --video " + mbi::test::quoted(dir / "v.mp4"), dir, true, {},
      "PATH=" + mbi::test::quoted(dir / "bin") + ":\"$PATH\" timeout 120");
  const std::string& err = r.err;
  INFO(err);
  CHECK(r.code == 2);  // timeout(1) would give 124
  CHECK(err.find("ffmpeg took no frame data for 10 s; no video written") != std::string::npos);
  CHECK_FALSE(fs::exists(dir / "v.mp4"));
  for (const auto& e : fs::directory_iterator(dir.path())) CHECK(e.path().filename().string().rfind(".mbi-tmp", 0) != 0);
}

TEST_CASE("viewer scripts: a drop's PATH is the rest of the line, spaces kept, comment and blanks cut", "[viewer][script]") {
  using namespace mbi::viewer;
  const std::deque<Event> events = parse_script("4 drop  /models/my cow.obj   # the cow\n", "s.txt");
  REQUIRE(events.size() == 1);
  CHECK(events[0].kind == Event::Drop);
  CHECK(events[0].path == "/models/my cow.obj");
  CHECK(format(events[0]) == "4 drop /models/my cow.obj");
  CHECK(parse_script(format(events[0]), "again.txt").front().path == events[0].path);
  CHECK_THROWS_WITH(parse_script("4 drop   # nothing\n", "s.txt"), "s.txt:1: 'drop' takes PATH");
}
