// `mbi cage`: output files, statistics, determinism and error reporting of the subcommand.
#include <mbi/interp/embed.hpp>
#include <mbi/io/io.hpp>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "common/files.hpp"
#include "common/temp_dir.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

namespace fs = std::filesystem;
using namespace mbi::io;
using mbi::test::slurp;
using mbi::test::TempDir;

namespace {

/// Runs `mbi <args>` with stderr captured to `err`; returns the exit code.
int run(const std::string& args, const fs::path& err) {
  const std::string cmd = std::string("\"") + MBI_EXE + "\" " + args + " 2> \"" + err.string() +
                          "\" > /dev/null";
  const int status = std::system(cmd.c_str());
  REQUIRE(WIFEXITED(status));
  return WEXITSTATUS(status);
}

/// A closed, slightly squashed sphere (UV grid).
SurfaceMesh ellipsoid() {
  const int nu = 24, nv = 12;
  SurfaceMesh m;
  m.V.resize(2 + nu * (nv - 1), 3);
  m.V.row(0) << 0, 0, 0.7;
  m.V.row(1) << 0, 0, -0.7;
  for (int j = 1; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const double th = M_PI * j / nv, ph = 2 * M_PI * i / nu;
      m.V.row(2 + (j - 1) * nu + i) << 1.2 * std::sin(th) * std::cos(ph),
          std::sin(th) * std::sin(ph), 0.7 * std::cos(th);
    }
  auto id = [&](int j, int i) { return 2 + (j - 1) * nu + (i % nu); };
  for (int i = 0; i < nu; ++i) {
    m.polygons.push_back({0, id(1, i), id(1, i + 1)});
    m.polygons.push_back({1, id(nv - 1, i + 1), id(nv - 1, i)});
    for (int j = 1; j + 1 < nv; ++j) m.polygons.push_back({id(j, i), id(j + 1, i), id(j + 1, i + 1), id(j, i + 1)});
  }
  return m;
}

}  // namespace

TEST_CASE("mbi cage writes a containing control mesh and its statistics", "[cli][cage]") {
  TempDir tmp("cli-cage");
  const fs::path dense = tmp.path() / "e.obj";
  write_surface(dense, ellipsoid());
  const SurfaceMesh m = read_surface(dense);
  const fs::path err = tmp.path() / "err.txt";
  const std::string base = (tmp.path() / "cage").string();
  const auto t0 = std::chrono::steady_clock::now();
  REQUIRE(run("cage \"" + dense.string() + "\" --vertices 120 --out \"" + base + "\" --stats \"" +
                  base + ".json\"",
              err) == 0);
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const ControlMesh c = read_tetgen(base);
  REQUIRE(c.dim() == 3);
  // cage.hpp: the voxel mesher's vertex count is within 10% of the target, every dihedral angle
  // >= 30 degrees (>= 45 with cubic cells; test_cage.cpp tells the two apart)
  REQUIRE(std::abs(c.U.rows() - 120) <= 12);
  REQUIRE(mbi::interp::embed(c.U, c.T, m.V).outside.empty());
  const auto j = nlohmann::json::parse(slurp(base + ".json"));
  for (const char* key : {"vertices", "tetrahedra", "min_dihedral_deg", "outside_points", "seconds"})
    REQUIRE(j.contains(key));
  REQUIRE(j["vertices"].get<long long>() == c.U.rows());
  REQUIRE(j["tetrahedra"].get<long long>() == c.T.rows());
  REQUIRE(j["outside_points"].get<int>() == 0);
  REQUIRE(j["min_dihedral_deg"].get<double>() >= 30.0);
  // the generation time: finite, within the wall time of the whole command measured here
  const double seconds = j["seconds"].get<double>();
  REQUIRE(std::isfinite(seconds));
  REQUIRE(seconds >= 0.0);
  REQUIRE(seconds <= wall_s);
  REQUIRE(j["mesher"].get<std::string>() == "voxel");

  // Same input, same files.
  const std::string node = slurp(base + ".node"), ele = slurp(base + ".ele");
  // an existing output is refused without --force (and left as it was), replaced with it
  REQUIRE(run("cage \"" + dense.string() + "\" --vertices 120 --out \"" + base + "\"", err) == 2);
  REQUIRE(slurp(base + ".node") == node);
  REQUIRE(run("cage \"" + dense.string() + "\" --vertices 120 --out \"" + base + "\" --force", err) == 0);
  REQUIRE(slurp(base + ".node") == node);
  REQUIRE(slurp(base + ".ele") == ele);
}

TEST_CASE("mbi cage --mesher tetgen", "[cli][cage][tetgen]") {
  TempDir tmp("cli-cage");
  const fs::path dense = tmp.path() / "e.obj";
  write_surface(dense, ellipsoid());
  const SurfaceMesh m = read_surface(dense);
  const fs::path err = tmp.path() / "err.txt";
  const std::string base = (tmp.path() / "cage").string();
  REQUIRE(run("cage \"" + dense.string() + "\" --vertices 120 --mesher tetgen --out \"" + base +
                  "\" --stats \"" + base + ".json\"",
              err) == 0);
  const ControlMesh c = read_tetgen(base);
  REQUIRE(c.dim() == 3);
  REQUIRE(std::abs(c.U.rows() - 120) <= 36);  // cage.hpp: TetGen within 30% of the target
  REQUIRE(mbi::interp::embed(c.U, c.T, m.V).outside.empty());
  const auto j = nlohmann::json::parse(slurp(base + ".json"));
  REQUIRE(j["mesher"].get<std::string>() == "tetgen");
  REQUIRE(j["vertices"].get<long long>() == c.U.rows());
  REQUIRE(j["tetrahedra"].get<long long>() == c.T.rows());
  REQUIRE(j["outside_points"].get<int>() == 0);
  REQUIRE(j["min_dihedral_deg"].get<double>() >= 5.0);

  // Same input, same files.
  const std::string node = slurp(base + ".node"), ele = slurp(base + ".ele");
  REQUIRE(run("cage \"" + dense.string() + "\" --vertices 120 --mesher tetgen --out \"" + base +
                  "\" --force",
              err) == 0);
  REQUIRE(slurp(base + ".node") == node);
  REQUIRE(slurp(base + ".ele") == ele);

  REQUIRE(run("cage \"" + dense.string() + "\" --vertices 120 --mesher delaunay --out \"" +
                  (tmp.path() / "x").string() + "\"",
              err) != 0);
  REQUIRE(slurp(err).find("mesher") != std::string::npos);
  REQUIRE_FALSE(fs::exists(tmp.path() / "x.node"));
}

TEST_CASE("mbi cage reports bad input on one line with exit code 2", "[cli][cage]") {
  TempDir tmp("cli-cage");
  const fs::path err = tmp.path() / "err.txt";
  const fs::path missing = tmp.path() / "missing.obj";
  REQUIRE(run("cage \"" + missing.string() + "\" --vertices 100 --out \"" +
                  (tmp.path() / "x").string() + "\"",
              err) == 2);
  std::string msg = slurp(err);
  INFO(msg);
  REQUIRE(msg.rfind("mbi cage: error: " + missing.string(), 0) == 0);
  REQUIRE(std::count(msg.begin(), msg.end(), '\n') == 1);

  const fs::path bad = tmp.path() / "bad.obj";
  std::ofstream(bad) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n";
  REQUIRE(run("cage \"" + bad.string() + "\" --vertices 100 --out \"" + (tmp.path() / "x").string() +
                  "\"",
              err) == 2);
  msg = slurp(err);
  REQUIRE(msg.find(bad.string() + ":4: face 0") != std::string::npos);
  REQUIRE_FALSE(fs::exists(tmp.path() / "x.node"));

  const fs::path ok = tmp.path() / "ok.obj";
  write_surface(ok, ellipsoid());
  REQUIRE(run("cage \"" + ok.string() + "\" --vertices 2 --out \"" + (tmp.path() / "x").string() +
                  "\"",
              err) == 2);
  msg = slurp(err);  // the option is named, not the library's function or parameter
  REQUIRE(msg.rfind("mbi cage: error: --vertices", 0) == 0);
  REQUIRE(msg.find("make_cage") == std::string::npos);
  REQUIRE(msg.find("target_vertices") == std::string::npos);
  REQUIRE(std::count(msg.begin(), msg.end(), '\n') == 1);
  REQUIRE_FALSE(fs::exists(tmp.path() / "x.node"));
}
