// Hardening of the readers (docs/hardening.md, mbi/io/parse.hpp): text variants that must work
// (byte-order mark, CR LF, lone CR, tabs, no final newline, very long lines), inputs that are not
// regular files, header counts checked before looping, coordinate limits, and a replay of the
// fuzz corpora (tests/fuzz/<target>/: seeds and every input a fuzzer crashed on) as regression
// tests: each must give a result or an mbi::io::Error naming the file, nothing else.
#include <mbi/io/atomic_file.hpp>
#include <mbi/io/io.hpp>
#include <mbi/io/parse.hpp>

#include <catch2/catch.hpp>

#include "common/files.hpp"
#include "common/temp_dir.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <string>

namespace fs = std::filesystem;
using namespace mbi::io;
using mbi::test::slurp;
using mbi::test::source_dir;
using mbi::test::TempDir;

namespace {

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const mbi::io::Error& e) {
    return e.what();
  }
  return "(no error)";
}

// Every line end of `s` ("\n") replaced by `eol`.
std::string with_eol(const std::string& s, const std::string& eol) {
  std::string out;
  for (char c : s) {
    if (c == '\n') out += eol;
    else out += c;
  }
  return out;
}

const std::string kBom = "\xEF\xBB\xBF";

// The text variants a reader must read exactly like the plain file: BOM, CR LF, lone CR, tabs
// for blanks, no final newline, and all of them at once.
std::vector<std::pair<std::string, std::string>> variants(const std::string& plain) {
  std::string tabs = plain;  // blanks after the first line (VTK's is a fixed text)
  for (std::size_t i = plain.find('\n'); i < tabs.size(); ++i)
    if (tabs[i] == ' ') tabs[i] = '\t';
  std::string no_final = plain;
  while (!no_final.empty() && no_final.back() == '\n') no_final.pop_back();
  std::string all = kBom + with_eol(tabs, "\r\n");
  while (all.size() >= 2 && all.compare(all.size() - 2, 2, "\r\n") == 0) all.resize(all.size() - 2);
  return {{"BOM", kBom + plain},         {"CRLF", with_eol(plain, "\r\n")},
          {"CR", with_eol(plain, "\r")}, {"tabs", tabs},
          {"no final newline", no_final}, {"BOM + CRLF + tabs + no final newline", all}};
}

const std::string kObj =
    "# a tetrahedron\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvn 0 0 1\n"
    "f 1//1 3//1 2//1\nf 1 2 4\nf 2 3 4\nf 1 4 3\n";
const std::string kOff = "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n";
const std::string kPly =
    "ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\nproperty double y\n"
    "property double z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n"
    "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n";
const std::string kStl =
    "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 0 1 0\nvertex 1 0 0\nendloop\n"
    "endfacet\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 0 1\n"
    "endloop\nendfacet\nendsolid t\n";
const std::string kPoints = "# points\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n";
const std::string kNode = "4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n";
const std::string kEle = "1 4 0\n0 0 1 2 3\n";
const std::string kMsh =
    "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n"
    "$EndNodes\n$Elements\n1\n1 4 2 0 1 1 2 3 4\n$EndElements\n";
const std::string kVtk =
    "# vtk DataFile Version 3.0\nt\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n0 0 0\n"
    "1 0 0\n0 1 0\n0 0 1\nCELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\n";

void same_surface(const SurfaceMesh& a, const SurfaceMesh& b) {
  REQUIRE(a.V == b.V);
  REQUIRE(a.F == b.F);
  REQUIRE(a.N.rows() == b.N.rows());
  if (a.N.size() > 0) REQUIRE(a.N.isApprox(b.N, 1e-15));
}

}  // namespace

TEST_CASE("text variants read exactly like the plain file, in every text format",
          "[io][hardening]") {
  struct Format {
    const char* name;
    std::string plain;
    std::function<void(const std::string&, const std::string&)> same;
  };
  auto surface = [](const char* file) {
    return [file](const std::string& a, const std::string& b) {
      same_surface(parse_surface(a, file), parse_surface(b, file));
    };
  };
  const std::vector<Format> formats = {
      {"OBJ", kObj, surface("t.obj")},
      {"OFF", kOff, surface("t.off")},
      {"PLY", kPly, surface("t.ply")},
      {"STL", kStl, surface("t.stl")},
      {"points", kPoints,
       [](const std::string& a, const std::string& b) {
         REQUIRE(parse_points(a, "t.txt") == parse_points(b, "t.txt"));
       }},
      {"TetGen", kNode + "#ele\n" + kEle,
       [](const std::string& a, const std::string& b) {
         auto split = [](const std::string& s) {
           const std::size_t cut = s.find("#ele");
           return std::pair{s.substr(0, cut), s.substr(cut + 4)};
         };
         const auto [na, ea] = split(a);
         const auto [nb, eb] = split(b);
         const ControlMesh ma = parse_tetgen(na, ea, "t"), mb = parse_tetgen(nb, eb, "t");
         REQUIRE(ma.U == mb.U);
         REQUIRE(ma.T == mb.T);
         REQUIRE(ma.T.rows() == 1);
       }},
      {"Gmsh", kMsh,
       [](const std::string& a, const std::string& b) {
         const ControlMesh ma = parse_gmsh(a, "t.msh"), mb = parse_gmsh(b, "t.msh");
         REQUIRE(ma.U == mb.U);
         REQUIRE(ma.T == mb.T);
       }},
      {"VTK", kVtk,
       [](const std::string& a, const std::string& b) {
         const ControlMesh ma = parse_vtk_mesh(a, "t.vtk"), mb = parse_vtk_mesh(b, "t.vtk");
         REQUIRE(ma.U == mb.U);
         REQUIRE(ma.T == mb.T);
       }},
  };
  for (const auto& f : formats)
    for (const auto& [what, text] : variants(f.plain)) {
      // PLY: the header is CR LF or LF (lone CR is not a PLY line end); Gmsh and VTK: a tab
      // inside a keyword line is a separator like a blank.
      if (std::string(f.name) == "PLY" && what == "CR") continue;
      INFO(f.name << ", " << what);
      f.same(f.plain, text);
    }
}

TEST_CASE("an OBJ with a byte-order mark keeps its first vertex (was dropped, faces shifted)",
          "[io][hardening]") {
  const SurfaceMesh plain = parse_surface(kObj, "t.obj");
  const SurfaceMesh bom = parse_surface(kBom + "v 0 0 0\n" + kObj.substr(kObj.find("v 1")), "t.obj");
  REQUIRE(bom.V.rows() == 4);
  same_surface(plain, bom);
  // and a first vertex that is bad is named as vertex 0 on line 1
  REQUIRE_THAT(error_of([] { parse_surface(kBom + "v nan 0 0\n", "b.obj"); }),
               Catch::StartsWith("b.obj:1: vertex 0 coordinate 0: non-finite"));
}

TEST_CASE("very long lines: a 4 MB comment, a 1 MB blank run, a face of 100,000 corners",
          "[io][hardening]") {
  const std::string comment = "#" + std::string(4 << 20, 'x') + "\n";
  same_surface(parse_surface(kObj, "t.obj"), parse_surface(comment + kObj, "t.obj"));
  REQUIRE(parse_points("0" + std::string(1 << 20, ' ') + "1 2\n", "p.txt").cols() == 3);
  std::string poly = "";
  const int k = 100000;
  for (int i = 0; i < k; ++i) poly += "v " + std::to_string(i) + " " + std::to_string(i % 7) + " 0\n";
  poly += "f";
  for (int i = 1; i <= k; ++i) poly += " " + std::to_string(i);
  const SurfaceMesh m = parse_surface(poly, "p.obj");
  REQUIRE(m.F.rows() == k - 2);
}

TEST_CASE("header counts: checked against the bytes that follow before looping", "[io][hardening]") {
  // 160 bytes declaring 2^31 - 1 items of an element without properties: refused at once
  // (it passed the size check as count x 0 bytes and looped for minutes)
  std::string ply =
      "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
      "property float z\nelement nothing 2147483647\nend_header\n";
  ply += std::string(12, '\0');
  ply.resize(160, '\0');
  const auto t0 = std::chrono::steady_clock::now();
  REQUIRE_THAT(error_of([&] { parse_surface(ply, "n.ply"); }),
               Catch::Contains("n.ply: header: element counts need at least 2147483659 bytes"));
  REQUIRE(std::chrono::steady_clock::now() - t0 < std::chrono::seconds(1));
  // PC2: 0 points x 2^31 - 1 samples (0 bytes each)
  std::string pc2 = std::string("POINTCACHE2", 11) + '\0';
  auto i32 = [&](std::int32_t x) { pc2.append(reinterpret_cast<const char*>(&x), 4); };
  auto f32 = [&](float x) { pc2.append(reinterpret_cast<const char*>(&x), 4); };
  i32(1), i32(0), f32(0), f32(1), i32(2147483647);
  REQUIRE_THAT(error_of([&] { parse_pc2(pc2, "z.pc2"); }),
               Catch::Contains("z.pc2: header says 2147483647 samples of 0 points"));
  // counts beyond kMaxCount or negative, in every text header
  REQUIRE_THAT(error_of([] { parse_surface("OFF\n2147483648 0 0\n", "c.off"); }),
               Catch::Contains("c.off:2: vertex count: 2147483648 out of range"));
  REQUIRE_THAT(error_of([] { parse_node("-1 3 0 0\n", "c.node"); }),
               Catch::Contains("c.node:1: header point count: -1 out of range"));
  REQUIRE_THAT(error_of([] { parse_gmsh("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n2147483647\n", "c.msh"); }),
               Catch::Contains("c.msh:5: header says 2147483647 nodes but only"));
}

TEST_CASE("ASCII Gmsh: naming lines costs nothing (200,000 nodes parse in linear time)",
          "[io][hardening]") {
  // Each number used to count the newlines from the start of the file: quadratic, minutes.
  const int n = 200000;
  std::string msh = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n" + std::to_string(n) + "\n";
  for (int i = 1; i <= n; ++i) msh += std::to_string(i) + " " + std::to_string(i % 10) + " 0 1\n";
  msh += "$EndNodes\n";
  const auto t0 = std::chrono::steady_clock::now();
  REQUIRE(parse_gmsh_nodes(msh, "big.msh").rows() == n);
  REQUIRE(std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60));  // ~0.1 s; quadratic was minutes
}

TEST_CASE("coordinates: NaN, inf, out of range and above 1e300 refused with file and line",
          "[io][hardening]") {
  for (const std::string bad : {"nan", "inf", "-inf", "1e308", "-1e301", "1e400"}) {
    INFO(bad);
    const std::string why = bad == "1e400" ? "number out of range" : bad.find('n') != std::string::npos ? "non-finite" : "larger in magnitude than 1e300";
    REQUIRE_THAT(error_of([&] { parse_surface("v 0 0 0\nv 0 " + bad + " 0\n", "c.obj"); }),
                 Catch::StartsWith("c.obj:2: vertex 1 coordinate 1: ") && Catch::Contains(why));
    REQUIRE_THAT(error_of([&] { parse_points("0 0\n" + bad + " 0\n", "c.txt"); }),
                 Catch::StartsWith("c.txt:2: point 1 coordinate 0: ") && Catch::Contains(why));
    REQUIRE_THAT(error_of([&] { parse_node("1 3 0 0\n0 0 0 " + bad + "\n", "c.node"); }),
                 Catch::StartsWith("c.node:2: point 0 coordinate 2: ") && Catch::Contains(why));
    REQUIRE_THAT(error_of([&] { parse_surface("OFF\n1 0 0\n" + bad + " 0 0\n", "c.off"); }),
                 Catch::StartsWith("c.off:3: vertex 0 coordinate 0: ") && Catch::Contains(why));
    REQUIRE_THAT(error_of([&] { parse_gmsh_nodes("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n1\n1 0 0 " + bad + "\n$EndNodes\n", "c.msh"); }),
                 Catch::StartsWith("c.msh:6: node 1"));
  }
  // 1e300 itself is accepted (the geometry code, not the reader, refuses what it cannot measure)
  REQUIRE(parse_points("1e300 -1e160\n", "ok.txt")(0, 0) == 1e300);
}

TEST_CASE("inputs that are not regular files are refused, naming what they are, without blocking",
          "[io][hardening]") {
  TempDir tmp("special");
  const fs::path fifo = tmp / "in.obj";
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);  // nobody writes: opening it blocking would hang
  const std::string is_fifo = "is a FIFO (named pipe), not a regular file";
  REQUIRE_THAT(error_of([&] { read_surface(fifo); }), Catch::Contains(fifo.string() + ": " + is_fifo));
  REQUIRE_THAT(error_of([&] { read_points(fifo); }), Catch::Contains(is_fifo));
  REQUIRE_THAT(error_of([&] { read_node(fifo); }), Catch::Contains(is_fifo));
  REQUIRE_THAT(error_of([&] { read_gmsh(fifo); }), Catch::Contains(is_fifo));
  REQUIRE_THAT(error_of([&] { read_vtk_points(fifo); }), Catch::Contains(is_fifo));
  REQUIRE_THAT(error_of([&] { read_pc2(fifo); }), Catch::Contains(is_fifo));
  REQUIRE_THAT(error_of([&] { read_png(fifo); }), Catch::Contains(is_fifo));
  const fs::path dir = tmp / "d.obj";
  fs::create_directories(dir);
  REQUIRE_THAT(error_of([&] { read_surface(dir); }), Catch::Contains("d.obj: is a directory, not a regular file"));
  REQUIRE_THAT(error_of([&] { read_points("/dev/zero"); }),
               Catch::Contains("/dev/zero: is a character device, not a regular file"));
  REQUIRE_THAT(error_of([&] { read_surface(tmp / "missing.obj"); }),
               Catch::Contains("missing.obj: cannot open for reading (No such file or directory)"));
}

TEST_CASE("PNG: only PNG reaches the decoder, sizes checked from the header", "[io][hardening]") {
  REQUIRE_THAT(error_of([] { parse_png("GIF89a....", "i.png"); }),
               Catch::Contains("i.png: not a PNG file (no PNG signature)"));
  // a valid signature and IHDR claiming 20000 x 8 pixels: a size stb_image itself accepts, so
  // only our check refuses it (before any pixel is decoded; stb does not check the IHDR CRC)
  std::string png = "\x89PNG\r\n\x1a\n";
  auto be32 = [&](std::uint32_t x) {
    for (int s = 24; s >= 0; s -= 8) png += static_cast<char>((x >> s) & 0xff);
  };
  be32(13);
  png += "IHDR";
  be32(20000), be32(8);
  png += std::string("\x08\x02\x00\x00\x00", 5);
  be32(0);
  REQUIRE_THAT(error_of([&] { parse_png(png, "big.png"); }),
               Catch::Contains("big.png: ") && Catch::Contains("at most 16384 x 16384"));
}

TEST_CASE("fuzz corpora replayed: every seed and every input a fuzzer found, result or mbi::io::Error",
          "[io][hardening][fuzz]") {
  // tests/fuzz/<target>/ holds the seeds and the inputs that crashed a reader before it was
  // fixed (crash-*, leak-*, timeout-*, oom-*): each is a regression test here.
  // a surface read is finite, positions and normals (the fuzz targets' invariant)
  const auto surface = [](const std::string& s, const char* name) {
    const mbi::io::SurfaceMesh m = parse_surface(s, name);
    REQUIRE(m.V.allFinite());
    REQUIRE(m.N.allFinite());
  };
  const std::map<std::string, std::function<void(const std::string&)>> targets = {
      {"obj", [&](const std::string& s) { surface(s, "fuzz.obj"); }},
      {"off", [&](const std::string& s) { surface(s, "fuzz.off"); }},
      {"ply", [&](const std::string& s) { surface(s, "fuzz.ply"); }},
      {"stl", [&](const std::string& s) { surface(s, "fuzz.stl"); }},
      {"points", [](const std::string& s) { parse_points(s, "fuzz.txt"); }},
      {"tetgen",
       [](const std::string& s) {
         const std::size_t cut = s.find("#ele");
         parse_node(s.substr(0, cut), "fuzz.node");
         parse_tetgen(s.substr(0, cut), cut == std::string::npos ? "" : s.substr(cut + 4), "fuzz");
       }},
      {"gmsh",
       [](const std::string& s) {
         parse_gmsh_nodes(s, "fuzz.msh");
         parse_gmsh(s, "fuzz.msh");
       }},
      {"vtk",
       [](const std::string& s) {
         parse_vtk_points(s, "fuzz.vtk");
         parse_vtk_mesh(s, "fuzz.vtk");
       }},
      {"pc2", [](const std::string& s) { parse_pc2(s, "fuzz.pc2"); }},
      {"png", [](const std::string& s) { parse_png(s, "fuzz.png"); }},
  };
  int files = 0, found = 0;
  for (const auto& [name, parse] : targets) {
    const fs::path dir = source_dir() / "tests" / "fuzz" / name;
    REQUIRE(fs::is_directory(dir));
    int seeds = 0;
    for (const auto& e : fs::directory_iterator(dir)) {
      const std::string f = e.path().filename().string();
      const bool regression = f.rfind("crash-", 0) == 0 || f.rfind("leak-", 0) == 0 ||
                              f.rfind("timeout-", 0) == 0 || f.rfind("oom-", 0) == 0;
      INFO(e.path());
      const std::string bytes = slurp(e.path());
      bool ok = true;
      try {
        parse(bytes);
      } catch (const mbi::io::Error& err) {
        ok = false;
        REQUIRE_THAT(err.what(), Catch::StartsWith("fuzz"));
      }
      ++files;
      if (regression) ++found;
      // seeds are valid files, except those named bad-* (slightly broken on purpose)
      if (!regression && f.rfind("bad-", 0) != 0) {
        REQUIRE(ok);
        ++seeds;
      }
    }
    INFO(name);
    REQUIRE(seeds >= 1);
  }
  INFO(files << " files, " << found << " inputs found by fuzzing");
  REQUIRE(files >= 40);
}

TEST_CASE("point lists: a long first line and many short ones allocate nothing large",
          "[io][hardening]") {
  // 200,000 numbers on the first line, then 200,000 lines of one: the matrix would be 320 GB
  std::string text;
  for (int i = 0; i < 200000; ++i) text += "1 ";
  text += "\n";
  for (int i = 0; i < 200000; ++i) text += "1\n";
  REQUIRE_THAT(error_of([&] { parse_points(text, "p.txt"); }),
               Catch::StartsWith("p.txt:2: point 1: 1 numbers, expected 200000 as on the first line"));
}

TEST_CASE("OutputSet: an output reserved but never written is not committed over its target",
          "[io][hardening]") {
  TempDir t("outputset");
  const fs::path a = t / "a.json", b = t / "b.json";
  {
    std::ofstream(b) << "the user's file\n";
    OutputSet out({}, /*force=*/true);
    const std::size_t ia = out.add(a, "--stats");
    out.add(b, "--vtk");
    write_text_atomic(out.staging(ia), "{}\n");
    REQUIRE_THAT(error_of([&] { out.commit(); }), Catch::Contains("b.json: was not written"));
  }
  CHECK(!fs::exists(a));                          // nothing renamed into place
  CHECK(slurp(b) == "the user's file\n");     // the target is untouched
  std::size_t left = 0;                           // and no staging file stays behind
  for (const auto& e : fs::directory_iterator(t.path())) left += e.path().filename() != "b.json";
  CHECK(left == 0);
  {
    OutputSet out({}, true);
    const std::size_t ia = out.add(a, "--stats"), ib = out.add(b, "--vtk");
    write_text_atomic(out.staging(ia), "{}\n");
    write_text_atomic(out.staging(ib), "[]\n");
    out.commit();
  }
  CHECK(slurp(a) == "{}\n");
  CHECK(slurp(b) == "[]\n");
}

TEST_CASE("numbers: one leading '+' is a sign, '+-1' and '++1' are not numbers", "[io][hardening]") {
  CHECK(parse_points("+1 -2 +3e0\n", "p.txt")(0, 0) == 1.0);
  CHECK(parse_points("+1 -2 +3e0\n", "p.txt")(0, 2) == 3.0);
  REQUIRE_THAT(error_of([] { parse_points("+-1 0 0\n", "p.txt"); }),
               Catch::Contains("p.txt") && Catch::Contains("not a number '+-1'"));
  REQUIRE_THAT(error_of([] { parse_points("++1 0 0\n", "p.txt"); }), Catch::Contains("not a number '++1'"));
  REQUIRE_THAT(error_of([] { parse_surface("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 +-3\n", "m.obj"); }),
               Catch::Contains("m.obj"));
}
