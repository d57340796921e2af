// `mbi deform --max-memory`: a control mesh over the old cap of 20,000 vertices is refused only
// by the memory estimate, with its sizes named and nothing written; --stats reports the estimate
// beside the factor it bounds.
#include <catch2/catch.hpp>

#include <mbi/generate/procedural.hpp>
#include <mbi/io/io.hpp>

#include "common/run_mbi.hpp"

#include <nlohmann/json.hpp>

#include <fstream>

namespace fs = std::filesystem;
using mbi::test::q;
using mbi::test::run_mbi;
using mbi::test::TempDir;

namespace {
// A box control mesh of nx x ny x nz cells (TetGen files) and a dense box inside it (OBJ); the
// deformed positions are the rest ones.
struct MemoryFiles {
  fs::path control, mesh;
  MemoryFiles(const TempDir& dir, const Eigen::Vector3i& cells) {
    Eigen::MatrixXd U, V;
    Eigen::MatrixXi T, F;
    mbi::generate::box_tets(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 1, 1), cells, U, T);
    mbi::generate::box_surface(Eigen::Vector3d(0.1, 0.1, 0.1), Eigen::Vector3d(0.9, 0.9, 0.9),
                               Eigen::Vector3i(4, 4, 4), V, F);
    control = dir / "cage";
    mbi::io::write_tetgen(control, U, T);
    mesh = dir / "dense.obj";
    mbi::io::write_surface(mesh, V, F);
  }
  std::string args(const fs::path& out) const {
    const std::string node = q(control.string() + ".node");
    return "deform --control " + node + " --deformed " + node + " --mesh " + q(mesh) + " --out " + q(out);
  }
};
}  // namespace

TEST_CASE("mbi deform: over 20,000 control vertices no cap, a refusal by --max-memory naming the sizes", "[cli][memory]") {
  TempDir dir("cli_memory");
  const MemoryFiles f(dir, Eigen::Vector3i(28, 28, 26));  // 29 * 29 * 27 = 22707 vertices
  const fs::path out = dir / "out.obj";
  const auto r = run_mbi(f.args(out) + " --max-memory 1M", dir);
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("the modified-BI precompute would need about") &&
                        Catch::Contains("more than the 1 MiB of --max-memory") &&
                        Catch::Contains("68121 unknowns") && Catch::Contains("M nonzeros"));
  CHECK_THAT(r.err, !Catch::Contains("cap"));
  CHECK_FALSE(fs::exists(out));
  const auto bad = run_mbi(f.args(out) + " --max-memory 8X", dir);
  CHECK(bad.code == 2);
  CHECK_THAT(bad.err, Catch::Contains("--max-memory") && Catch::Contains("'8X'"));
}

TEST_CASE("mbi deform --stats: the memory estimate beside the factor it bounds", "[cli][memory]") {
  TempDir dir("cli_memory_stats");
  const MemoryFiles f(dir, Eigen::Vector3i(8, 8, 8));
  const fs::path out = dir / "out.obj", stats = dir / "s.json";
  const auto r = run_mbi(f.args(out) + " --max-memory 4G --stats " + q(stats), dir);
  REQUIRE(r.code == 0);
  const nlohmann::json j = nlohmann::json::parse(std::ifstream(stats));
  const auto& e = j["memory_estimate"];
  const long long nonzeros = j["factor"]["nonzeros"];
  CHECK(e["factor_nonzeros"].get<long long>() >= nonzeros);
  CHECK(e["factor_nonzeros"].get<long long>() <= 2 * nonzeros);
  CHECK(e["peak_bytes"].get<double>() > e["factor_bytes"].get<double>());
  CHECK(e["unknowns"].get<long long>() == 3 * 9 * 9 * 9);
  CHECK(j["timings_ms"]["solve"].get<double>() > 0);
}
