// Interoperability through the mbi executable: what users give us survives (UVs, groups, materials,
// normals deformed), file formats follow the output's extension.
#include <catch2/catch.hpp>

#include <mbi/generate/procedural.hpp>
#include <mbi/io/io.hpp>

#include <Eigen/Geometry>

#include "common/run_mbi.hpp"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <sys/wait.h>

namespace fs = std::filesystem;
using mbi::test::q;
using mbi::test::Result;
using mbi::test::run_mbi;
using mbi::test::slurp;
using mbi::test::TempDir;

namespace {


int count_lines(const std::string& s) { return static_cast<int>(std::count(s.begin(), s.end(), '\n')); }

/// Lines of `text` starting with "<key> ".
std::vector<std::string> records(const std::string& text, const std::string& key) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);)
    if (l.rfind(key + " ", 0) == 0) out.push_back(l);
  return out;
}

// Box control mesh (TetGen), twisted positions, and a textured bar OBJ with normals, groups,
// materials and smoothing groups.
struct Setup {
  Eigen::MatrixXd U, X, V;
  Eigen::MatrixXi T, F;
  fs::path control, deformed, mesh;
  std::string obj;
  explicit Setup(const TempDir& dir) {
    mbi::generate::box_tets(Eigen::Vector3d(-0.5, -0.5, 0), Eigen::Vector3d(0.5, 0.5, 4),
                            Eigen::Vector3i(2, 2, 6), U, T);
    X = mbi::generate::twist_bend(U, 0, 0, 0, 4, 1.2, 0.1);
    mbi::generate::box_surface(Eigen::Vector3d(-0.4, -0.4, 0.1), Eigen::Vector3d(0.4, 0.4, 3.9),
                               Eigen::Vector3i(4, 4, 20), V, F);
    control = dir / "bar";
    mbi::io::write_tetgen(control, U, T);
    deformed = dir / "x.txt";
    mbi::io::write_points(deformed, X);
    std::ostringstream s;
    s << "# a textured bar\nmtllib bar.mtl\no Bar\n";
    for (Eigen::Index i = 0; i < V.rows(); ++i) s << "v " << V(i, 0) << " " << V(i, 1) << " " << V(i, 2) << "\n";
    for (Eigen::Index i = 0; i < V.rows(); ++i) s << "vt " << (V(i, 0) + 0.5) << " " << V(i, 2) / 4 << "\n";
    Eigen::MatrixXd N = Eigen::MatrixXd::Zero(V.rows(), 3);
    for (Eigen::Index f = 0; f < F.rows(); ++f) {
      const Eigen::RowVector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
      for (int k = 0; k < 3; ++k) N.row(F(f, k)) += (b - a).cross(c - a);
    }
    N.rowwise().normalize();
    for (Eigen::Index i = 0; i < V.rows(); ++i) s << "vn " << N(i, 0) << " " << N(i, 1) << " " << N(i, 2) << "\n";
    s << "g bar\nusemtl steel\ns 1\n";
    for (Eigen::Index f = 0; f < F.rows(); ++f) {
      if (f == F.rows() / 2) s << "g end\nusemtl rust\ns off\n";
      s << "f";
      for (int k = 0; k < 3; ++k) s << " " << F(f, k) + 1 << "/" << F(f, k) + 1 << "/" << F(f, k) + 1;
      s << "\n";
    }
    obj = s.str();
    mesh = dir / "bar.obj";
    std::ofstream(mesh) << obj;
  }
  std::string args(const fs::path& mesh_file, const fs::path& out) const {
    return "deform --control " + q(control.string() + ".node") + " --deformed " + q(deformed) +
           " --mesh " + q(mesh_file) + " --out " + q(out);
  }
};

}  // namespace

TEST_CASE("mbi deform keeps UVs, groups, materials, smoothing, normals are deformed", "[cli][interop]") {
  TempDir dir("interop");
  Setup s(dir);
  const fs::path out = dir / "out.obj";
  const Result r = run_mbi(s.args(s.mesh, out), dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
  const std::string got = slurp(out);
  for (const char* key : {"mtllib", "o", "vt", "g", "usemtl", "s"})
    CHECK(records(got, key) == records(s.obj, key));
  const mbi::io::SurfaceMesh m = mbi::io::read_surface(out);
  REQUIRE(m.V.rows() == s.V.rows());
  REQUIRE(m.N.rows() == s.V.rows());
  CHECK(m.F == s.F);
  // corners keep their texture coordinates: "f a/a/a" still names vt a
  for (const auto& l : records(got, "f")) {
    std::istringstream in(l.substr(2));
    for (std::string c; in >> c;) {
      const std::string v = c.substr(0, c.find('/'));
      CHECK(c == v + "/" + v + "/" + v);
    }
  }
  // deformed normals: unit, and close to the deformed surface's own vertex normals
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(m.V.rows(), 3);
  for (Eigen::Index f = 0; f < m.F.rows(); ++f) {
    const Eigen::RowVector3d a = m.V.row(m.F(f, 0)), b = m.V.row(m.F(f, 1)), c = m.V.row(m.F(f, 2));
    for (int k = 0; k < 3; ++k) A.row(m.F(f, k)) += (b - a).cross(c - a);
  }
  A.rowwise().normalize();
  double mean_dot = 0;
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) {
    CHECK(m.N.row(i).norm() == Approx(1.0).epsilon(1e-9));
    mean_dot += m.N.row(i).dot(A.row(i)) / static_cast<double>(m.V.rows());
  }
  CHECK(mean_dot > 0.9);
  const mbi::io::SurfaceMesh rest = mbi::io::read_surface(s.mesh);
  CHECK((m.N - rest.N).cwiseAbs().maxCoeff() > 0.1);  // they did move
}

TEST_CASE("mbi deform: output format follows the extension, points as .obj are a valid OBJ",
          "[cli][interop]") {
  TempDir dir("interop");
  Setup s(dir);
  mbi::io::write_points(dir / "pts.xyz", s.V);
  REQUIRE(run_mbi(s.args(dir / "pts.xyz", dir / "pts.txt"), dir).code == 0);
  const Result r = run_mbi(s.args(dir / "pts.xyz", dir / "pts.obj"), dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
  const std::string text = slurp(dir / "pts.obj");
  CHECK(static_cast<Eigen::Index>(records(text, "v").size()) == s.V.rows());
  CHECK(count_lines(text) == s.V.rows());
  CHECK(mbi::io::read_surface(dir / "pts.obj").V == mbi::io::read_points(dir / "pts.txt"));
  // a surface to PLY: positions, faces, normals
  REQUIRE(run_mbi(s.args(s.mesh, dir / "o.ply"), dir).code == 0);
  const mbi::io::SurfaceMesh p = mbi::io::read_surface(dir / "o.ply");
  CHECK(p.F == s.F);
  CHECK(p.N.rows() == s.V.rows());
  // binary PLY in, binary PLY out
  mbi::io::write_surface(dir / "bin.ply", mbi::io::read_surface(s.mesh), mbi::io::Encoding::binary);
  REQUIRE(run_mbi(s.args(dir / "bin.ply", dir / "bin_out.ply"), dir).code == 0);
  CHECK_THAT(slurp(dir / "bin_out.ply"), Catch::Contains("format binary_little_endian 1.0"));
  // binary STL in, binary STL out
  mbi::io::write_surface(dir / "bin.stl", s.V, s.F, mbi::io::Encoding::binary);
  REQUIRE(run_mbi(s.args(dir / "bin.stl", dir / "bin_out.stl"), dir).code == 0);
  CHECK(fs::file_size(dir / "bin_out.stl") == 84u + 50u * static_cast<unsigned>(s.F.rows()));
  // an unknown output extension is refused before anything runs
  const Result bad = run_mbi(s.args(s.mesh, dir / "o.vtk"), dir);
  CHECK(bad.code == 2);
  CHECK_THAT(bad.err, Catch::StartsWith("mbi deform: error: --out") && Catch::Contains("'.vtk'"));
}

TEST_CASE("mbi run --mesh: written frames keep the model's UVs and carry deformed normals",
          "[cli][interop]") {
  TempDir dir("interop");
  Setup s(dir);
  std::ofstream(dir / "scene.toml") << "name = \"uv\"\n[dense]\npath = \"bar.obj\"\n[control]\npath = \"bar.node\"\n"
                                       "[simulation]\nframes = 2\n"
                                       "[[constraints]]\nselect = { box_relative = { min = [0, 0, 0], max = [1, 1, 0] } }\n"
                                       "[[constraints]]\ntype = \"kinematic\"\n"
                                       "select = { box_relative = { min = [0, 0, 1], max = [1, 1, 1] } }\n"
                                       "motion = { twist_axis = [0, 0, 1], twist_rate = 3.0 }\n"
                                       "[output]\nevery = 1\nimage = false\n";
  const Result r = run_mbi("run " + q(dir / "scene.toml") + " --gpu off --quiet --out " + q(dir / "o"), dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
  const std::string got = slurp(dir / "o" / "mesh_0002.obj");
  for (const char* key : {"mtllib", "o", "vt", "g", "usemtl", "s"})
    CHECK(records(got, key) == records(s.obj, key));
  const mbi::io::SurfaceMesh m = mbi::io::read_surface(dir / "o" / "mesh_0002.obj");
  REQUIRE(m.N.rows() == s.V.rows());
  CHECK((m.N - mbi::io::read_surface(s.mesh).N).cwiseAbs().maxCoeff() > 1e-3);
}

TEST_CASE("CLI messages: unknown subcommand with a suggestion, one-line prefixed parse errors",
          "[cli][interop]") {
  TempDir dir("interop");
  auto one_line = [](const Result& r) { return count_lines(r.err) == 1; };
  Result r = run_mbi("rn", dir);
  CHECK(r.code == 2);
  CHECK(r.err == "mbi: error: unknown subcommand 'rn' (did you mean 'run'?)\n");
  r = run_mbi("defrom --mesh x", dir);
  CHECK(r.err == "mbi: error: unknown subcommand 'defrom' (did you mean 'deform'?)\n");
  r = run_mbi("frobnicate", dir);
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::StartsWith("mbi: error: unknown subcommand 'frobnicate' (known: cage, deform"));
  CHECK(one_line(r));
  r = run_mbi("", dir);
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::StartsWith("mbi: error: a subcommand is required: cage, deform"));
  CHECK(one_line(r));
  // parse errors of a subcommand carry its prefix, on one line
  for (const auto& [args, needle] : std::vector<std::pair<std::string, std::string>>{
           {"deform --alpha abc", "mbi deform: error: "},
           {"deform --method foo", "mbi deform: error: --method"},
           {"deform --nope", "mbi deform: error: "},
           {"run", "mbi run: error: scene is required"},
           {"cage x.obj --out y", "mbi cage: error: --vertices is required"}}) {
    r = run_mbi(args, dir);
    INFO(args << "\n" << r.err);
    CHECK(r.code == 2);
    CHECK_THAT(r.err, Catch::StartsWith(needle));
    CHECK(one_line(r));
  }
  // no internal function names: cage -n 3, a degenerate control element
  r = run_mbi("cage x.obj -n 3 -o " + q(dir / "c"), dir);
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::StartsWith("mbi cage: error: --vertices") && !Catch::Contains("make_cage"));
  Setup s(dir);
  Eigen::MatrixXi T = s.T;
  T(5, 3) = T(5, 2);
  mbi::io::write_tetgen(dir / "degen", s.U, T);
  r = run_mbi("deform --control " + q(dir / "degen") + " --deformed " + q(s.deformed) + " --mesh " +
                  q(s.mesh) + " --out " + q(dir / "o.obj"),
              dir);
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("element 5") && !Catch::Contains("validate_mesh"));
  // --help exits 0 and marks what is required
  r = run_mbi("cage --help", dir);
  CHECK(r.code == 0);
  for (const char* opt : {"dense TEXT REQUIRED", "--vertices INT:INT in [8 - 1000000] REQUIRED", "--out TEXT REQUIRED"})
    CHECK_THAT(r.out, Catch::Contains(opt));
  r = run_mbi("deform --help", dir);
  CHECK(r.code == 0);
  for (const char* opt : {"--control", "--deformed", "--mesh", "--out"}) {
    const std::size_t at = r.out.find(std::string("  ") + opt + " TEXT");
    REQUIRE(at != std::string::npos);
    CHECK(r.out.substr(at, r.out.find('\n', at) - at).find("REQUIRED (unless --example)") != std::string::npos);
  }
  CHECK_THAT(run_mbi("run --help", dir).out, Catch::Contains("scene TEXT REQUIRED"));
}

TEST_CASE("a stale .face beside .node/.ele breaks neither deform nor run, cage removes it",
          "[cli][interop]") {
  TempDir dir("interop");
  Setup s(dir);
  std::ofstream(dir / "bar.face") << "3 1\n0 0 1 999\nstale and broken\n";
  Result r = run_mbi(s.args(s.mesh, dir / "o.obj"), dir);
  INFO(r.err);
  CHECK(r.code == 0);
  std::ofstream(dir / "scene.toml") << "[dense]\npath = \"bar.obj\"\n[control]\npath = \"bar.node\"\n"
                                       "[simulation]\nframes = 1\n[[constraints]]\n"
                                       "select = { box_relative = { min = [0, 0, 0], max = [1, 1, 0] } }\n"
                                       "[output]\nimage = false\n";
  r = run_mbi("run " + q(dir / "scene.toml") + " --gpu off --quiet --out " + q(dir / "run"), dir);
  CHECK(r.code == 0);
  // cage: a stale companion of BASE goes, and says so
  mbi::io::write_surface(dir / "ell.obj", mbi::io::read_surface(s.mesh));
  std::ofstream(dir / "cage.face") << "stale\n";
  std::ofstream(dir / "cage.edge") << "stale\n";
  r = run_mbi("cage " + q(dir / "ell.obj") + " -n 40 -o " + q(dir / "cage"), dir);
  INFO(r.err);
  CHECK(r.code == 0);
  CHECK(fs::exists(dir / "cage.node"));
  CHECK_FALSE(fs::exists(dir / "cage.face"));
  CHECK_FALSE(fs::exists(dir / "cage.edge"));
  CHECK_THAT(r.err, Catch::Contains("removed") && Catch::Contains("cage.face"));
}

TEST_CASE("deform refuses an existing output unless --force, as run does", "[cli][interop]") {
  TempDir dir("interop");
  Setup s(dir);
  const fs::path out = dir / "o.obj";
  std::ofstream(out) << "keep me\n";
  Result r = run_mbi(s.args(s.mesh, out), dir);
  CHECK(r.code == 2);
  CHECK(r.err == "mbi deform: error: --out " + out.string() + ": exists (use --force to overwrite)\n");
  CHECK(slurp(out) == "keep me\n");
  std::ofstream(dir / "stats.json") << "{}";
  r = run_mbi(s.args(s.mesh, dir / "new.obj") + " --stats " + q(dir / "stats.json"), dir);
  CHECK(r.code == 2);
  CHECK_FALSE(fs::exists(dir / "new.obj"));
  r = run_mbi(s.args(s.mesh, out) + " --force --stats " + q(dir / "stats.json"), dir);
  CHECK(r.code == 0);
  CHECK(mbi::io::read_surface(out).V.rows() == s.V.rows());
  CHECK(slurp(dir / "stats.json").size() > 10);
}

TEST_CASE("run --quiet keeps warnings, --force clears an earlier run's extra frames only",
          "[cli][interop]") {
  TempDir dir("interop");
  Setup s(dir);
  // a dense model partly outside the control mesh
  mbi::io::SurfaceMesh wide = mbi::io::read_surface(s.mesh);
  wide.V.col(0) *= 1.5;
  wide.N.resize(0, 0);
  mbi::io::write_surface(dir / "wide.obj", wide);
  auto scene = [&](int every) {
    std::ofstream(dir / "scene.toml") << "[dense]\npath = \"wide.obj\"\n[control]\npath = \"bar.node\"\n"
                                         "[simulation]\nframes = 4\n[[constraints]]\n"
                                         "select = { box_relative = { min = [0, 0, 0], max = [1, 1, 0] } }\n"
                                         "[output]\nimage = false\nevery = " << every << "\n";
  };
  scene(1);
  const fs::path out = dir / "o";
  Result r = run_mbi("run " + q(dir / "scene.toml") + " --gpu off --quiet --out " + q(out), dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(count_lines(r.err) == 1);  // the warning, once, short
  CHECK_THAT(r.err, Catch::StartsWith("mbi run: warning: ") && Catch::Contains("outside the control mesh"));
  CHECK(fs::exists(out / "mesh_0003.obj"));
  // the same folder again, every 2nd frame: frames 1 and 3 of the earlier run must not stay;
  // a user's file in the folder does
  std::ofstream(out / "notes.txt") << "mine\n";
  std::ofstream(out / "mesh_final.obj") << "mine too\n";
  scene(2);
  r = run_mbi("run " + q(dir / "scene.toml") + " --gpu off --quiet --out " + q(out), dir);
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("--force"));
  r = run_mbi("run " + q(dir / "scene.toml") + " --gpu off --quiet --force --out " + q(out), dir);
  REQUIRE(r.code == 0);
  for (int f : {0, 2, 4}) CHECK(fs::exists(mbi::io::frame_path(out / "mesh", f, ".obj")));
  for (int f : {1, 3}) {
    CHECK_FALSE(fs::exists(mbi::io::frame_path(out / "mesh", f, ".obj")));
    CHECK_FALSE(fs::exists(mbi::io::frame_path(out / "control", f, ".vtk")));
  }
  CHECK(slurp(out / "notes.txt") == "mine\n");
  CHECK(fs::exists(out / "mesh_final.obj"));
}

TEST_CASE("mbi deform with gmsh and VTK files from the tools: .msh/.vtk as --control and --deformed",
          "[cli][interop][gmsh]") {
  TempDir dir("interop");
  const char* src = std::getenv("MBI_SOURCE_DIR");
  REQUIRE(src != nullptr);
  const fs::path data = fs::path(src) / "tests" / "data" / "gmsh";
  // a dense box surface inside the 1 x 1 x 2 box, and the gmsh mesh twisted
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  mbi::generate::box_surface(Eigen::Vector3d(0.1, 0.1, 0.1), Eigen::Vector3d(0.9, 0.9, 1.9),
                             Eigen::Vector3i(3, 3, 6), V, F);
  mbi::io::write_surface(dir / "dense.obj", V, F);
  const mbi::io::ControlMesh cm = mbi::io::read_gmsh(data / "box-41-bin.msh");
  const Eigen::MatrixXd X = mbi::generate::twist_bend(cm.U, 0.5, 0.5, 0, 2, 0.8, 0.05);
  mbi::io::write_points(dir / "x.txt", X);
  // the deformed positions as .msh (nodes only, the file's order and tags) and as .vtk
  {
    std::ofstream msh(dir / "x.msh");
    msh.precision(17);
    msh << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n" << X.rows() << "\n";
    for (Eigen::Index i = 0; i < X.rows(); ++i) msh << i + 7 << " " << X(i, 0) << " " << X(i, 1) << " " << X(i, 2) << "\n";
    msh << "$EndNodes\n";
  }
  mbi::io::write_vtk(dir / "x.vtk", X, cm.T);
  mbi::io::write_vtk(dir / "rest.vtk", cm.U, cm.T);  // as mbi cage --vtk writes it
  auto deform = [&](const fs::path& control, const fs::path& deformed, const fs::path& out) {
    return run_mbi("deform --control " + q(control) + " --deformed " + q(deformed) + " --mesh " +
                       q(dir / "dense.obj") + " --out " + q(out),
                   dir);
  };
  Result r = deform(data / "box-41-bin.msh", dir / "x.txt", dir / "ref.obj");
  INFO(r.err);
  REQUIRE(r.code == 0);
  const Eigen::MatrixXd ref = mbi::io::read_surface(dir / "ref.obj").V;
  for (const auto& [control, deformed] :
       std::vector<std::pair<fs::path, fs::path>>{{data / "box-41-bin.msh", dir / "x.msh"},
                                                  {data / "box-41-bin.msh", dir / "x.vtk"},
                                                  {data / "box-22.msh", dir / "x.txt"},
                                                  {data / "box-40.msh", dir / "x.msh"},
                                                  {data / "box-bin.vtk", dir / "x.vtk"},
                                                  {dir / "rest.vtk", dir / "x.txt"}}) {
    INFO(control << " + " << deformed);
    fs::remove(dir / "o.obj");
    r = deform(control, deformed, dir / "o.obj");
    INFO(r.err);
    REQUIRE(r.code == 0);
    CHECK((mbi::io::read_surface(dir / "o.obj").V - ref).cwiseAbs().maxCoeff() < 1e-6);
  }
  // second-order tetrahedra: used by their corners, with a notice
  r = deform(data / "box-41-order2.msh", data / "box-41-order2.msh", dir / "o2.obj");
  CHECK(r.code == 0);
  CHECK_THAT(r.err, Catch::Contains("mbi deform: note: ") && Catch::Contains("higher-order tetrahedra used by their corners"));
  // a Physical Surface only: named as such
  r = deform(data / "surface-only.msh", dir / "x.txt", dir / "o3.obj");
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("surface mesh of a 3D model"));
  CHECK(count_lines(r.err) == 1);
}
