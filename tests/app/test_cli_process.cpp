// The process level through the mbi executable: two runs into one folder (the folder lock),
// SIGINT and SIGTERM during a run (outputs finished up to the last frame, exit 128 + signal) and a
// second signal (at once, no temporaries), a full disk (RLIMIT_FSIZE: the frame is taken back
// everywhere, errors name the user's files), and resident memory over 10,000 frames.
#include <catch2/catch.hpp>
#include <common/files.hpp>

#include <mbi/io/image.hpp>
#include <mbi/io/io.hpp>

#include <nlohmann/json.hpp>

#include "common/run_mbi.hpp"
#include "common/skip.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace fs = std::filesystem;
using mbi::test::slurp;
using mbi::test::TempDir;
using nlohmann::json;

namespace {

#if defined(__SANITIZE_ADDRESS__)
constexpr bool kSanitized = true;
#else
constexpr bool kSanitized = false;
#endif

void write(const fs::path& p, const std::string& text) { std::ofstream(p) << text; }

// An octahedron (6 vertices) inside the box control mesh of `scene`.
void octahedron_obj(const fs::path& p) {
  write(p, "v 0.5 0.5 0.2\nv 0.5 0.5 2.8\nv 0.1 0.5 1.5\nv 0.9 0.5 1.5\nv 0.5 0.1 1.5\nv 0.5 0.9 1.5\n"
           "f 1 5 3\nf 1 4 5\nf 1 6 4\nf 1 3 6\nf 2 3 5\nf 2 5 4\nf 2 4 6\nf 2 6 3\n");
}

// A small box surface (8 vertices) inside the box control mesh of `scene`.
void small_obj(const fs::path& p) {
  write(p, "v 0.05 0.05 0.05\nv 0.05 0.05 2.95\nv 0.05 0.95 0.05\nv 0.05 0.95 2.95\n"
           "v 0.95 0.05 0.05\nv 0.95 0.05 2.95\nv 0.95 0.95 0.05\nv 0.95 0.95 2.95\n"
           "f 1 2 4\nf 1 4 3\nf 5 7 8\nf 5 8 6\nf 1 5 6\nf 1 6 2\nf 3 4 8\nf 3 8 7\n"
           "f 1 3 7\nf 1 7 5\nf 2 6 8\nf 2 8 4\n");
}

// A drag scene (box control mesh of 63 vertices, no physics) of the model file `dense`: cheap
// frames, also under the sanitizers.
std::string scene(const std::string& name, const std::string& dense, const std::string& output) {
  return "name = \"" + name + "\"\nmode = \"drag\"\n[dense]\npath = \"" + dense + "\"\n" +
         "[control]\nbuiltin = \"box\"\ncells = [2, 2, 6]\n"
         "[[drags]]\nselect = { box_relative = { min = [0, 0, 0], max = [1, 1, 0] } }\nkeys = [[0, 0, 0, 0]]\n"
         "[[drags]]\nselect = { box_relative = { min = [0.5, 0, 1], max = [1, 1, 1] } }\n"
         "keys = [[0, 0, 0, 0], [100, 0.4, 0.3, 0.0]]\n"
         "[interpolation]\nalpha = 0.1\ngpu = \"off\"\n[output]\n" + output;
}

struct Spawned {
  pid_t pid = -1;
  fs::path err;
};

// Starts `mbi args...` in `dir` (stderr to a file there), with a file size limit when given
// (a full disk: writes past it fail with EFBIG).
Spawned spawn(const TempDir& dir, const std::vector<std::string>& args, const std::string& tag,
              std::optional<rlim_t> file_size = std::nullopt) {
  Spawned s;
  s.err = dir / (tag + ".err");
  s.pid = ::fork();
  REQUIRE(s.pid >= 0);
  if (s.pid == 0) {
    if (::chdir(dir.path().c_str()) != 0) ::_exit(127);
    const int fd = ::open(s.err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int null = ::open("/dev/null", O_WRONLY);
    if (fd < 0 || null < 0 || ::dup2(fd, 2) < 0 || ::dup2(null, 1) < 0) ::_exit(126);
    if (file_size) {
      ::signal(SIGXFSZ, SIG_IGN);
      const rlimit lim{*file_size, *file_size};
      ::setrlimit(RLIMIT_FSIZE, &lim);
    }
    std::vector<char*> argv{const_cast<char*>(MBI_EXE)};
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(MBI_EXE, argv.data());
    ::_exit(127);
  }
  return s;
}

// The exit code of a spawned mbi (-1 when a signal ended it).
int wait_for(const Spawned& s) {
  int status = 0;
  ::waitpid(s.pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// Waits up to 60 s for `p` to exist.
bool appears(const fs::path& p) {
  const auto t0 = std::chrono::steady_clock::now();
  while (!fs::exists(p)) {
    if (std::chrono::steady_clock::now() - t0 > std::chrono::seconds(60)) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return true;
}

json metrics(const fs::path& dir) { return json::parse(slurp(dir / "metrics.json")); }

}  // namespace

TEST_CASE("two runs into one folder at once: one writes it, the other is refused at once naming it",
          "[cli][process][lock]") {
  TempDir dir("lock");
  small_obj(dir / "small.obj");
  octahedron_obj(dir / "octahedron.obj");
  write(dir / "a.toml", scene("a", "small.obj", "every = 100000\nimage = false\n"));
  write(dir / "b.toml", scene("b", "octahedron.obj", "every = 100000\nimage = false\n"));
  const std::string frames = kSanitized ? "30" : "300";
  for (int attempt = 0; attempt < 2; ++attempt) {
    fs::remove_all(dir / "o");
    // started together: the second starts within milliseconds, the first holds the folder for
    // its whole run (loading included, about half a second)
    const std::vector<std::string> common{"--frames", frames, "--out", "o", "--quiet", "--force"};
    std::vector<std::string> a{"run", "a.toml"}, b{"run", "b.toml"};
    a.insert(a.end(), common.begin(), common.end());
    b.insert(b.end(), common.begin(), common.end());
    const Spawned ra = spawn(dir, a, "a"), rb = spawn(dir, b, "b");
    const int ca = wait_for(ra), cb = wait_for(rb);
    INFO(slurp(ra.err) << slurp(rb.err));
    REQUIRE(((ca == 0 && cb == 2) || (ca == 2 && cb == 0)));
    const Spawned& lost = ca == 2 ? ra : rb;
    const Spawned& won = ca == 2 ? rb : ra;
    CHECK_THAT(slurp(lost.err), Catch::StartsWith("mbi run: error: o: another process is writing into this folder") &&
                                    Catch::Contains("process " + std::to_string(won.pid) + ": ") &&
                                    Catch::Contains(" run " + std::string(ca == 2 ? "b" : "a") + ".toml"));
    // the folder holds the winner's run alone
    const json j = metrics(dir / "o");
    CHECK(j["scene"] == (ca == 2 ? "b" : "a"));
    CHECK(j["frames"].size() == std::stoul(frames) + 1);
    const Eigen::Index rows = ca == 2 ? 6 : 8;
    CHECK(mbi::io::read_surface(dir / "o" / "mesh_0000.obj").V.rows() == rows);
    CHECK(mbi::io::read_pc2(dir / "o" / "dense.pc2").frames.front().rows() == rows);
  }
}

TEST_CASE("SIGINT or SIGTERM during a run: the next frame is the last, every output finished",
          "[cli][process][signal]") {
  TempDir dir("signal");
  small_obj(dir / "small.obj");
  write(dir / "s.toml", scene("s", "small.obj", "every = 5\nimage = false\n"));
  for (const int sig : {SIGINT, SIGTERM}) {
    const std::string name = sig == SIGINT ? "SIGINT" : "SIGTERM";
    INFO(name);
    const fs::path o = dir / name;
    const Spawned r = spawn(dir, {"run", "s.toml", "--frames", "1000000", "--out", name, "--quiet"}, name);
    REQUIRE(appears(o / "mesh_0010.obj"));
    ::kill(r.pid, sig);
    CHECK(wait_for(r) == 128 + sig);
    const std::string err = slurp(r.err);
    INFO(err);
    const json j = metrics(o);
    const int last = j["frames_completed"];
    CHECK(last > 10);
    CHECK_THAT(err, Catch::Contains("mbi run: interrupted by " + name + " after frame " + std::to_string(last)));
    CHECK(j["interrupted"] == name);
    CHECK(j["failure"].is_null());
    CHECK(j["frames"].size() == static_cast<std::size_t>(last + 1));
    CHECK(mbi::io::read_pc2(o / "dense.pc2").frames.size() == static_cast<std::size_t>(last + 1));
    CHECK(mbi::io::read_surface(mbi::io::frame_path(o / "mesh", last, ".obj")).V.rows() == 8);
    CHECK(fs::exists(mbi::io::frame_path(o / "control", last, ".vtk")));
    CHECK(mbi::test::temporaries(o) == 0);
  }
}

TEST_CASE("a second signal ends the run at once: no temporaries, no partial file under a final name",
          "[cli][process][signal]") {
  TempDir dir("signal2");
  small_obj(dir / "small.obj");
  // 3D pictures of every frame: drawn after the last frame, which takes long enough to interrupt
  write(dir / "s.toml", scene("s", "small.obj", "every = 1\n"));
  const fs::path o = dir / "o";
  const Spawned r = spawn(dir, {"run", "s.toml", "--frames", "1000000", "--out", "o", "--quiet"}, "s");
  REQUIRE(appears(o / "mesh_0020.obj"));
  ::kill(r.pid, SIGINT);
  REQUIRE(appears(o / "frame_0000.png"));  // finishing: drawing the pictures
  ::kill(r.pid, SIGINT);
  CHECK(wait_for(r) == 130);
  CHECK(mbi::test::temporaries(o) == 0);
  CHECK_FALSE(fs::exists(o / "metrics.json"));  // not reached
  for (const auto& e : fs::directory_iterator(o)) {
    const std::string name = e.path().filename().string();
    INFO(name);
    if (name.rfind("frame_", 0) == 0) CHECK(mbi::io::read_png(e.path()).width > 0);  // complete
    if (name.rfind("mesh_", 0) == 0) CHECK(mbi::io::read_surface(e.path()).V.rows() == 8);
  }
}

TEST_CASE("a full disk fails the frame everywhere: dense.pc2 and metrics.json list the same frames",
          "[cli][process][full]") {
  TempDir dir("full");
  small_obj(dir / "small.obj");
  write(dir / "s.toml", scene("s", "small.obj", "every = 1\nimage = false\n"));
  // control_NNNN.vtk (about 9.5 kB) is the first file over the limit: frame 0 cannot be written
  const Spawned r = spawn(dir, {"run", "s.toml", "--frames", "5", "--out", "o", "--quiet"}, "s", 9000);
  CHECK(wait_for(r) == 3);
  const std::string err = slurp(r.err);
  INFO(err);
  CHECK_THAT(err, Catch::Contains("frame 0: ") && Catch::Contains("control_0000.vtk: write error (File too large)"));
  CHECK(err.find(".mbi-tmp") == std::string::npos);
  const json j = metrics(dir / "o");
  CHECK(j["frames"].empty());
  CHECK(mbi::io::read_pc2(dir / "o" / "dense.pc2").frames.empty());
  CHECK_FALSE(fs::exists(dir / "o" / "mesh_0000.obj"));  // the frame's other files are taken back
  CHECK(mbi::test::temporaries(dir / "o") == 0);
}

TEST_CASE("deform and cage on a full disk: the error names --out's file, nothing is left",
          "[cli][process][full]") {
  TempDir dir("full-out");
  small_obj(dir / "small.obj");
  const Spawned d = spawn(dir, {"deform", "--example", "twist-bar", "--out", "bar.obj"}, "d", 100000);
  CHECK(wait_for(d) == 2);
  CHECK_THAT(slurp(d.err), Catch::StartsWith("mbi deform: error: bar.obj: write error (File too large)"));
  const Spawned c = spawn(dir, {"cage", "small.obj", "-n", "200", "--out", "cage"}, "c", 1000);
  CHECK(wait_for(c) == 2);
  CHECK_THAT(slurp(c.err), Catch::StartsWith("mbi cage: error: cage.node: write error (File too large)"));
  std::vector<std::string> left;
  for (const auto& e : fs::directory_iterator(dir.path())) left.push_back(e.path().filename().string());
  std::sort(left.begin(), left.end());
  CHECK(left == std::vector<std::string>{"c.err", "d.err", "small.obj"});
}

TEST_CASE("soak: resident memory of mbi run at frame 10,000 is within 10 MB of frame 100",
          "[cli][process][soak]") {
  if (kSanitized) mbi::test::skip("ASan's quarantine keeps freed memory resident");
  TempDir dir("soak");
  small_obj(dir / "small.obj");
  write(dir / "s.toml", scene("soak", "small.obj", "every = 1000\nimage = false\n"));
  const Spawned r = spawn(dir, {"run", "s.toml", "--frames", "10000", "--out", "o", "--quiet"}, "s");
  REQUIRE(wait_for(r) == 0);
  const json j = metrics(dir / "o");
  REQUIRE(j["frames"].size() == 10001);
  const long at100 = j["frames"][100]["rss_kb"], at10000 = j["frames"][10000]["rss_kb"];
  std::printf("soak: resident memory %ld kB at frame 100, %ld kB at frame 10000\n", at100, at10000);
  CHECK(at100 > 0);
  CHECK(at10000 - at100 <= 10 * 1024);
}

TEST_CASE("3D pictures: the stored frames do not grow resident memory, all are drawn alike",
          "[cli][process][soak]") {
  if (kSanitized) mbi::test::skip("ASan's quarantine keeps freed memory resident");
  TempDir dir("pictures");
  small_obj(dir / "small.obj");
  write(dir / "s.toml", scene("p", "small.obj", "every = 1\n"));
  const Spawned r = spawn(dir, {"run", "s.toml", "--frames", "60", "--out", "o", "--quiet"}, "s");
  REQUIRE(wait_for(r) == 0);
  const json j = metrics(dir / "o");
  // each frame stores 2 panels x 144 tetrahedra x 10 points x 3 doubles (69 kB): 4 MB over 60
  const long at5 = j["frames"][5]["rss_kb"], at60 = j["frames"][60]["rss_kb"];
  CHECK(at60 - at5 < 1024);
  const mbi::io::Image first = mbi::io::read_png(dir / "o" / "frame_0000.png");
  const mbi::io::Image last = mbi::io::read_png(dir / "o" / "frame_0060.png");
  CHECK((first.width == last.width && first.height == last.height));
}
