// One output and signal policy over a whole `mbi deform` sequence, from main to the last rename:
// a signal at each stage (loading, precompute, frames, finishing; MBI_TEST_SIGNAL_AT raises it
// there) leaves the finished outputs or none, never a temporary; a full disk keeps the frames
// written and names the user's file; outputs are the same bytes for the same inputs; every
// output is checked before any work; the small option checks (--fps, --threads).
#include <catch2/catch.hpp>
#include <common/files.hpp>

#include <mbi/io/io.hpp>

#include <nlohmann/json.hpp>

#include "common/run_mbi.hpp"
#include "common/skip.hpp"

#include <csignal>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>

namespace fs = std::filesystem;
using mbi::test::q;
using mbi::test::run_mbi;
using mbi::test::slurp;
using mbi::test::TempDir;

namespace {

fs::path vtu_data(const std::string& name) { return mbi::test::source_dir() / "tests" / "data" / "vtu" / name; }

// twist.pc2: 3 frames of box.node's 27 nodes; sphere.obj: 144 vertices inside
std::string deform_outs(const fs::path& deformed, const std::string& outs, const std::string& more = "") {
  return "deform --control " + q(vtu_data("box.node")) + " --mesh " + q(vtu_data("sphere.obj")) + " --deformed " + q(deformed) +
         " --out " + outs + " " + more;
}

// The JSON chunk of a .glb.
nlohmann::json glb_json(const fs::path& file) {
  const std::string b = slurp(file);
  REQUIRE(b.size() > 20);
  std::uint32_t n = 0;
  std::memcpy(&n, b.data() + 12, 4);
  return nlohmann::json::parse(b.substr(20, n));
}

// The frames an output of `kind` holds (-1: none there).
int frames_in(const fs::path& dir, const std::string& kind) {
  if (kind == "o.pc2") return fs::exists(dir / kind) ? static_cast<int>(mbi::io::read_pc2(dir / kind).frames.size()) : -1;
  if (kind == "o.mdd") return fs::exists(dir / kind) ? static_cast<int>(mbi::io::read_mdd(dir / kind).frames.size()) : -1;
  if (kind == "o.glb") return fs::exists(dir / kind) ? static_cast<int>(glb_json(dir / kind)["nodes"].size()) - 1 : -1;
  int k = 0;
  while (fs::exists(dir / ("n_" + std::to_string(k) + ".obj"))) ++k;
  return k == 0 ? -1 : k;
}

}  // namespace

TEST_CASE("lifetime: a signal at every stage of a sequence leaves the finished outputs or none", "[app][sequence][signal]") {
  for (const std::string kind : {"o.pc2", "o.mdd", "o.glb", "n_%d.obj"}) {
    for (const std::string stage : {"load", "precompute", "frame", "finish", "frame:TERM"}) {
      INFO(kind << " at " << stage);
      TempDir dir("life");
      const fs::path out = dir / "out";
      fs::create_directory(out);
      const auto r = run_mbi(deform_outs(vtu_data("twist.pc2"), q(out / kind), "--stats " + q(out / "s.json")), dir,
                             "MBI_TEST_SIGNAL_AT=" + stage);
      INFO(r.err);
      CHECK(r.code == 128 + (stage == "frame:TERM" ? SIGTERM : SIGINT));
      CHECK(mbi::test::temporaries(out) == 0);
      if (stage == "load" || stage == "precompute") {
        CHECK(fs::is_empty(out));  // exits at once: nothing written
      } else if (stage == "finish") {
        CHECK(frames_in(out, kind) == 3);  // every frame computed: finished, not dropped
        CHECK_THAT(r.err, Catch::Contains("interrupted by SIGINT (outputs up to frame 2 kept: every frame was done"));
        CHECK_THAT(slurp(out / "s.json"), Catch::Contains("\"frames\": 3") && Catch::Contains("\"interrupted_by_signal\": 2"));
      } else {
        CHECK(frames_in(out, kind) == 2);  // raised during frame 1: that frame is the last
        CHECK_THAT(r.err, Catch::Contains("(outputs up to frame 1 kept)"));
        CHECK_THAT(slurp(out / "s.json"), Catch::Contains("\"frames\": 2"));
      }
    }
  }
}

TEST_CASE("lifetime: a signal at every stage of one pose leaves the finished output or none", "[app][sequence][signal]") {
  // one pose is a trajectory of one frame: a signal during its frame lets that frame finish
  for (const std::string stage : {"load", "precompute", "frame", "finish", "frame:TERM"}) {
    INFO(stage);
    TempDir dir("life");
    const fs::path out = dir / "out";
    fs::create_directory(out);
    const auto r = run_mbi(deform_outs(vtu_data("twist_0001.txt"), q(out / "o.obj"), "--stats " + q(out / "s.json")), dir,
                           "MBI_TEST_SIGNAL_AT=" + stage);
    INFO(r.err);
    CHECK(r.code == 128 + (stage == "frame:TERM" ? SIGTERM : SIGINT));
    CHECK(mbi::test::temporaries(out) == 0);
    if (stage == "load" || stage == "precompute") {
      CHECK(fs::is_empty(out));  // exits at once: nothing written
      continue;
    }
    CHECK(mbi::io::read_surface(out / "o.obj").V.rows() == 144);  // complete
    CHECK_THAT(r.err, Catch::Contains("(outputs up to frame 0 kept: every frame was done, the outputs are finished)"));
    const nlohmann::json j = nlohmann::json::parse(slurp(out / "s.json"));
    CHECK(j["frames"] == 1);
    CHECK(j["interrupted_by_signal"] == (stage == "frame:TERM" ? SIGTERM : SIGINT));
  }
}

TEST_CASE("lifetime: two identical runs into x.glb give identical bytes, the root node named x", "[app][sequence]") {
  TempDir dir("life");
  fs::create_directory(dir / "a");
  fs::create_directory(dir / "b");
  for (const std::string sub : {"a", "b"}) {
    REQUIRE(run_mbi(deform_outs(vtu_data("twist.pc2"), q(dir / sub / "x.glb")), dir).code == 0);  // an animation
    REQUIRE(run_mbi(deform_outs(vtu_data("twist_0001.txt"), q(dir / sub / "y.glb")), dir).code == 0);  // one pose
  }
  for (const std::string name : {"x.glb", "y.glb"}) {
    INFO(name);
    CHECK(slurp(dir / "a" / name) == slurp(dir / "b" / name));
    const nlohmann::json j = glb_json(dir / "a" / name);
    CHECK(j["nodes"][0]["name"] == fs::path(name).stem().string());
    CHECK(j.dump().find(".mbi-tmp") == std::string::npos);
  }
}

TEST_CASE("lifetime: a full disk keeps the frames written and names the user's file", "[app][sequence]") {
  // 144 points: 1,728 bytes a frame; a 4 KiB limit holds the header and 2 frames of a cache
  for (const std::string kind : {"o.pc2", "o.mdd", "n_%d.obj"}) {
    INFO(kind);
    TempDir dir("life");
    const std::string cmd = "cd " + q(dir.path()) + " && sh -c 'ulimit -f 8; exec \"$0\" \"$@\"' " + q(MBI_EXE) + " " +
                            deform_outs(vtu_data("twist.pc2"), q(kind)) + " > out.txt 2> err.txt";
    const int status = std::system(cmd.c_str());
    const std::string err = slurp(dir / "err.txt");
    INFO(err);
    CHECK(WEXITSTATUS(status) == (kind == "n_%d.obj" ? 2 : 3));
    CHECK_THAT(err, Catch::Contains("write error (File too large)"));
    CHECK(err.find(".mbi-tmp") == std::string::npos);
    CHECK(mbi::test::temporaries(dir.path()) == 0);
    if (kind != "n_%d.obj") {
      CHECK_THAT(err, Catch::Contains("frame 2: " + kind + ": write error") && Catch::Contains("(outputs up to frame 1 kept)"));
      CHECK(frames_in(dir.path(), kind) == 2);
    }
  }
}

TEST_CASE("lifetime: every output is checked before any work, together", "[app][sequence]") {
  TempDir dir("life");
  fs::copy(vtu_data("sphere.obj"), dir / "s2.obj");
  const std::string two = "deform --control " + q(vtu_data("box.node")) + " --mesh " + q(vtu_data("sphere.obj")) + " --mesh " +
                          q(dir / "s2.obj") + " --deformed " + q(vtu_data("twist.pc2"));
  // two series that expand to the same names
  auto r = run_mbi(two + " --out " + q(dir / "z_%d.obj") + " --out " + q(dir / "z_%01d.obj"), dir);
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("z_0.obj: is also another output of this command"));
  CHECK(!fs::exists(dir / "z_0.obj"));
  // an animated glTF that is one of a series' frames
  r = run_mbi(two + " --out " + q(dir / "q_%d.glb") + " --out " + q(dir / "q_1.glb"), dir);
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("q_1.glb: is also another output of this command"));
  // a glob that matches a folder: refused before any work
  fs::create_directory(dir / "g");
  for (int k = 0; k < 3; ++k) fs::copy(vtu_data("twist_000" + std::to_string(k) + ".txt"), dir / "g" / ("t_" + std::to_string(k) + ".txt"));
  fs::create_directory(dir / "g" / "t_3.txt");
  r = run_mbi(deform_outs(dir / "g" / "t_*.txt", q(dir / "g.pc2")), dir);
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("t_3.txt: frame 3 of") && Catch::Contains("is a folder"));
  CHECK(!fs::exists(dir / "g.pc2"));
  // a '%' that is no printf pattern is part of a plain name
  r = run_mbi(deform_outs(vtu_data("twist_0001.txt"), q(dir / "100%.obj")), dir);
  INFO(r.err);
  CHECK(r.code == 0);
  CHECK(mbi::io::read_surface(dir / "100%.obj").V.rows() == 144);
  CHECK(mbi::test::temporaries(dir.path()) == 0);
}

TEST_CASE("lifetime: --fps and --threads take what they can use, saying the range readably", "[app][sequence]") {
  TempDir dir("life");
  for (const std::string fps : {"1e-300", "1e308"}) {
    INFO(fps);
    const auto r = run_mbi(deform_outs(vtu_data("twist.pc2"), q(dir / "x.glb"), "--fps " + fps), dir);
    CHECK(r.code == 2);
    CHECK_THAT(r.err, Catch::Contains("not finite and increasing as float32; give a rate from 5.88e-39 to 8.51e+37"));
    CHECK(!fs::exists(dir / "x.glb"));
  }
  auto r = run_mbi(deform_outs(vtu_data("twist.pc2"), q(dir / "x.glb"), "--fps 1e400"), dir);
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("--fps 1e400: give a number of frames per second > 0"));
  CHECK(r.err.size() < 200);
  r = run_mbi(deform_outs(vtu_data("twist.pc2"), q(dir / "x.pc2"), "--threads 0x10"), dir);
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("--threads 0x10: give a whole number of threads in decimal digits"));
}

TEST_CASE("lifetime: a 2^31-frame PC2 is streamed under a 1 GiB memory limit", "[app][sequence]") {
#if defined(__SANITIZE_ADDRESS__)
  mbi::test::skip("AddressSanitizer reserves more address space than the limit");
#endif
  TempDir dir("life");
  // header: 27 points, 2^31 - 1 samples; the file really is that long (sparse: no disk used)
  const std::int32_t points = 27, samples = 0x7fffffff;
  std::string h("POINTCACHE2\0", 12);
  const std::int32_t version = 1;
  const float start = 0, rate = 1;
  h.append(reinterpret_cast<const char*>(&version), 4).append(reinterpret_cast<const char*>(&points), 4);
  h.append(reinterpret_cast<const char*>(&start), 4).append(reinterpret_cast<const char*>(&rate), 4);
  h.append(reinterpret_cast<const char*>(&samples), 4);
  std::ofstream(dir / "huge.pc2", std::ios::binary) << h;
  std::error_code ec;
  fs::resize_file(dir / "huge.pc2", 32 + 12ull * points * samples, ec);
  if (ec) mbi::test::skip("this file system holds no sparse file of 695 GB");
  const std::string cmd = "cd " + q(dir.path()) + " && MBI_TEST_SIGNAL_AT=frame sh -c 'ulimit -v 1048576; exec \"$0\" \"$@\"' " +
                          q(MBI_EXE) + " " + deform_outs("huge.pc2", "o.pc2") + " > out.txt 2> err.txt";
  const int status = std::system(cmd.c_str());
  const std::string err = slurp(dir / "err.txt");
  INFO(err);
  CHECK(WEXITSTATUS(status) == 128 + SIGINT);  // stopped after frame 1, as asked
  CHECK(mbi::io::read_pc2(dir / "o.pc2").frames.size() == 2);
  // an MDD output needs every frame's time: refused before any work, naming the limit
  const std::string mdd = "cd " + q(dir.path()) + " && sh -c 'ulimit -v 1048576; exec \"$0\" \"$@\"' " + q(MBI_EXE) + " " +
                          deform_outs("huge.pc2", "o.mdd") + " > out.txt 2> err.txt";
  CHECK(WEXITSTATUS(std::system(mdd.c_str())) == 2);
  CHECK_THAT(slurp(dir / "err.txt"), Catch::Contains("--out o.mdd: 2147483647 frames of huge.pc2 are more than the 16777216"));
  CHECK(!fs::exists(dir / "o.mdd"));
  // an MDD of as many frames: its 8 GB of times are not read whole, the limit is named
  const char mdd_head[8] = {0x7f, -1, -1, -1, 0, 0, 0, 27};  // big endian: 2^31 - 1 frames of 27 points
  std::ofstream(dir / "huge.mdd", std::ios::binary).write(mdd_head, 8);
  fs::resize_file(dir / "huge.mdd", 8 + (4 + 12ull * points) * samples, ec);
  REQUIRE(!ec);
  const std::string from_mdd = "cd " + q(dir.path()) + " && sh -c 'ulimit -v 1048576; exec \"$0\" \"$@\"' " + q(MBI_EXE) + " " +
                               deform_outs("huge.mdd", "m.pc2") + " > out.txt 2> err.txt";
  CHECK(WEXITSTATUS(std::system(from_mdd.c_str())) == 2);
  CHECK_THAT(slurp(dir / "err.txt"), Catch::Contains("2147483647 frames of huge.mdd are more than the 16777216"));
  CHECK(!fs::exists(dir / "m.pc2"));
}

TEST_CASE("lifetime: a zlib .vtu within the inflation bound but past the memory limit is an error naming it", "[app][sequence]") {
#if defined(__SANITIZE_ADDRESS__)
  mbi::test::skip("AddressSanitizer reserves more address space than the limit");
#endif
  TempDir dir("life");
  // 40 million float32 points of zeros: 480 MB inflated from 0.7 MB, 655 times (the bound: 1100)
  const std::string py = R"(
import struct, sys, zlib
n = 40_000_000; block = 32768; total = 12 * n
blocks = [zlib.compress(bytes(block))] * (total // block) + [zlib.compress(bytes(total % block))]
head = struct.pack('<III', len(blocks), block, total % block) + b''.join(struct.pack('<I', len(b)) for b in blocks)
xml = ('<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian" header_type="UInt32" '
       'compressor="vtkZLibDataCompressor"><UnstructuredGrid><Piece NumberOfPoints="%d" NumberOfCells="0"><Points>'
       '<DataArray type="Float32" NumberOfComponents="3" format="appended" offset="0"/></Points></Piece>'
       '</UnstructuredGrid><AppendedData encoding="raw">_' % n).encode()
open(sys.argv[1], 'wb').write(xml + head + b''.join(blocks) + b'</AppendedData></VTKFile>')
)";
  std::ofstream(dir / "make.py") << py;
  REQUIRE(std::system(("/usr/bin/python3 " + q(dir / "make.py") + " " + q(dir / "big.vtu")).c_str()) == 0);
  const std::string cmd = "cd " + q(dir.path()) + " && sh -c 'ulimit -v 786432; exec \"$0\" \"$@\"' " + q(MBI_EXE) + " " +
                          deform_outs("big.vtu", "o.obj") + " > out.txt 2> err.txt";
  const int status = std::system(cmd.c_str());
  const std::string err = slurp(dir / "err.txt");
  INFO(err);
  CHECK(WEXITSTATUS(status) == 2);
  CHECK_THAT(err, Catch::Contains("big.vtu: not enough memory for its arrays"));
  CHECK(err.find("bad_alloc") == std::string::npos);
  CHECK(!fs::exists(dir / "o.obj"));
}
