// mbi deform on whole trajectories: mbi run's own control_NNNN.vtk and a meshio-written .pvd of
// the same poses give mbi run's dense output again; every input kind into every output kind;
// the outputs' timing; a bad frame or a signal keeps the frames before it, complete.
#include <catch2/catch.hpp>

#include <mbi/io/io.hpp>

#include "common/run_mbi.hpp"

#include <csignal>
#include <cstdlib>
#include <fstream>
#include <set>

#include <nlohmann/json.hpp>

namespace fs = std::filesystem;
using mbi::test::q;
using mbi::test::run_mbi;
using mbi::test::TempDir;

namespace {

fs::path data(const std::string& name) { return mbi::test::source_dir() / "tests" / "data" / "vtu" / name; }

std::string deform(const fs::path& deformed, const fs::path& out, const std::string& more = "") {
  return "deform --control " + q(data("box.node")) + " --mesh " + q(data("sphere.obj")) + " --deformed " + q(deformed) +
         " --out " + q(out) + " " + more;
}

double max_diff(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  REQUIRE(a.rows() == b.rows());
  REQUIRE(a.cols() == b.cols());
  return (a - b).cwiseAbs().maxCoeff();
}

// Debian's interpreter with meshio (the test package list installs python3-meshio).
bool have_meshio() { return std::system("/usr/bin/python3 -c 'import meshio' > /dev/null 2>&1") == 0; }

}  // namespace

TEST_CASE("sequence: mbi run's control frames and a meshio .pvd of them give mbi run's dense frames", "[app][sequence]") {
  TempDir dir("seq");
  const fs::path run = dir / "run";
  const auto r = run_mbi("run " + q(data("sag.toml")) + " --out " + q(run) + " --quiet", dir);
  REQUIRE(r.code == 0);
  const int frames = 5;  // frames 0..4
  REQUIRE(fs::exists(run / "control_0004.vtk"));
  const mbi::io::PointCache dense = mbi::io::read_pc2(run / "dense.pc2");
  REQUIRE(dense.frames.size() == frames);

  // mbi run's own control_NNNN.vtk by a printf pattern: the OBJ frames bit for bit (same doubles)
  auto a = run_mbi(deform(run / "control_%04d.vtk", dir / "a_%04d.obj", "--alpha 0.1"), dir);
  INFO(a.err);
  REQUIRE(a.code == 0);
  CHECK_THAT(a.out, Catch::Contains("frames:  5 of 5"));
  for (int k = 0; k < frames; ++k) {
    const auto got = mbi::io::read_surface(mbi::io::numbered_file((dir / "a_%04d.obj").string(), k));
    const auto ref = mbi::io::read_surface(mbi::io::frame_path(run / "mesh", k, ".obj"));
    CHECK(max_diff(got.V, ref.V) <= 1e-12);
    CHECK(got.F == ref.F);
  }
  // the same by a glob into MDD: float32 of the same values
  a = run_mbi(deform(run / "control_*.vtk", dir / "g.mdd", "--alpha 0.1"), dir);
  REQUIRE(a.code == 0);
  const mbi::io::PointCache g = mbi::io::read_mdd(dir / "g.mdd");
  REQUIRE(g.frames.size() == frames);
  for (int k = 0; k < frames; ++k) CHECK(max_diff(g.frames[k], dense.frames[k]) <= 1e-6);

  // meshio reads control_NNNN.vtk and writes .vtu frames (ASCII, base64, zlib) and a .pvd
  if (!have_meshio()) {
    WARN("python3-meshio missing (scripts/install-deps.sh test): the meshio trajectory is not checked");
    return;
  }
  const std::string convert = "/usr/bin/python3 " + q(data("make.py")) + " " + q(run) + " " + q(dir / "m") + " 2>/dev/null";
  REQUIRE(std::system(convert.c_str()) == 0);
  a = run_mbi(deform(dir / "m" / "run.pvd", dir / "m.pc2", "--alpha 0.1"), dir);
  REQUIRE(a.code == 0);
  const mbi::io::PointCache m = mbi::io::read_pc2(dir / "m.pc2");
  REQUIRE(m.frames.size() == frames);
  // meshio's ASCII keeps 12 digits; the cache is float32: a float's round-off of coordinates < 2
  for (int k = 0; k < frames; ++k) CHECK(max_diff(m.frames[k], dense.frames[k]) <= 2.5e-7);
}

TEST_CASE("sequence: every trajectory into PC2, MDD and OBJ frames, as single poses give", "[app][sequence]") {
  TempDir dir("seq");
  // single-pose mbi deform (the frame pipeline) of the middle pose, the reference
  REQUIRE(run_mbi(deform(data("twist_0001.txt"), dir / "one.obj"), dir).code == 0);
  const Eigen::MatrixXd one = mbi::io::read_surface(dir / "one.obj").V;
  int n = 0;
  for (const std::string in : {"twist.pc2", "twist-blender.mdd", "twist.pvd", "twist_%04d.vtu", "twist_*.txt"}) {
    for (const std::string ext : {".pc2", ".mdd", "_%02d.obj"}) {
      INFO(in << " -> " << ext);
      const fs::path out = dir / ("o" + std::to_string(n++) + ext);
      const auto r = run_mbi(deform(data(in), out), dir);
      INFO(r.err);
      REQUIRE(r.code == 0);
      Eigen::MatrixXd got;
      if (ext == ".pc2") got = mbi::io::read_pc2(out).frames.at(1);
      else if (ext == ".mdd") got = mbi::io::read_mdd(out).frames.at(1);
      else got = mbi::io::read_surface(mbi::io::numbered_file(out.string(), 1)).V;
      // caches hold float32 of float-kernel positions; the inputs' poses: float32 (caches), 12 digits (ASCII .vtu)
      CHECK(max_diff(got, one) <= 1e-6);
    }
  }
  CHECK(dir.entries() == 10 + 5 * 3 + 3);  // caches, OBJ frames, stdout, stderr, one.obj: no temporaries
}

TEST_CASE("sequence: the outputs keep the trajectory's timing", "[app][sequence]") {
  TempDir dir("seq");
  REQUIRE(run_mbi(deform(data("twist.pvd"), dir / "t.mdd"), dir).code == 0);
  CHECK(mbi::io::read_mdd(dir / "t.mdd").times == std::vector<float>{0.5f, 1.0f, 1.5f});
  REQUIRE(run_mbi(deform(data("twist.pvd"), dir / "t.pc2"), dir).code == 0);
  const mbi::io::PointCache p = mbi::io::read_pc2(dir / "t.pc2");
  CHECK(p.start_frame == 12.0f);  // 0.5 s at 24 frames per second, then every 0.5 s
  CHECK(p.sample_rate == 12.0f);
  REQUIRE(run_mbi(deform(data("twist.pc2"), dir / "p.mdd"), dir).code == 0);
  CHECK(mbi::io::read_mdd(dir / "p.mdd").times == std::vector<float>{1 / 24.0f, 2 / 24.0f, 3 / 24.0f});  // frames 1, 2, 3
}

namespace {

// Control positions U (1 + a t) at irregular times, as a .pvd of legacy .vtk files: a motion
// linear in t, which linear interpolation between frames reproduces exactly, and affine in space,
// which every method reproduces: the dense points at time t are P (1 + a t).
constexpr double kGrowth = 0.25;
fs::path growing_box(const TempDir& dir, const std::vector<double>& times) {
  const mbi::io::ControlMesh box = mbi::io::read_control_mesh(data("box.node"));
  std::ofstream pvd(dir / "grow.pvd");
  pvd << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n";
  for (std::size_t k = 0; k < times.size(); ++k) {
    const std::string name = "grow_" + std::to_string(k) + ".vtk";
    mbi::io::write_vtk(dir / name, box.U * (1 + kGrowth * times[k]), box.T);
    pvd << "<DataSet timestep=\"" << times[k] << "\" part=\"0\" file=\"" << name << "\"/>\n";
  }
  pvd << "</Collection>\n</VTKFile>\n";
  return dir / "grow.pvd";
}

}  // namespace

TEST_CASE("sequence: --fps resamples to the output rate, positions linear between input frames", "[app][sequence]") {
  TempDir dir("seq");
  const fs::path pvd = growing_box(dir, {0.2, 0.5, 1.3});
  const Eigen::MatrixXd P = mbi::io::read_surface(data("sphere.obj")).V;
  const auto r = run_mbi(deform(pvd, dir / "r.pc2", "--fps 10 --mesh " + q(data("sphere.obj")) + " --out " + q(dir / "r.mdd")), dir);
  INFO(r.err);
  REQUIRE(r.code == 0);
  // 0.2 s to 1.3 s at 10 frames a second: 12 frames, the first at the scene's frame 0 for a
  // player that plays sample f at frame f (Blender's Mesh Cache by default)
  const mbi::io::PointCache pc2 = mbi::io::read_pc2(dir / "r.pc2"), mdd = mbi::io::read_mdd(dir / "r.mdd");
  REQUIRE(pc2.frames.size() == 12);
  CHECK(pc2.start_frame == 2.0f);
  CHECK(pc2.sample_rate == 1.0f);
  REQUIRE(mdd.times.size() == 12);
  for (int k = 0; k < 12; ++k) {
    const double t = 0.2 + k / 10.0;
    INFO("frame " << k << " at " << t << " s");
    CHECK(mdd.times[static_cast<std::size_t>(k)] == Approx(t).epsilon(1e-6));
    // the analytic motion; float32 caches
    CHECK(max_diff(pc2.frames[static_cast<std::size_t>(k)], P * (1 + kGrowth * t)) <= 1e-6);
    CHECK(max_diff(mdd.frames[static_cast<std::size_t>(k)], P * (1 + kGrowth * t)) <= 1e-6);
  }
  // a glTF of the same frames keys them at the same times
  REQUIRE(run_mbi(deform(pvd, dir / "r.glb", "--fps 10"), dir).code == 0);
  CHECK(max_diff(mbi::io::read_surface(dir / "r.glb").V, P * (1 + kGrowth * 0.2)) <= 1e-6);
}

TEST_CASE("sequence: --fps refuses what it cannot use, naming --fps", "[app][sequence]") {
  TempDir dir("seq");
  for (const std::string bad : {"0", "-24", "nan", "inf", "abc", ""}) {
    INFO("--fps '" << bad << "'");
    const auto r = run_mbi(deform(data("twist.pvd"), dir / "x.pc2", "--fps '" + bad + "'"), dir);
    CHECK(r.code == 2);
    CHECK_THAT(r.err, Catch::Contains("--fps " + bad + ": give a number of frames per second > 0"));
  }
  // no frame times in seconds: a PC2 (frame numbers), numbered files, one pose
  for (const fs::path& in : {data("twist.pc2"), data("twist_%04d.vtu"), data("twist_0001.txt")}) {
    INFO(in);
    const auto r = run_mbi(deform(in, dir / "x.pc2", "--fps 30"), dir);
    CHECK(r.code == 2);
    CHECK_THAT(r.err, Catch::Contains("--fps: ") && Catch::Contains("has no frame times in seconds to resample"));
  }
  CHECK(!fs::exists(dir / "x.pc2"));
}

TEST_CASE("sequence: --displacement adds a meshio .vtu/.vtk point field, as the motion baked into the points", "[app][sequence]") {
  if (!have_meshio()) {
    WARN("python3-meshio missing (scripts/install-deps.sh test): displacement fields are not checked");
    return;
  }
  TempDir dir("seq");
  const std::string make = "/usr/bin/python3 " + q(data("make_displacement.py")) + " " + q(dir / "d") + " 2>/dev/null";
  REQUIRE(std::system(make.c_str()) == 0);
  auto r = run_mbi(deform(dir / "d" / "baked_%04d.vtu", dir / "baked.pc2"), dir);
  REQUIRE(r.code == 0);
  const mbi::io::PointCache baked = mbi::io::read_pc2(dir / "baked.pc2");
  REQUIRE(baked.frames.size() == 3);
  // the field in ASCII, base64 and zlib .vtu, ASCII and binary .vtk
  for (const std::string ext : {".vtu", ".vtk"}) {
    INFO(ext);
    r = run_mbi(deform(dir / "d" / ("disp_%04d" + ext), dir / "disp.pc2", "--force --displacement displacement"), dir);
    INFO(r.err);
    REQUIRE(r.code == 0);
    CHECK(r.err.find("warning") == std::string::npos);
    const mbi::io::PointCache disp = mbi::io::read_pc2(dir / "disp.pc2");
    REQUIRE(disp.frames.size() == 3);
    // 12 digits in ASCII, points + field against their sum: float32 round-off of the output
    for (std::size_t k = 0; k < 3; ++k) CHECK(max_diff(disp.frames[k], baked.frames[k]) <= 1e-6);
    CHECK(max_diff(disp.frames[2], baked.frames[0]) > 0.01);  // the frames do move
  }
  // one pose too
  r = run_mbi(deform(dir / "d" / "disp_0002.vtu", dir / "one.txt", "--displacement displacement"), dir);
  REQUIRE(r.code == 0);
  CHECK(max_diff(mbi::io::read_points(dir / "one.txt"), baked.frames[2]) <= 1e-6);

  // without the option: the rest pose, and a warning naming the field and the option, once
  r = run_mbi(deform(dir / "d" / "disp_%04d.vtu", dir / "rest.pc2"), dir);
  REQUIRE(r.code == 0);
  CHECK_THAT(r.err, Catch::Contains("disp_0000.vtu: the positions are the rest mesh's") &&
                        Catch::Contains("'displacement' (27 x 3): give --displacement displacement"));
  CHECK(r.err.find("warning") == r.err.rfind("warning"));
  // a missing field, a field of the wrong shape, a file without fields: the file and the field named
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"disp_%04d.vtu --displacement nope", "disp_0000.vtu: no point field 'nope' (point fields: temperature, displacement)"},
      {"disp_%04d.vtk --displacement temperature", "disp_0000.vtk: point field 'temperature': 27 x 1 values"},
      {"baked_%04d.vtu --displacement displacement", "baked_0000.vtu: no point field 'displacement' (point fields: none)"}};
  for (const auto& [args, message] : bad) {
    INFO(args);
    r = run_mbi(deform(dir / "d" / args.substr(0, args.find(' ')), dir / "bad.pc2", args.substr(args.find(' '))), dir);
    CHECK(r.code != 0);
    CHECK_THAT(r.err, Catch::Contains(message));
  }
  r = run_mbi(deform(data("twist.pc2"), dir / "bad.pc2", "--displacement u"), dir);
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("twist.pc2: no point field 'u': a point cache holds positions only"));
  CHECK(!fs::exists(dir / "bad.pc2"));
}

TEST_CASE("sequence: a bad frame ends it with every earlier frame complete", "[app][sequence]") {
  TempDir dir("seq");
  for (int k = 0; k < 3; ++k) fs::copy(data("twist_000" + std::to_string(k) + ".txt"), dir / ("x_" + std::to_string(k) + ".txt"));
  std::ofstream(dir / "x_3.txt") << "0 0 0\n1 1 1\n";  // 2 positions for 27 nodes
  for (const std::string ext : {".pc2", ".mdd", "_%d.obj"}) {
    INFO(ext);
    const auto r = run_mbi(deform(dir / "x_%d.txt", dir / ("out" + ext), "--stats " + q(dir / ("s" + ext.substr(1, 3) + ".json"))), dir);
    CHECK(r.code == 3);
    CHECK_THAT(r.err, Catch::Contains("mbi deform: error: frame 3: ") && Catch::Contains("x_3.txt: 2 positions, but the control mesh") &&
                          Catch::Contains("(outputs up to frame 2 kept)"));
    if (ext == ".pc2") CHECK(mbi::io::read_pc2(dir / "out.pc2").frames.size() == 3);
    if (ext == ".mdd") CHECK(mbi::io::read_mdd(dir / "out.mdd").times.size() == 3);
    if (ext != ".pc2" && ext != ".mdd") {
      CHECK(fs::exists(dir / "out_2.obj"));
      CHECK(!fs::exists(dir / "out_3.obj"));
    }
    CHECK_THAT(mbi::test::slurp(dir / ("s" + ext.substr(1, 3) + ".json")), Catch::Contains("\"frames\": 3") && Catch::Contains("\"failure\""));
  }
  // a bad first frame: nothing written, exit 2
  std::ofstream(dir / "y_0.txt") << "0 0 0\n";
  const auto r = run_mbi(deform(dir / "y_%d.txt", dir / "y.pc2"), dir);
  CHECK(r.code == 2);
  CHECK(!fs::exists(dir / "y.pc2"));
  for (const auto& e : fs::directory_iterator(dir.path())) CHECK(e.path().filename().string().rfind(".mbi-tmp", 0) != 0);
}

TEST_CASE("sequence: SIGINT stops after the frame in progress, the cache holds the frames done", "[app][sequence]") {
  TempDir dir("seq");
  // 4,000 frames of 200,000 points: long enough to be interrupted a second after they start
  const Eigen::MatrixXd P = (Eigen::MatrixXd::Random(200000, 3).array() * 0.3 + 0.35).matrix();
  mbi::io::write_points(dir / "p.xyz", P);
  {
    const Eigen::MatrixXd X = mbi::io::read_node(data("box.node"));
    mbi::io::Pc2Writer w(dir / "long.pc2", static_cast<int>(X.rows()));
    for (int k = 0; k < 4000; ++k) w.append(X);
    w.finish();
  }
  const std::string cmd = "(" + q(MBI_EXE) + " deform --control " + q(data("box.node")) + " --mesh " + q(dir / "p.xyz") +
                          " --deformed " + q(dir / "long.pc2") + " --out " + q(dir / "o.pc2") + " > " + q(dir / "out.txt") +
                          " 2> " + q(dir / "err.txt") + " & pid=$!; " +
                          // the cache's temporary appears as the frames start (slow builds: ASan)
                          "for i in $(seq 1200); do ls " + q(dir.path()) + "/.mbi-tmp.*.tmp > /dev/null 2>&1 && break; " +
                          "sleep 0.1; done; sleep 1; kill -INT $pid; wait $pid; echo $? > " + q(dir / "code.txt") + ")";
  REQUIRE(std::system(cmd.c_str()) == 0);
  const std::string err = mbi::test::slurp(dir / "err.txt");
  INFO(err);
  CHECK(std::stoi(mbi::test::slurp(dir / "code.txt")) == 128 + SIGINT);
  CHECK_THAT(err, Catch::Contains("interrupted by SIGINT (outputs up to frame"));
  const mbi::io::PointCache c = mbi::io::read_pc2(dir / "o.pc2");
  CHECK(c.frames.size() > 0);
  CHECK(c.frames.size() < 4000);
  for (const auto& e : fs::directory_iterator(dir.path())) CHECK(e.path().filename().string().rfind(".mbi-tmp", 0) != 0);
}

TEST_CASE("mbi deform --max-outside refuses points far outside, naming how many and the worst", "[app][sequence]") {
  TempDir dir("seq");
  Eigen::MatrixXd P(3, 3);
  P << 0.3, 0.3, 0.3, 0.3, 0.3, 1.5, 0.3, 0.3, 2.0;  // the box's top is at z = 1.414
  mbi::io::write_points(dir / "p.xyz", P);
  const std::string base = "deform --control " + q(data("box.node")) + " --mesh " + q(dir / "p.xyz") + " --deformed ";
  auto r = run_mbi(base + q(data("twist.pc2")) + " --out " + q(dir / "o.pc2") + " --max-outside 0.1", dir);
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("p.xyz: 1 of 3 points lie farther outside the control mesh") &&
                        Catch::Contains("the worst, point 2, by 0.5858"));
  r = run_mbi(base + q(data("twist_0001.txt")) + " --out " + q(dir / "o.xyz") + " --max-outside 0.01", dir);
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("2 of 3 points lie farther outside"));
  CHECK(run_mbi(base + q(data("twist.pc2")) + " --out " + q(dir / "o.pc2") + " --max-outside 0.5", dir).code == 0);
}

TEST_CASE("sequence: one pose is a trajectory of one frame: same positions, table and --stats keys", "[app][sequence]") {
  TempDir dir("seq");
  const auto seq = run_mbi(deform(data("twist_%04d.txt"), dir / "n_%d.obj", "--stats " + q(dir / "seq.json")), dir);
  INFO(seq.err);
  REQUIRE(seq.code == 0);
  const auto one = run_mbi(deform(data("twist_0002.txt"), dir / "one.obj", "--stats " + q(dir / "one.json")), dir);
  INFO(one.err);
  REQUIRE(one.code == 0);
  // the last frame of the series and the pose alone: the same double evaluation
  CHECK(max_diff(mbi::io::read_surface(dir / "n_2.obj").V, mbi::io::read_surface(dir / "one.obj").V) == 0.0);
  const nlohmann::json js = nlohmann::json::parse(mbi::test::slurp(dir / "seq.json"));
  const nlohmann::json jo = nlohmann::json::parse(mbi::test::slurp(dir / "one.json"));
  std::set<std::string> ks, ko;
  for (auto it = js.begin(); it != js.end(); ++it) ks.insert(it.key());
  for (auto it = jo.begin(); it != jo.end(); ++it) ko.insert(it.key());
  CHECK(ks == ko);
  CHECK(js["frames"] == 3);
  CHECK(jo["frames"] == 1);
  CHECK(js["disc"] == jo["disc"]);  // the sequence's table is its last frame's
  CHECK(js["e_total"] == jo["e_total"]);
  CHECK(js["disc"]["modified_bi"]["mean"].get<double>() < js["disc"]["bi"]["mean"].get<double>());
  // both summaries print the table; only the one pose names its file
  for (const std::string& out : {seq.out, one.out}) CHECK_THAT(out, Catch::Contains("face discontinuity over"));
  CHECK_THAT(seq.out, Catch::Contains("frames:  3 of 3") && Catch::Contains("the last frame"));
  CHECK_THAT(one.out, Catch::Contains("wrote "));
}
