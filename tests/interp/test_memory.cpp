// The memory estimate (mbi/interp/memory.hpp) against the factor that the precompute builds, on
// meshes small enough for CI: an upper bound of the factor's entries and of the bytes the solver
// keeps, not far above them; the refusal and its message; memory sizes as the command line gives
// them.
#include <mbi/interp/memory.hpp>

#include <catch2/catch.hpp>

#include "test_support.hpp"

#include <mbi/error.hpp>

using namespace mbi::interp;

TEST_CASE("memory estimate: an upper bound of the factor's entries and kept bytes, within 2x", "[memory]") {
  struct Case {
    const char* name;
    mbi::test::Mesh mesh;
    bool large = false;  ///< CHOLMOD only (Eigen's simplicial factor takes seconds there)
  };
  mbi::test::Mesh jittered = mbi::test::box_tet_mesh(9, 8, 7);
  mbi::test::jitter(jittered, 0.2, 1.0 / 9, 5);
  mbi::test::Mesh flat = mbi::test::square_tri_mesh(40, 30);
  mbi::test::jitter(flat, 0.2, 1.0 / 40, 6);
  const std::vector<Case> cases{{"Kuhn box 6x5x4", mbi::test::box_tet_mesh(6, 5, 4)},
                                {"jittered box 9x8x7", jittered},
                                {"Kuhn box 15x15x14: METIS beside AMD", mbi::test::box_tet_mesh(15, 15, 14), true},
                                {"jittered 2D 40x30", flat}};
  std::vector<Factorization> kinds{Factorization::Eigen};
  if (cholmod_available()) kinds.push_back(Factorization::Cholmod);
  for (const Case& c : cases)
    for (Factorization f : kinds)
      for (bool pin : {false, true}) {
        if (c.large && (f == Factorization::Eigen || pin)) continue;
        Options o;
        o.factorization = f;
        o.pin_boundary = pin;
        o.solve_path = SolvePath::Sparse;
        CAPTURE(c.name, kFactorizationNames.name(f), pin);
        const MemoryEstimate e = estimate_memory(c.mesh.U, c.mesh.T, 1000, o);
        const ModifiedBI mbi(c.mesh.U, c.mesh.T, o);
        CAPTURE(e.factor_nonzeros, mbi.factor_nonzeros(), e.ordering, mbi.factorization());
        CHECK(e.unknowns >= mbi.unknowns());
        CHECK(e.unknowns <= mbi.unknowns() + 6);
        CHECK(e.factor_nonzeros >= mbi.factor_nonzeros());
        CHECK(e.factor_nonzeros <= 2 * mbi.factor_nonzeros());
        CHECK(e.factor_bytes >= static_cast<double>(mbi.memory_bytes()) - 16.0 * (c.mesh.U.size() + c.mesh.T.size()));
        CHECK(e.peak_bytes > e.factor_bytes + e.assembly_bytes);
      }
}

TEST_CASE("memory estimate: the dense operator counted when that path is chosen", "[memory]") {
  const mbi::test::Mesh mesh = mbi::test::box_tet_mesh(3, 3, 3);
  Options o;
  o.solve_path = SolvePath::Dense;
  const MemoryEstimate dense = estimate_memory(mesh.U, mesh.T, 0, o);
  o.solve_path = SolvePath::Sparse;
  const MemoryEstimate sparse = estimate_memory(mesh.U, mesh.T, 0, o);
  const double n = static_cast<double>(mesh.U.rows());
  CHECK(dense.dense_operator_bytes == 8.0 * (3 * n - 6) * n);
  CHECK(sparse.dense_operator_bytes == 0.0);
  CHECK(dense.peak_bytes - sparse.peak_bytes == dense.dense_operator_bytes);
  // more dense points, more memory
  CHECK(estimate_memory(mesh.U, mesh.T, 2000000).model_bytes > estimate_memory(mesh.U, mesh.T, 1000000).model_bytes);
}

TEST_CASE("memory estimate: a run over the limit is refused, naming the sizes, and bad input named", "[memory]") {
  const mbi::test::Mesh mesh = mbi::test::box_tet_mesh(6, 5, 4);
  const MemoryEstimate e = estimate_memory(mesh.U, mesh.T, 5000);
  CHECK_THROWS_WITH(check_memory(e, 1024.0 * 1024, "--max-memory", "cage.node"),
                    Catch::StartsWith("cage.node: the modified-BI precompute would need about") &&
                        Catch::Contains("more than the 1 MiB of --max-memory") &&
                        Catch::Contains(std::to_string(e.unknowns) + " unknowns") && Catch::Contains("M nonzeros") &&
                        Catch::Contains("a larger --max-memory"));
  CHECK_NOTHROW(check_memory(e, e.peak_bytes * 1.01, "--max-memory", "cage.node"));
  CHECK_NOTHROW(check_memory(e, 0, "MemAvailable", "cage.node"));  // unknown: no check
  Eigen::MatrixXi bad = mesh.T;
  bad(3, 2) = static_cast<int>(mesh.U.rows());
  CHECK_THROWS_AS(estimate_memory(mesh.U, bad, 0), mbi::Error);
  CHECK_THROWS_WITH(estimate_memory(mesh.U, mesh.T, -1), Catch::Contains("dense_points"));
#ifdef __linux__
  CHECK(available_memory_bytes() > 0);
#endif
}

TEST_CASE("memory sizes: K, M, G, T in powers of 1024, bytes without a unit", "[memory]") {
  const double G = 1024.0 * 1024 * 1024;
  CHECK(parse_memory_size("8G") == 8 * G);
  CHECK(parse_memory_size("1.5GiB") == 1.5 * G);
  CHECK(parse_memory_size("512m") == 512.0 * 1024 * 1024);
  CHECK(parse_memory_size("300MB") == 300.0 * 1024 * 1024);
  CHECK(parse_memory_size("2T") == 2048 * G);
  CHECK(parse_memory_size("2e9") == 2e9);
  CHECK(parse_memory_size("4096B") == 4096.0);
  for (const char* bad : {"", "G", "-1G", "0", "8X", "8 G", "nanG", "1e400", "0.5"}) {
    CAPTURE(bad);
    CHECK_THROWS_WITH(parse_memory_size(bad), Catch::Contains(std::string("'") + bad + "'"));
  }
}
