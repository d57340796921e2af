// `mbi deform` and `mbi run` end to end through the real executable: outputs agree with the
// library, statistics are complete, and every bad input gives exit code 2, a one-line message
// naming the file / line / element, and no output file.
#include <catch2/catch.hpp>

#include <mbi/interp.hpp>
#include <mbi/io/io.hpp>
#include <mbi/generate/procedural.hpp>

#include "common/run_mbi.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <sys/wait.h>

namespace fs = std::filesystem;
using mbi::test::q;
using mbi::test::Result;
using mbi::test::run_mbi;
using mbi::test::TempDir;

namespace {


// A 3D setup on disk: box control mesh (TetGen), twisted positions (text), dense bar (OBJ).
struct Files {
  Eigen::MatrixXd U, X, V;
  Eigen::MatrixXi T, F;
  fs::path control, deformed, mesh;
  explicit Files(const TempDir& dir) {
    mbi::generate::box_tets(Eigen::Vector3d(-0.5, -0.5, 0), Eigen::Vector3d(0.5, 0.5, 4),
                          Eigen::Vector3i(2, 2, 6), U, T);
    X = mbi::generate::twist_bend(U, 0, 0, 0, 4, 1.2, 0.1);
    mbi::generate::box_surface(Eigen::Vector3d(-0.4, -0.4, 0.1), Eigen::Vector3d(0.4, 0.4, 3.9),
                             Eigen::Vector3i(4, 4, 20), V, F);
    control = dir / "bar";
    mbi::io::write_tetgen(control, U, T);
    deformed = dir / "x.txt";
    mbi::io::write_points(deformed, X);
    mesh = dir / "dense.obj";
    mbi::io::write_surface(mesh, V, F);
  }
  std::string args(const fs::path& out) const {
    return "deform --control " + q(control.string() + ".node") + " --deformed " + q(deformed) +
           " --mesh " + q(mesh) + " --out " + q(out);
  }
};

}  // namespace

TEST_CASE("mbi deform on files matches the library and writes complete stats", "[cli]") {
  TempDir dir("cli");
  Files f(dir);
  const fs::path out = dir / "out.obj", stats = dir / "stats.json";
  const Result r = run_mbi(f.args(out) + " --stats " + q(stats), dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
  const mbi::io::SurfaceMesh got = mbi::io::read_surface(out);
  REQUIRE(got.V.rows() == f.V.rows());
  CHECK(got.F == f.F);  // faces and vertex order kept

  const mbi::interp::ModifiedBI solver(f.U, f.T);
  const mbi::interp::Embedding emb = mbi::interp::embed(f.U, f.T, f.V);
  Eigen::MatrixXd expected;
  mbi::interp::evaluate<double>(solver.bezier(f.X, solver.solve(f.X)), emb, expected);
  CHECK((got.V - expected).cwiseAbs().maxCoeff() < 1e-12);  // OBJ written with %.17g

  std::ifstream in(stats);
  const nlohmann::json j = nlohmann::json::parse(in);
  for (const char* key : {"method", "dim", "alpha", "beta", "control_vertices", "elements", "points",
                          "outside_points", "null_space_dim", "disc", "e_vibr", "e_disc", "timings_ms"})
    CHECK(j.contains(key));
  CHECK(j["dim"] == 3);
  CHECK(j["null_space_dim"] == 6);
  CHECK(j["control_vertices"] == f.U.rows());
  CHECK(j["points"] == f.V.rows());
  CHECK(j["alpha"].get<double>() == Approx(0.1));
  for (const char* t : {"embed", "precompute", "read", "deform", "write"}) CHECK(j["timings_ms"].contains(t));
  CHECK(j["frames"] == 1);  // one pose: a trajectory of one frame
  CHECK(j["frames_in_trajectory"] == 1);
  for (const char* s : {"bi", "modified_bi", "ratio"})
    for (const char* v : {"mean", "std", "max"}) CHECK(j["disc"][s].contains(v));
  CHECK(j["disc"]["bi"]["mean"].get<double>() > j["disc"]["modified_bi"]["mean"].get<double>());
}

TEST_CASE("mbi deform: BI, Gmsh, point lists, 2D", "[cli]") {
  TempDir dir("cli");
  Files f(dir);
  SECTION("--method bi reproduces plain barycentric interpolation") {
    const fs::path out = dir / "bi.txt";
    std::string a = f.args(out) + " --method bi";
    // dense as a point list: written back with round-trip precision
    mbi::io::write_points(dir / "pts.xyz", f.V);
    a = "deform --control " + q(f.control) + " --deformed " + q(f.deformed) + " --mesh " +
        q(dir / "pts.xyz") + " --out " + q(out) + " --method bi";
    REQUIRE(run_mbi(a, dir).code == 0);
    const Eigen::MatrixXd got = mbi::io::read_points(out);
    const mbi::interp::Embedding emb = mbi::interp::embed(f.U, f.T, f.V);
    Eigen::MatrixXd expected;
    mbi::interp::evaluate<double>(mbi::interp::bezier_bi(f.X, f.T), emb, expected);
    CHECK((got - expected).cwiseAbs().maxCoeff() == 0.0);
  }
  SECTION("Gmsh 2.2 control mesh") {
    std::ofstream msh(dir / "c.msh");
    msh << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n" << f.U.rows() << "\n";
    for (int i = 0; i < f.U.rows(); ++i)
      msh << i + 1 << " " << f.U(i, 0) << " " << f.U(i, 1) << " " << f.U(i, 2) << "\n";
    msh << "$EndNodes\n$Elements\n" << f.T.rows() << "\n";
    for (int e = 0; e < f.T.rows(); ++e)
      msh << e + 1 << " 4 2 0 1 " << f.T(e, 0) + 1 << " " << f.T(e, 1) + 1 << " " << f.T(e, 2) + 1
          << " " << f.T(e, 3) + 1 << "\n";
    msh << "$EndElements\n";
    msh.close();
    const std::string a = "deform --control " + q(dir / "c.msh") + " --deformed " + q(f.deformed) +
                          " --mesh " + q(f.mesh) + " --out " + q(dir / "g.obj");
    const Result r = run_mbi(a, dir);
    INFO(r.err);
    CHECK(r.code == 0);
  }
  SECTION("2D control mesh and 2D points, alpha and pinned boundary") {
    Eigen::MatrixXd U2, P2;
    Eigen::MatrixXi T2, F2;
    mbi::generate::grid_2d(4, 3, 4, 3, U2, T2);
    mbi::generate::grid_2d(4, 3, 40, 30, P2, F2);
    Eigen::MatrixXd X2 = U2;
    for (int i = 0; i < X2.rows(); ++i) X2(i, 1) += 0.2 * std::sin(U2(i, 0));
    mbi::io::write_tetgen(dir / "tri", U2, T2);
    mbi::io::write_points(dir / "x2.txt", X2);
    mbi::io::write_points(dir / "p2.txt", P2);
    const std::string a = "deform --control " + q(dir / "tri.ele") + " --deformed " + q(dir / "x2.txt") +
                          " --mesh " + q(dir / "p2.txt") + " --out " + q(dir / "o2.txt") +
                          " --alpha 0.5 --pin-boundary --stats " + q(dir / "s2.json");
    const Result r = run_mbi(a, dir);
    INFO(r.err);
    REQUIRE(r.code == 0);
    CHECK(mbi::io::read_points(dir / "o2.txt").rows() == P2.rows());
    std::ifstream in(dir / "s2.json");
    const nlohmann::json j = nlohmann::json::parse(in);
    CHECK(j["dim"] == 2);
    CHECK(j["alpha"].get<double>() == Approx(0.5));
    CHECK(j["null_space_dim"] == 0);
  }
}

TEST_CASE("mbi deform --example twist-bar prints the table", "[cli]") {
  TempDir dir("cli");
  const Result r = run_mbi("deform --example twist-bar --stats " + q(dir / "s.json"), dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
  std::ifstream in(dir / "s.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  CHECK(j["control_vertices"] == 35);
  CHECK(j["points"] == 23402);
  CHECK(j["outside_points"] == 0);
  // modified-BI is far smoother than BI on the smoothly twisted bar
  CHECK(j["disc"]["ratio"]["mean"].get<double>() > 20.0);
  std::ifstream out(dir / "stdout.txt");
  std::stringstream ss;
  ss << out.rdbuf();
  CHECK_THAT(ss.str(), Catch::Contains("Mean") && Catch::Contains("StdDev") && Catch::Contains("Max"));
}

TEST_CASE("mbi deform --example twist-bar: BI, Phong and modified-BI side by side", "[cli][phong]") {
  TempDir dir("cli");
  for (const char* method : {"phong", "modified-bi"}) {
    INFO("--method " << method);
    const Result r = run_mbi(std::string("deform --example twist-bar --method ") + method +
                                 " --alpha 0.1 --force --stats " + q(dir / "s.json"),
                             dir);
    INFO(r.err);
    REQUIRE(r.code == 0);
    std::ifstream in(dir / "s.json");
    const nlohmann::json j = nlohmann::json::parse(in);
    CHECK(j["method"] == method);
    // the existing keys, plus Phong's column and its ratio to BI
    for (const char* k : {"bi", "modified_bi", "ratio", "phong", "phong_ratio"})
      for (const char* s : {"mean", "std", "max"}) CHECK(j["disc"][k][s].is_number());
    const double bi = j["disc"]["bi"]["mean"], ph = j["disc"]["phong"]["mean"],
                 mb = j["disc"]["modified_bi"]["mean"];
    CHECK(j["disc"]["phong_ratio"]["mean"].get<double>() == Approx(bi / ph));
    CHECK(bi > ph);
    CHECK(ph > mb);
    // accuracy against the closed-form twist, for all three
    for (const char* k : {"bi", "phong", "modified_bi"})
      for (const char* s : {"position_rms", "position_max", "gradient_rms", "gradient_max", "size"})
        CHECK(j["accuracy"][k][s].is_number());
    CHECK(j["accuracy"]["bi"]["size"].get<double>() == Approx(std::sqrt(38.0)));
    const double e_bi = j["accuracy"]["bi"]["position_rms"], e_ph = j["accuracy"]["phong"]["position_rms"],
                 e_mb = j["accuracy"]["modified_bi"]["position_rms"];
    INFO("position RMS / size: BI " << e_bi << ", Phong " << e_ph << ", modified-BI " << e_mb);
    CHECK(e_bi > e_ph);
    CHECK(e_ph > e_mb);
    std::ifstream out(dir / "stdout.txt");
    std::stringstream ss;
    ss << out.rdbuf();
    const std::string text = ss.str();
    INFO(text);
    CHECK_THAT(text, Catch::Contains("BI") && Catch::Contains("Phong") &&
                         Catch::Contains("modified-BI") && Catch::Contains("BI/Phong") &&
                         Catch::Contains("closed-form deformation") && Catch::Contains("pos RMS") &&
                         Catch::Contains("grad RMS"));
  }
}

TEST_CASE("mbi deform errors: exit 2, one line naming the culprit, nothing written", "[cli]") {
  TempDir dir("cli");
  Files f(dir);
  const fs::path out = dir / "out.obj";
  auto expect_error = [&](const std::string& args, const std::string& needle) {
    const Result r = run_mbi(args, dir);
    INFO(args << "\n" << r.err);
    CHECK(r.code == 2);
    CHECK_THAT(r.err, Catch::Contains(needle));
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    CHECK_FALSE(fs::exists(out));
  };
  expect_error("deform --control " + q(dir / "nope.node") + " --deformed " + q(f.deformed) +
                   " --mesh " + q(f.mesh) + " --out " + q(out),
               "nope.node");
  // count mismatch
  mbi::io::write_points(dir / "short.txt", f.X.topRows(f.X.rows() - 1));
  expect_error("deform --control " + q(f.control) + " --deformed " + q(dir / "short.txt") +
                   " --mesh " + q(f.mesh) + " --out " + q(out),
               "short.txt");
  // NaN in the deformed positions: the file and line are named
  {
    std::ofstream bad(dir / "nan.txt");
    for (int i = 0; i < f.X.rows(); ++i) bad << (i == 3 ? std::string("nan") : std::to_string(f.X(i, 0))) << " " << f.X(i, 1) << " " << f.X(i, 2) << "\n";
  }
  expect_error("deform --control " + q(f.control) + " --deformed " + q(dir / "nan.txt") +
                   " --mesh " + q(f.mesh) + " --out " + q(out),
               "nan.txt:4");
  // malformed dense mesh
  std::ofstream(dir / "broken.obj") << "v 0 0 0\nv 1 0 0\nf 1 2 9\n";
  expect_error("deform --control " + q(f.control) + " --deformed " + q(f.deformed) + " --mesh " +
                   q(dir / "broken.obj") + " --out " + q(out),
               "broken.obj");
  // degenerate element: the element is named
  {
    Eigen::MatrixXd U = f.U;
    Eigen::MatrixXi T = f.T;
    T(5, 3) = T(5, 2);  // repeated vertex
    mbi::io::write_tetgen(dir / "degen", U, T);
  }
  expect_error("deform --control " + q(dir / "degen") + " --deformed " + q(f.deformed) +
                   " --mesh " + q(f.mesh) + " --out " + q(out),
               "element 5");
  // alpha must be positive
  expect_error(f.args(out) + " --alpha 0", "--alpha");
  expect_error(f.args(out) + " --alpha -1", "--alpha");
  // an existing output survives a failed run untouched
  std::ofstream(out) << "keep me\n";
  const Result r = run_mbi("deform --control " + q(dir / "degen") + " --deformed " + q(f.deformed) +
                           " --mesh " + q(f.mesh) + " --out " + q(out),
                       dir);
  CHECK(r.code == 2);
  std::ifstream kept(out);
  std::string line;
  std::getline(kept, line);
  CHECK(line == "keep me");
}

TEST_CASE("mbi run: scene errors name file, line and key", "[cli]") {
  TempDir dir("cli");
  std::ofstream(dir / "bad.toml") << "[dense]\nbuiltin = \"paper-bar\"\n[control]\nbuiltin = \"paper-bar\"\n[simulation]\nfps = 30\n";
  const Result r = run_mbi("run " + q(dir / "bad.toml") + " --out " + q(dir / "o"), dir);
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("bad.toml:6") && Catch::Contains("simulation.fps"));
  CHECK_FALSE(fs::exists(dir / "o"));
}

TEST_CASE("mbi run writes the outputs of a scene", "[cli]") {
  TempDir dir("cli");
  const char* src = std::getenv("MBI_SOURCE_DIR");
  REQUIRE(src != nullptr);
  const Result r = run_mbi("run " + q(fs::path(src) / "scenes" / "twist-bar.toml") + " --frames 2 --out " +
                           q(dir / "o"),
                       dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(fs::exists(dir / "o" / "metrics.json"));
  CHECK(fs::exists(dir / "o" / "dense.pc2"));
  CHECK(fs::exists(dir / "o" / "mesh_0002.obj"));
  CHECK(fs::exists(dir / "o" / "frame_0002.png"));
}

TEST_CASE("mbi run --gpu: on without OpenGL exits 2 naming why, auto notes the fallback once", "[cli][gpu]") {
  TempDir dir("cli");
  const char* src = std::getenv("MBI_SOURCE_DIR");
  REQUIRE(src != nullptr);
  const std::string scene = q(fs::path(src) / "scenes" / "twist-bar.toml");
  const Result on = run_mbi("run " + scene + " --frames 2 --gpu on --out " + q(dir / "on"), dir, "MBI_GL=none");
  CHECK(on.code == 2);
  CHECK_THAT(on.err, Catch::StartsWith("mbi run: error: gpu = on, but no OpenGL context") &&
                         Catch::Contains("MBI_GL=none"));
  CHECK(std::count(on.err.begin(), on.err.end(), '\n') == 1);
  CHECK_FALSE(fs::exists(dir / "on"));
  const Result aut = run_mbi("run " + scene + " --frames 2 --quiet --out " + q(dir / "auto"), dir, "MBI_GL=none");
  CHECK(aut.code == 0);
  CHECK_THAT(aut.err, Catch::Contains("note: no OpenGL context") && Catch::Contains("on the CPU"));
  CHECK(std::count(aut.err.begin(), aut.err.end(), '\n') == 1);  // once, even with --quiet
  CHECK(fs::exists(dir / "auto" / "frame_0002.png"));
  const Result gpu = run_mbi("run " + scene + " --frames 2 --gpu on --out " + q(dir / "gpu"), dir);
  CHECK(gpu.code == 0);
  CHECK_THAT(gpu.out, Catch::Contains("evaluated on gpu"));
}

TEST_CASE("mbi run: a failing simulation step exits 3, keeps the outputs so far, one error line",
          "[cli]") {
  TempDir dir("cli");
  // as in the runner test "a failing simulation step stops the run and keeps what was written":
  // an absurd force on a soft bar makes the simulator's energy guard fail step 3
  const fs::path out = dir / "o";
  const Result r =
      run_mbi("run " + q(mbi::test::source_dir() / "tests/data/scenes/fail.toml") + " --out " + q(out) + " --quiet", dir);
  INFO(r.err);
  CHECK(r.code == 3);
  // --quiet: stderr holds the error alone, on one line, naming the step and the frames kept
  CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  CHECK_THAT(r.err, Catch::StartsWith("mbi run: error: ") && Catch::Contains("step 3") &&
                        Catch::Contains("up to frame 2 kept"));
  // the outputs of frames 0 to 2 are kept and complete, nothing after them
  std::ifstream in(out / "metrics.json");
  REQUIRE(in.good());
  const nlohmann::json m = nlohmann::json::parse(in);
  CHECK(m["frames_completed"] == 2);
  CHECK_THAT(m["failure"].get<std::string>(), Catch::Contains("step 3"));
  CHECK(mbi::io::read_pc2(out / "dense.pc2").frames.size() == 3);
  for (int f : {0, 2}) {
    const mbi::io::SurfaceMesh mesh = mbi::io::read_surface(mbi::io::frame_path(out / "mesh", f, ".obj"));
    CHECK(mesh.V.allFinite());
    CHECK(fs::exists(mbi::io::frame_path(out / "control", f, ".vtk")));
    CHECK(fs::exists(mbi::io::frame_path(out / "frame", f, ".png")));
  }
  CHECK_FALSE(fs::exists(mbi::io::frame_path(out / "mesh", 4, ".obj")));
  for (const auto& e : fs::directory_iterator(out))  // no temporary files left behind
    CHECK(e.path().filename().string().find(".tmp") == std::string::npos);
}
