// VTK XML (.vtu) written by real writers (tests/data/vtu, see its README: meshio and VTK itself,
// every encoding), ParaView collections, MDD and point caches read a frame at a time, and
// control trajectories (printf patterns, globs, .pvd, caches).
#include <mbi/io/io.hpp>
#include <mbi/io/parse.hpp>

#include "common/files.hpp"
#include "common/temp_dir.hpp"

#include <catch2/catch.hpp>

#include <cstring>
#include <fstream>
#include <limits>

namespace fs = std::filesystem;
using namespace mbi::io;
using mbi::test::TempDir;

namespace {

fs::path data(const std::string& name) { return mbi::test::source_dir() / "tests" / "data" / "vtu" / name; }

// The three twisted poses of the fixtures, as %.17g text.
std::vector<Eigen::MatrixXd> twist_frames() {
  std::vector<Eigen::MatrixXd> f;
  for (int k = 0; k < 3; ++k) f.push_back(read_points(data("twist_000" + std::to_string(k) + ".txt")));
  return f;
}

}  // namespace

TEST_CASE("vtu: every encoding of meshio and VTK reads the same box as TetGen", "[io][vtu]") {
  const ControlMesh ref = read_control_mesh(data("box.node"));
  REQUIRE(ref.U.rows() == 27);
  REQUIRE(ref.T.rows() == 48);
  for (const char* name : {"box-meshio-ascii.vtu", "box-meshio-binary.vtu", "box-meshio-zlib.vtu", "box-vtk-raw.vtu",
                           "box-vtk-raw-zlib.vtu", "box-vtk-appended-base64.vtu", "box-vtk-appended-base64-zlib.vtu",
                           "box-vtk-binary-zlib-bigendian.vtu"}) {
    INFO(name);
    const ControlMesh m = read_control_mesh(data(name));
    // Float64 everywhere: bit for bit, but meshio's ASCII prints 12 digits
    const double tol = std::string(name).find("ascii") != std::string::npos ? 1e-11 : 0.0;
    CHECK((m.U - ref.U).cwiseAbs().maxCoeff() <= tol);
    CHECK(m.T == ref.T);
    CHECK((read_positions(data(name)) - ref.U).cwiseAbs().maxCoeff() <= tol);
  }
}

TEST_CASE("vtu: messages name the file, the line and what is wrong", "[io][vtu]") {
  const std::string good = mbi::test::slurp(data("box-meshio-ascii.vtu"));
  auto message = [](const std::string& bytes) {
    try {
      parse_vtu_mesh(bytes, "x.vtu");
    } catch (const mbi::io::Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  CHECK_THAT(message("<VTKFile type=\"PolyData\"/>"), Catch::Contains("x.vtu:1: VTKFile of type 'PolyData'"));
  CHECK_THAT(message("<VTKFile"), Catch::Contains("x.vtu:1: not valid XML"));
  std::string bad = good;
  bad.replace(bad.find("NumberOfPoints=\"27\""), 19, "NumberOfPoints=\"28\"");
  CHECK_THAT(message(bad), Catch::Contains("Points: 81 values, expected 84"));
  const std::string lzma = mbi::test::slurp(data("box-meshio-zlib.vtu"));
  std::string l = lzma;
  l.replace(l.find("vtkZLibDataCompressor"), 21, "vtkLZMADataCompressor");
  CHECK_THAT(message(l), Catch::Contains("compressor vtkLZMADataCompressor not supported"));
  // a zlib header claiming more than its block can hold
  std::string z = lzma;
  const std::size_t at = z.find("format=\"binary\">") + 17;
  z[at + 2] = 'B';
  CHECK_THAT(message(z), Catch::Contains("x.vtu:"));
}

TEST_CASE("pvd: datasets sorted by timestep, names relative to the collection", "[io][vtu]") {
  const std::vector<PvdEntry> e = read_pvd(data("twist.pvd"));
  REQUIRE(e.size() == 3);
  CHECK(e[0].time == 0.5);
  CHECK(e[2].time == 1.5);
  CHECK(e[1].file == data("twist_0001.vtu"));
  CHECK(e[1].line == 5);
  const std::string two = "<VTKFile type=\"Collection\"><Collection>\n<DataSet timestep=\"2\" file=\"b.vtu\"/>\n"
                          "<DataSet timestep=\"1\" file=\"a.vtu\"/>\n</Collection></VTKFile>";
  const std::vector<PvdEntry> s = parse_pvd(two, "dir/c.pvd");
  CHECK(s[0].file == fs::path("dir/a.vtu"));
  CHECK(s[0].line == 3);
  CHECK_THROWS_WITH(parse_pvd("<VTKFile type=\"Collection\"><Collection>\n<DataSet timestep=\"1\" file=\"a\"/>\n"
                              "<DataSet timestep=\"1\" file=\"b\"/></Collection></VTKFile>", "c.pvd"),
                    Catch::Contains("c.pvd:3: two DataSets of timestep 1"));
  CHECK_THROWS_WITH(parse_pvd("<VTKFile type=\"Collection\"><Collection>\n<DataSet part=\"1\" file=\"a\"/>"
                              "</Collection></VTKFile>", "c.pvd"),
                    Catch::Contains("c.pvd:2: DataSet of part 1"));
}

TEST_CASE("MDD: written, read back, shorter when fewer frames come, Blender's rest frame skipped", "[io][mdd]") {
  TempDir dir("vtu");
  const std::vector<Eigen::MatrixXd> f = twist_frames();
  {
    MddWriter w(dir / "a.mdd", 27, {0.0f, 0.5f, 1.0f});
    for (const auto& x : f) w.append(x);
    w.finish();
  }
  const PointCache a = read_mdd(dir / "a.mdd");
  REQUIRE(a.frames.size() == 3);
  CHECK(a.times == std::vector<float>{0.0f, 0.5f, 1.0f});
  CHECK((a.frames[2] - f[2]).cwiseAbs().maxCoeff() < 1e-6);
  {  // two of three frames: the file says two
    MddWriter w(dir / "b.mdd", 27, {0.0f, 0.5f, 1.0f});
    w.append(f[0]);
    w.append(f[1]);
    w.finish();
  }
  const PointCache b = read_mdd(dir / "b.mdd");
  REQUIRE(b.frames.size() == 2);
  CHECK(b.frames[1] == a.frames[1]);
  CHECK(b.times == std::vector<float>{0.0f, 0.5f});
  CHECK(fs::file_size(dir / "b.mdd") == 8 + 2 * 4 + 2 * 27 * 12);
  {  // destroyed before finish(): nothing left
    MddWriter w(dir / "c.mdd", 27, {0.0f});
    w.append(f[0]);
  }
  CHECK(!fs::exists(dir / "c.mdd"));
  CHECK(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator()) == 2);
  const PointCache blender = read_mdd(data("twist-blender.mdd"));
  REQUIRE(blender.frames.size() == 3);
  CHECK((blender.frames[0] - f[0]).cwiseAbs().maxCoeff() < 1e-6);
  CHECK(blender.times == std::vector<float>{0.5f, 1.0f, 1.5f});
}

TEST_CASE("point caches a frame at a time: the same frames as read whole", "[io][mdd]") {
  for (const char* name : {"twist.pc2", "twist-blender.mdd"}) {
    INFO(name);
    PointCacheReader r(data(name));
    const PointCache whole = fs::path(name).extension() == ".pc2" ? read_pc2(data(name)) : read_mdd(data(name));
    REQUIRE(r.frames() == 3);
    REQUIRE(r.points() == 27);
    for (int k = 2; k >= 0; --k) CHECK(r.frame(k) == whole.frames[static_cast<std::size_t>(k)]);
    CHECK_THROWS_WITH(r.frame(3), Catch::Contains("frame 3 of 3"));
  }
  TempDir dir("vtu");
  std::string cut = mbi::test::slurp(data("twist.pc2"));
  cut.resize(cut.size() - 4);
  mbi::test::write_text(dir / "cut.pc2", cut);
  CHECK_THROWS_WITH(PointCacheReader(dir / "cut.pc2"), Catch::Contains("cut.pc2: header says 27 points x 3 samples (1004 bytes) but the file has 1000 (truncated?)"));
  std::string nan = mbi::test::slurp(data("twist.pc2"));
  const float q = std::numeric_limits<float>::quiet_NaN();
  std::memcpy(nan.data() + 32 + 2 * 27 * 12 + 5 * 12 + 4, &q, 4);
  mbi::test::write_text(dir / "nan.pc2", nan);
  PointCacheReader r(dir / "nan.pc2");
  CHECK_NOTHROW(r.frame(1));
  CHECK_THROWS_WITH(r.frame(2), Catch::Contains("nan.pc2: frame 2: point 5: non-finite coordinate"));
}

TEST_CASE("trajectories: pattern, glob, collection and caches give the same poses", "[io][trajectory]") {
  const std::vector<Eigen::MatrixXd> f = twist_frames();
  for (const std::string& spec : {data("twist_%04d.txt").string(), data("twist_*.txt").string(), data("twist.pvd").string(),
                                 data("twist_%04d.vtu").string(), data("twist_000[0-2].vtu").string()}) {
    INFO(spec);
    CHECK(Trajectory::names_trajectory(spec));
    Trajectory t(spec);
    REQUIRE(t.frames() == 3);
    for (int k = 0; k < 3; ++k) CHECK((t.read(k) - f[static_cast<std::size_t>(k)]).cwiseAbs().maxCoeff() < 1e-11);
  }
  Trajectory pvd(data("twist.pvd").string());
  CHECK(pvd.times() == std::vector<double>{0.5, 1.0, 1.5});
  CHECK(pvd.files().size() == 4);
  CHECK_THAT(pvd.where(1), Catch::Contains("frame 1: ") && Catch::Contains("twist_0001.vtu"));
  for (const char* name : {"twist.pc2", "twist-blender.mdd"}) {
    Trajectory t(data(name).string());
    REQUIRE(t.frames() == 3);
    CHECK((t.read(1) - f[1]).cwiseAbs().maxCoeff() < 1e-6);
  }
  CHECK(Trajectory(data("twist.pc2").string()).pc2_timing() == std::pair{1.0f, 1.0f});
  CHECK(Trajectory(data("twist-blender.mdd").string()).times() == std::vector<double>{0.5, 1.0, 1.5});
  CHECK(!Trajectory::names_trajectory(data("twist_0001.vtu").string()));
  CHECK(Trajectory(data("twist_0001.vtu").string()).frames() == 1);
}

TEST_CASE("trajectories: numbering from 1, natural order, and what is refused", "[io][trajectory]") {
  TempDir dir("vtu");
  for (int k : {1, 2, 10}) write_points(dir / ("p_" + std::to_string(k) + ".txt"), Eigen::MatrixXd::Constant(2, 3, k));
  Trajectory g((dir / "p_*.txt").string());  // 1, 2, 10: not 1, 10, 2
  REQUIRE(g.frames() == 3);
  CHECK(g.read(2)(0, 0) == 10);
  Trajectory p((dir / "p_%d.txt").string());  // from 1 (no 0) up to the first gap
  REQUIRE(p.frames() == 2);
  CHECK(p.read(1)(0, 0) == 2);
  CHECK_THROWS_WITH(Trajectory((dir / "q_%04d.txt").string()), Catch::Contains("neither") && Catch::Contains("q_0000.txt"));
  CHECK_THROWS_WITH(Trajectory((dir / "q_*.txt").string()), Catch::Contains("no file matches"));
  CHECK_THROWS_WITH(Trajectory((dir / "p_%4d.txt").string()), Catch::Contains("one %d or %0Nd"));
  CHECK_THROWS_WITH(Trajectory((dir / "p_%d_%d.txt").string()), Catch::Contains("one %d or %0Nd"));
  CHECK_THROWS_WITH(Trajectory((dir / "%d/p.txt").string()), Catch::Contains("in the file name"));
  mbi::test::write_text(dir / "m.pvd", "<VTKFile type=\"Collection\"><Collection>\n"
                                       "<DataSet timestep=\"0\" file=\"p_1.txt\"/>\n"
                                       "<DataSet timestep=\"1\" file=\"gone.vtu\"/>\n</Collection></VTKFile>\n");
  CHECK_THROWS_WITH(Trajectory((dir / "m.pvd").string()), Catch::Contains("m.pvd:3: frame 1: ") && Catch::Contains("gone.vtu does not exist"));
  mbi::test::write_text(dir / "p_3.txt", "1 2 3\nx 2 3\n");
  Trajectory bad((dir / "p_%d.txt").string());
  REQUIRE(bad.frames() == 3);
  CHECK_THROWS_WITH(bad.read(2), Catch::StartsWith("frame 2: ") && Catch::Contains("p_3.txt:2"));
}

TEST_CASE("point data: fields of a raw appended .vtu and a legacy .vtk, and positions displaced by one", "[io][vtu]") {
  TempDir dir("vtu_fields");
  // one tetrahedron; appended raw data (UInt32 headers): points, then the field "u" (4 x 3)
  const double P[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  const double U[12] = {0.5, 0, 0, 0, 0.25, 0, 0, 0, -1, 1e-3, 2e-3, 3e-3};
  std::string raw = "_";
  for (const double* a : {P, U}) {
    const std::uint32_t bytes = 96;
    raw.append(reinterpret_cast<const char*>(&bytes), 4).append(reinterpret_cast<const char*>(a), 96);
  }
  std::ofstream(dir / "t.vtu", std::ios::binary)
      << "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\" "
         "header_type=\"UInt32\">\n<UnstructuredGrid>\n<Piece NumberOfPoints=\"4\" NumberOfCells=\"1\">\n"
         "<PointData><DataArray type=\"Float64\" Name=\"u\" NumberOfComponents=\"3\" format=\"appended\" offset=\"100\"/>"
         "</PointData>\n<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"appended\" offset=\"0\"/>"
         "</Points>\n<Cells><DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">0 1 2 3</DataArray>"
         "<DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">4</DataArray>"
         "<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">10</DataArray></Cells>\n</Piece>\n</UnstructuredGrid>\n"
         "<AppendedData encoding=\"raw\">"
      << raw << "</AppendedData>\n</VTKFile>\n";
  // the same as legacy VTK: SCALARS with a lookup table, then VECTORS
  std::ofstream(dir / "t.vtk") << "# vtk DataFile Version 3.0\nt\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n"
                                  "0 0 0 1 0 0 0 1 0 0 0 1\nCELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\nCELL_DATA 1\n"
                                  "SCALARS id int 1\nLOOKUP_TABLE default\n7\nPOINT_DATA 4\nSCALARS T float\n"
                                  "LOOKUP_TABLE default\n1 2 3 4\nVECTORS u double\n"
                                  "0.5 0 0 0 0.25 0 0 0 -1 1e-3 2e-3 3e-3\n";
  const Eigen::MatrixXd rest = Eigen::Map<const Eigen::Matrix<double, 4, 3, Eigen::RowMajor>>(P);
  const Eigen::MatrixXd u = Eigen::Map<const Eigen::Matrix<double, 4, 3, Eigen::RowMajor>>(U);
  for (const char* name : {"t.vtu", "t.vtk"}) {
    INFO(name);
    const PointData d = read_point_data(dir / name);
    CHECK(d.P == rest);
    const PointField& field = d.fields.back();
    CHECK(field.name == "u");
    CHECK(field.values == u);
    CHECK(read_positions(dir / name, "u") == rest + u);
    CHECK(read_positions(dir / name, "") == rest);
    try {
      read_positions(dir / name, "v");
      FAIL("no error");
    } catch (const Error& e) {
      CHECK_THAT(e.what(), Catch::Contains(name) && Catch::Contains("no point field 'v'"));
    }
  }
  CHECK(read_point_data(dir / "t.vtk").fields.size() == 2);  // T and u; the cell data is not a point field
  CHECK_THROWS_WITH(read_positions(dir / "t.vtk", "T"), Catch::Contains("point field 'T': 4 x 1 values"));
  CHECK_THROWS_WITH(read_point_data(data("twist.pc2")), Catch::Contains("point fields are read from .vtu and .vtk files"));
}
