// The output-file machinery every command shares: short temporary names (any valid target name
// works), folder names refused as file names, write errors naming the user's file, folder locks
// (released when their process dies), scratch files, the signal-safe removal of temporaries,
// PC2 samples kept whole on a full disk; and the two format policies for deformed positions
// (PLY integer coordinates written as double, homogeneous 4OFF divided by w).
#include <mbi/io/atomic_file.hpp>
#include <mbi/io/folder_lock.hpp>
#include <mbi/io/io.hpp>
#include <mbi/io/scratch_file.hpp>

#include "common/temp_dir.hpp"

#include <catch2/catch.hpp>
#include <common/files.hpp>

#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using namespace mbi::io;
using mbi::test::TempDir;

namespace {

void write_bytes(const fs::path& p, const std::string& s) { std::ofstream(p, std::ios::binary) << s; }

int temporaries(const fs::path& dir) {
  int n = 0;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().filename().string().rfind(kTemporaryPrefix, 0) == 0) ++n;
  return n;
}

// A tetrahedron's surface, positions `scale` times the unit one.
SurfaceMesh tet_surface(double scale) {
  SurfaceMesh m;
  m.V.resize(4, 3);
  m.V << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  m.V *= scale;
  m.F.resize(4, 3);
  m.F << 0, 2, 1, 0, 1, 3, 1, 2, 3, 0, 3, 2;
  return m;
}

}  // namespace

TEST_CASE("temporary names are short: a 255-byte target name is written, nothing left behind",
          "[io][files]") {
  TempDir tmp("names");
  const std::string name = std::string(251, 'a') + ".obj";  // NAME_MAX: 255 bytes
  {
    AtomicFile f(tmp / name);
    CHECK(f.temporary().filename().string().size() < 48);
    CHECK(f.temporary().filename().string().find('a') == std::string::npos);
  }
  write_surface(tmp / name, tet_surface(1));
  CHECK(read_surface(tmp / name).V.rows() == 4);
  OutputSet out({}, /*force=*/true);
  const std::size_t i = out.add(tmp / name, "--out");
  const std::size_t j = out.add(tmp / (std::string(250, 's') + ".json"), "--stats");
  CHECK(out.staging(i).extension() == ".obj");  // writers pick the format by it
  out.write(i, [](const fs::path& p) { write_surface(p, tet_surface(2)); });
  out.write(j, [](const fs::path& p) { write_text_atomic(p, "{}\n"); });
  out.commit();
  CHECK(read_surface(tmp / name).V(1, 0) == 2.0);
  CHECK(temporaries(tmp.path()) == 0);
}

TEST_CASE("a folder's name is not a file name", "[io][files]") {
  TempDir tmp("folder-names");
  for (const fs::path& p : {tmp.path() / "", tmp / ".", tmp / "..", fs::path("sub/")}) {
    INFO(p);
    CHECK_THROWS_WITH(check_file_name(p, "--out"), Catch::Contains("--out") && Catch::Contains("names a folder"));
    OutputSet out({}, true);
    CHECK_THROWS_WITH(out.add(p, "--out"), Catch::Contains("names a folder"));
  }
  CHECK(tmp.entries() == 0);
}

TEST_CASE("a write error names the output, not its staging file", "[io][files]") {
  TempDir tmp("write-error");
  OutputSet out({}, true);
  const std::size_t i = out.add(tmp / "model.obj", "--out");
  try {
    out.write(i, [](const fs::path& p) { throw mbi::io::Error(p.string() + ": write error (No space left on device)"); });
    FAIL("no error");
  } catch (const mbi::io::Error& e) {
    const std::string what = e.what();
    CHECK(what == (tmp / "model.obj").string() + ": write error (No space left on device)");
    CHECK(what.find(kTemporaryPrefix) == std::string::npos);
  }
}

TEST_CASE("a folder lock is held by one at a time, names its holder, and goes with its process",
          "[io][files][lock]") {
  TempDir tmp("lock");
  {
    FolderLock first(tmp.path());
    CHECK(folder_lock_holder(tmp.path()).find("process " + std::to_string(::getpid())) == 0);
    CHECK_THROWS_WITH(FolderLock(tmp.path()), Catch::Contains("another process is writing into this folder") &&
                                                  Catch::Contains("process " + std::to_string(::getpid())));
  }
  CHECK_NOTHROW(FolderLock(tmp.path()));
  // a process holding it and killed: the kernel lets go, no stale lock
  int ready[2];
  REQUIRE(::pipe(ready) == 0);
  const pid_t pid = ::fork();
  REQUIRE(pid >= 0);
  if (pid == 0) {
    try {
      FolderLock held(tmp.path());
      [[maybe_unused]] const ssize_t n = ::write(ready[1], "x", 1);
      ::pause();
    } catch (...) {
    }
    ::_exit(1);
  }
  char c = 0;
  REQUIRE(::read(ready[0], &c, 1) == 1);
  CHECK_THROWS_WITH(FolderLock(tmp.path()), Catch::Contains("process " + std::to_string(pid)));
  ::kill(pid, SIGKILL);
  ::waitpid(pid, nullptr, 0);
  CHECK_NOTHROW(FolderLock(tmp.path()));
  ::close(ready[0]);
  ::close(ready[1]);
}

TEST_CASE("OutputSet refuses a folder another process holds, after a short wait", "[io][files][lock]") {
  TempDir tmp("lock-set");
  FolderLock run(tmp.path());  // as a run holds its folder
  OutputSet out({}, true);
  CHECK_THROWS_WITH(out.add(tmp / "c.node", "--out"),
                    Catch::StartsWith("--out " + (tmp / "c.node").string()) &&
                        Catch::Contains("another process is writing into this folder"));
  CHECK(tmp.entries() == 0);
}

TEST_CASE("a scratch file has no name, keeps what it was given, and takes back the last part",
          "[io][files]") {
  TempDir tmp("scratch");
  ScratchFile s(tmp.path(), "test");
  CHECK(tmp.entries() == 0);
  s.append("hello ", 6);
  const long mark = s.size();
  s.append("world", 5);
  char buf[5];
  s.read(mark, buf, 5);
  CHECK(std::string(buf, 5) == "world");
  s.truncate(mark);
  CHECK(s.size() == 6);
  CHECK_THROWS_AS(s.read(mark, buf, 5), mbi::io::Error);
}

TEST_CASE("remove_temporaries_now removes what this process is writing", "[io][files]") {
  TempDir tmp("signal");
  AtomicFile f(tmp / "a.obj");
  OutputSet out({}, true);
  out.add(tmp / "b.json", "--stats");
  f.write("partial");
  CHECK(temporaries(tmp.path()) == 2);
  remove_temporaries_now();
  CHECK(tmp.entries() == 0);
}

TEST_CASE("PC2 on a full disk: a sample is written whole or not at all", "[io][files][pc2]") {
  TempDir tmp("pc2-full");
  const fs::path file = tmp / "dense.pc2";
  // a child with a file size limit (a full disk): it appends until a write fails, then finishes
  const pid_t pid = ::fork();
  REQUIRE(pid >= 0);
  if (pid == 0) {
    ::signal(SIGXFSZ, SIG_IGN);  // the write fails with EFBIG instead of ending the process
    const rlimit lim{10000, 10000};
    ::setrlimit(RLIMIT_FSIZE, &lim);
    try {
      Pc2Writer w(file, 100);
      const Eigen::MatrixXd P = Eigen::MatrixXd::Constant(100, 3, 0.5);
      try {
        for (int s = 0; s < 100; ++s) w.append(P);
      } catch (const mbi::io::Error&) {
      }
      w.finish();
      ::_exit(w.samples());
    } catch (...) {
      ::_exit(255);
    }
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  REQUIRE(WIFEXITED(status));
  const int samples = WEXITSTATUS(status);
  CHECK(samples == (10000 - 32) / 1200);  // the samples that fit
  CHECK(read_pc2(file).frames.size() == static_cast<std::size_t>(samples));
  CHECK(temporaries(tmp.path()) == 0);
}

TEST_CASE("PLY integer positions take deformed positions as double, ASCII and binary",
          "[io][files][ply]") {
  TempDir tmp("ply-int");
  const std::string header_tail = "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
  for (const std::string& type : {std::string("int"), std::string("uchar"), std::string("short")})
    for (bool binary : {false, true}) {
      INFO(type << (binary ? " binary" : " ascii"));
      std::string ply = std::string("ply\nformat ") + (binary ? "binary_little_endian" : "ascii") +
                        " 1.0\nelement vertex 3\nproperty " + type + " x\nproperty " + type +
                        " y\nproperty " + type + " z\nproperty uchar red\n" + header_tail;
      const int P[3][3] = {{0, 0, 0}, {10, 0, 0}, {0, 10, 0}};
      for (const auto& p : P) {
        for (int c : p) {
          if (!binary) ply += std::to_string(c) + " ";
          else if (type == "uchar") ply += static_cast<char>(c);
          else if (type == "short") ply += std::string{static_cast<char>(c), 0};
          else ply += std::string{static_cast<char>(c), 0, 0, 0};
        }
        ply += binary ? std::string(1, '\x07') : std::string("7\n");
      }
      ply += binary ? std::string("\x03\0\0\0\0\x01\0\0\0\x02\0\0\0", 13) : std::string("3 0 1 2\n");
      write_bytes(tmp / "in.ply", ply);
      SurfaceMesh m = read_surface(tmp / "in.ply");
      m.V *= 1.37;  // deformed: not integers, some over 255
      m.V(1, 0) = 300.25;
      write_surface(tmp / "out.ply", m);
      const std::string out = mbi::test::slurp(tmp / "out.ply");
      CHECK(out.find("property double x\nproperty double y\nproperty double z\nproperty uchar red\n") !=
            std::string::npos);
      CHECK(out.find("property " + type + " x") == std::string::npos);
      const SurfaceMesh r = read_surface(tmp / "out.ply");
      CHECK(r.V == m.V);  // exactly: neither rounded nor clamped
    }
}

TEST_CASE("4OFF: each vertex is (x, y, z) / w", "[io][files][off]") {
  TempDir tmp("off4");
  write_bytes(tmp / "h.off", "4OFF\n4 4 0\n0 0 0 2\n2 0 0 2\n0 -3 0 -3\n0 0 0.25 0.25\n"
                             "3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n");
  CHECK(read_surface(tmp / "h.off").V == tet_surface(1).V);
  write_bytes(tmp / "w0.off", "4OFF\n1 0 0\n1 2 3 0\n");
  CHECK_THROWS_WITH(read_surface(tmp / "w0.off"), Catch::Contains("w0.off:3: vertex 0: w = 0"));
  write_bytes(tmp / "tiny.off", "4OFF\n1 0 0\n1e200 0 0 1e-200\n");
  CHECK_THROWS_AS(read_surface(tmp / "tiny.off"), mbi::io::Error);  // x / w overflows the limit
}

TEST_CASE("PC2 and MDD from floats on a full disk: the frames that fit are kept, the file readable", "[io][files][pc2]") {
  for (const std::string name : {"dense.pc2", "dense.mdd"}) {
    INFO(name);
    TempDir tmp("cache-full");
    const fs::path file = tmp / name;
    // a child with a file size limit (a full disk) appends float frames until a write fails
    const pid_t pid = ::fork();
    REQUIRE(pid >= 0);
    if (pid == 0) {
      ::signal(SIGXFSZ, SIG_IGN);
      const rlimit lim{10000, 10000};
      ::setrlimit(RLIMIT_FSIZE, &lim);
      try {
        const std::vector<float> xyz(300, 0.5f);
        auto fill = [&](auto& w) {
          try {
            for (int s = 0; s < 100; ++s) w.append(xyz.data());
          } catch (const mbi::io::Error&) {
          }
          w.finish();
          ::_exit(w.samples());
        };
        if (name == "dense.pc2") {
          Pc2Writer w(file, 100);
          fill(w);
        }
        MddWriter w(file, 100, std::vector<float>(100, 0.0f));
        fill(w);
      } catch (...) {
        ::_exit(255);
      }
    }
    int status = 0;
    ::waitpid(pid, &status, 0);
    REQUIRE(WIFEXITED(status));
    const int samples = WEXITSTATUS(status);
    CHECK(samples > 0);
    CHECK(samples < 100);
    const PointCache c = name == "dense.pc2" ? read_pc2(file) : read_mdd(file);
    CHECK(static_cast<int>(c.frames.size()) == samples);
    CHECK(temporaries(tmp.path()) == 0);
  }
}

TEST_CASE("glTF animation times must be finite and strictly increasing as float32", "[io][files][gltf]") {
  TempDir tmp("gltf-times");
  const SurfaceMesh m = tet_surface(1);
  GltfWriter w(tmp / "a.glb", m);
  w.append(0.0, m.V);
  CHECK_THROWS_WITH(w.append(1e300, m.V), Catch::Contains("frame 1: time 1e+300 s is not finite as float32"));
  CHECK_THROWS_WITH(w.append(1e-300, m.V), Catch::Contains("frame 1: time 1e-300 s is not after the previous frame's (0 s) as float32"));
  CHECK_THROWS_WITH(w.append(std::nan(""), m.V), Catch::Contains("is not finite"));
  w.append(1.0, m.V);
  CHECK_THROWS_WITH(w.append(1.0 + 1e-12, m.V), Catch::Contains("frame 2: time 1 s is not after"));
  w.finish();
  CHECK(w.samples() == 2);
}
