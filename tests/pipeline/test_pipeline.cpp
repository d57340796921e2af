// The frame pipeline against the library calls it wraps, wired by hand here (independent path):
// every driver, both methods, the CPU evaluator in double and float, normals, failures.
#include <catch2/catch.hpp>

#include <mbi/interp.hpp>
#include <mbi/pipeline/frame_pipeline.hpp>

#include "common/grid_meshes.hpp"

#include <algorithm>
#include <random>
#include <string>

using namespace mbi;
using pipeline::FramePipeline;
using pipeline::Method;

namespace {

test::Mesh bar() { return test::box_tet_mesh(6, 2, 2, Eigen::Vector3d(3, 1, 1)); }

// Random points inside the box (rest coordinates).
Eigen::MatrixXd points_in(const Eigen::MatrixXd& U, int p, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(0.02, 0.98);
  const Eigen::RowVectorXd lo = U.colwise().minCoeff(), hi = U.colwise().maxCoeff();
  Eigen::MatrixXd P(p, U.cols());
  for (int i = 0; i < p; ++i)
    for (Eigen::Index c = 0; c < U.cols(); ++c) P(i, c) = lo(c) + uni(rng) * (hi(c) - lo(c));
  return P;
}

double max_abs(const Eigen::MatrixXd& A) { return A.size() ? A.cwiseAbs().maxCoeff() : 0.0; }

}  // namespace

TEST_CASE("pipeline: given positions, modified-BI equals the library calls by hand", "[pipeline]") {
  const test::Mesh m = bar();
  const Eigen::MatrixXd P = points_in(m.U, 500, 3);
  const Eigen::MatrixXd X = test::twist_bend(m.U, 1.2, 0.3);
  FramePipeline pipe(m.U, m.T, interp::embed(m.U, m.T, P),
                     std::make_unique<pipeline::GivenDriver>(std::vector<Eigen::MatrixXd>{m.U, X}));
  // frame 0: the rest pose reproduces the points (BI and modified-BI reproduce affine maps)
  REQUIRE(pipe.step().ok);
  CHECK(pipe.frame() == 0);
  CHECK(max_abs(pipe.positions() - P) < 1e-12);
  REQUIRE(pipe.step().ok);
  CHECK(pipe.frame() == 1);

  const interp::ModifiedBI solver(m.U, m.T);
  const interp::VertexMatrices M = solver.solve(X);
  Eigen::MatrixXd expect;
  interp::evaluate<double>(solver.bezier(X, M), interp::embed(m.U, m.T, P), expect);
  CHECK(max_abs(pipe.M() - M) <= 1e-12 * (1 + max_abs(M)));
  CHECK(max_abs(pipe.positions() - expect) < 1e-12);
  CHECK(pipe.timings().solve_ms > 0);
  CHECK(pipe.precompute_ms() > 0);
  // past the end of the sequence the frame fails and the results stay those of frame 1
  const pipeline::FrameResult r = pipe.step();
  CHECK_FALSE(r.ok);
  CHECK(r.frame == 1);
  CHECK_THAT(r.message, Catch::Contains("no control positions for frame 2"));
  CHECK(max_abs(pipe.positions() - expect) < 1e-12);
}

TEST_CASE("pipeline: BI skips the precompute and the solve", "[pipeline]") {
  const test::Mesh m = bar();
  const Eigen::MatrixXd P = points_in(m.U, 300, 5);
  const Eigen::MatrixXd X = test::twist_bend(m.U, 0.8, 0.2);
  auto driver = std::make_unique<pipeline::GivenDriver>(m.U);
  driver->set(X);
  pipeline::PipelineOptions o;
  o.method = Method::BI;
  FramePipeline pipe(m.U, m.T, interp::embed(m.U, m.T, P), std::move(driver), o);
  REQUIRE(pipe.step().ok);
  CHECK(pipe.precompute_ms() == 0);  // no ModifiedBI was built
  CHECK(pipe.timings().solve_ms == 0);
  CHECK(max_abs(pipe.M()) == 0);
  // BI by its definition: sum_k bary_k X(T(e, k))
  const interp::Embedding emb = interp::embed(m.U, m.T, P);
  Eigen::MatrixXd expect = Eigen::MatrixXd::Zero(P.rows(), 3);
  for (int i = 0; i < emb.size(); ++i)
    for (int k = 0; k < 4; ++k) expect.row(i) += emb.bary(i, k) * X.row(m.T(emb.element(i), k));
  CHECK(max_abs(pipe.positions() - expect) < 1e-12);
  // the comparison still gets modified-BI's M on demand, and it differs from BI
  Eigen::MatrixXd mbi;
  pipe.evaluate_with(Method::ModifiedBI, mbi);
  CHECK(pipe.precompute_ms() > 0);
  CHECK(max_abs(mbi - expect) > 1e-4);
  const interp::ModifiedBI solver(m.U, m.T);
  CHECK(max_abs(pipe.modified_bi_M() - solver.solve(X)) < 1e-10);
}

TEST_CASE("pipeline: Phong is the kernel with the closed-form M, no factorisation", "[pipeline][phong]") {
  const test::Mesh m = bar();
  const Eigen::MatrixXd P = points_in(m.U, 400, 9);
  const Eigen::MatrixXd X = test::twist_bend(m.U, 1.1, 0.2);
  auto driver = std::make_unique<pipeline::GivenDriver>(m.U);
  driver->set(X);
  pipeline::PipelineOptions o;
  o.method = Method::Phong;
  FramePipeline pipe(m.U, m.T, interp::embed(m.U, m.T, P), std::move(driver), o);
  CHECK(pipe.phong_precompute_ms() > 0);  // the weights, once, at construction
  REQUIRE(pipe.step().ok);
  CHECK(pipe.precompute_ms() == 0);  // no ModifiedBI was built
  // by hand: interp::Phong's M, Bezier points, evaluation
  const interp::Phong ph(m.U, m.T);
  const interp::VertexMatrices M = ph.M(X);
  CHECK(max_abs(pipe.M() - M) < 1e-14);
  CHECK(max_abs(pipe.phong_M() - M) < 1e-14);
  Eigen::MatrixXd expect;
  interp::evaluate<double>(interp::bezier_points(m.U, m.T, X, M), interp::embed(m.U, m.T, P), expect);
  CHECK(max_abs(pipe.positions() - expect) < 1e-12);
  // it differs from both BI and modified-BI; evaluate_with(Phong) from another method agrees
  Eigen::MatrixXd bi, mbi;
  pipe.evaluate_with(Method::BI, bi);
  pipe.evaluate_with(Method::ModifiedBI, mbi);
  CHECK(pipe.precompute_ms() > 0);
  CHECK(max_abs(bi - expect) > 1e-4);
  CHECK(max_abs(mbi - expect) > 1e-4);
  pipe.set_method(Method::BI);
  CHECK(max_abs(pipe.positions() - bi) < 1e-14);
  Eigen::MatrixXd phong;
  pipe.evaluate_with(Method::Phong, phong);
  CHECK(max_abs(phong - expect) < 1e-12);
  pipe.set_method(Method::Phong);
  CHECK(max_abs(pipe.positions() - expect) < 1e-12);
  // alpha does not change Phong
  pipe.set_alpha(1.0);
  CHECK(max_abs(pipe.positions() - expect) < 1e-12);
}

TEST_CASE("pipeline: BI builds Phong's weights only when asked", "[pipeline][phong]") {
  const test::Mesh m = bar();
  const Eigen::MatrixXd P = points_in(m.U, 100, 2);
  auto driver = std::make_unique<pipeline::GivenDriver>(m.U);
  driver->set(test::twist_bend(m.U, 0.5, 0.1));
  pipeline::PipelineOptions o;
  o.method = Method::BI;
  FramePipeline pipe(m.U, m.T, interp::embed(m.U, m.T, P), std::move(driver), o);
  REQUIRE(pipe.step().ok);
  CHECK(pipe.phong_precompute_ms() == 0);
  CHECK(pipe.phong_M().rows() == m.U.rows() * 3);
  CHECK(pipe.phong_precompute_ms() > 0);
}

TEST_CASE("pipeline: switching the method takes effect on the current frame", "[pipeline]") {
  const test::Mesh m = bar();
  const Eigen::MatrixXd P = points_in(m.U, 200, 7);
  const Eigen::MatrixXd X = test::twist_bend(m.U, 1.0, 0.1);
  auto driver = std::make_unique<pipeline::GivenDriver>(m.U);
  driver->set(X);
  FramePipeline pipe(m.U, m.T, interp::embed(m.U, m.T, P), std::move(driver));
  REQUIRE(pipe.step(false).ok);  // drive + solve, no evaluation yet
  const Eigen::MatrixXd mbi = pipe.positions();  // evaluated on demand
  Eigen::MatrixXd bi;
  pipe.evaluate_with(Method::BI, bi);
  pipe.set_method(Method::BI);
  CHECK(max_abs(pipe.positions() - bi) < 1e-14);
  pipe.set_method(Method::ModifiedBI);
  CHECK(max_abs(pipe.positions() - mbi) < 1e-14);
  // alpha: a different alpha gives a different (still smooth) field
  pipe.set_alpha(1.0);
  CHECK(max_abs(pipe.positions() - mbi) > 1e-6);
  CHECK_THROWS_AS(pipe.set_alpha(0.0), mbi::Error);
}

TEST_CASE("pipeline: the simulator driver steps the simulation it owns", "[pipeline]") {
  const test::Mesh m = bar();
  const Eigen::MatrixXd P = points_in(m.U, 200, 9);
  sim::Parameters sp;
  sp.dt = 0.02;
  const sim::Material mat{1e5, 0.3, 1000};
  auto make_sim = [&] {
    sim::Simulator s(m.U, m.T, mat, sp);
    std::vector<int> left;
    for (int i = 0; i < m.U.rows(); ++i)
      if (m.U(i, 0) < 1e-9) left.push_back(i);
    s.fix(left);
    return s;
  };
  auto driver = std::make_unique<pipeline::SimulatorDriver>(make_sim());
  // a force on the free end from the first step on (first = 0)
  const interp::Embedding tip = interp::embed(m.U, m.T, Eigen::RowVector3d(2.9, 0.5, 0.5));
  driver->add_scripted_force(0, 3, tip.element(0), tip.bary.row(0).transpose(),
                             Eigen::Vector3d(0, 0, -50));
  FramePipeline pipe(m.U, m.T, interp::embed(m.U, m.T, P), std::move(driver));
  REQUIRE(pipe.step().ok);
  CHECK(max_abs(pipe.control_positions() - m.U) == 0);  // frame 0: no step

  // the same simulation by hand
  sim::Simulator ref = make_sim();
  const int h = ref.add_point_force(tip.element(0), tip.bary.row(0).transpose(), Eigen::Vector3d(0, 0, -50));
  double lowest = 0;  // rest: z >= 0
  for (int f = 1; f <= 6; ++f) {
    if (f == 4) ref.remove(h);  // active on frames 0..3
    REQUIRE(ref.step().success);
    REQUIRE(pipe.step().ok);
    CHECK(max_abs(pipe.control_positions() - ref.positions()) == 0);
    lowest = std::min(lowest, pipe.control_positions().col(2).minCoeff());
  }
  CHECK(lowest < -5e-4);  // the force (from frame 1 on: first = 0 applies) bent the bar down
  CHECK(pipe.timings().drive_ms > 0);
  // reset: back to the rest pose
  pipe.reset();
  REQUIRE(pipe.step().ok);
  CHECK(pipe.frame() == 0);
  CHECK(max_abs(pipe.positions() - P) < 1e-12);
}

TEST_CASE("pipeline: handles reach their targets and M comes from the joint solve", "[pipeline]") {
  const test::Mesh m = test::square_tri_mesh(6, 4, Eigen::Vector2d(3, 2));
  const Eigen::MatrixXd P = points_in(m.U, 300, 11);
  const std::vector<int> handles{0, 6, static_cast<int>(m.U.rows()) - 1, 17};
  interp::ControlOptions co;
  Eigen::MatrixXd targets(4, 2);
  for (int k = 0; k < 4; ++k) targets.row(k) = m.U.row(handles[static_cast<size_t>(k)]);
  targets.row(3) += Eigen::RowVector2d(0.4, -0.3);
  auto fn = [&](int frame) -> Eigen::MatrixXd {
    Eigen::MatrixXd t = targets;
    t.row(3) = m.U.row(17) + frame / 2.0 * (targets.row(3) - m.U.row(17));
    return t;
  };
  FramePipeline pipe(m.U, m.T, interp::embed(m.U, m.T, P),
                     std::make_unique<pipeline::HandleDriver>(m.U, m.T, handles, co, fn));
  REQUIRE(pipe.step().ok);
  REQUIRE(pipe.step().ok);
  REQUIRE(pipe.step().ok);  // frame 2: the full displacement
  for (int k = 0; k < 4; ++k)
    CHECK((pipe.control_positions().row(handles[static_cast<size_t>(k)]) - targets.row(k)).norm() < 1e-9);
  CHECK(pipe.timings().solve_ms == 0);  // M came with the positions
  interp::HandleSolver hs(m.U, m.T, handles, co);
  const Eigen::MatrixXd X = hs.solve(targets);
  CHECK(max_abs(pipe.control_positions() - X) < 1e-10);
  CHECK(max_abs(pipe.M() - hs.last_M()) < 1e-8);
  // free vertices moved
  CHECK((pipe.control_positions() - m.U).rowwise().norm().maxCoeff() > 0.1);
}

TEST_CASE("pipeline: float evaluation and normals agree with double", "[pipeline]") {
  const test::Mesh m = bar();
  const Eigen::MatrixXd P = points_in(m.U, 400, 13);
  Eigen::MatrixXd N = Eigen::MatrixXd::Random(P.rows(), 3);
  N.rowwise().normalize();
  const Eigen::MatrixXd X = test::twist_bend(m.U, 1.0, 0.2);
  pipeline::PipelineOptions o;
  o.normals = true;
  auto make = [&](pipeline::Precision p) {
    auto driver = std::make_unique<pipeline::GivenDriver>(m.U);
    driver->set(X);
    return FramePipeline(m.U, m.T, interp::embed(m.U, m.T, P), std::move(driver), o,
                         std::make_unique<pipeline::CpuEvaluator>(p, 1), N);
  };
  FramePipeline d = make(pipeline::Precision::Double), f = make(pipeline::Precision::Float);
  REQUIRE(d.step().ok);
  REQUIRE(f.step().ok);
  const double size = 3.0;
  CHECK(max_abs(d.positions() - f.positions()) < 1e-5 * size);
  CHECK(max_abs(d.normals() - f.normals()) < 1e-5);
  // normals by hand
  const interp::ModifiedBI solver(m.U, m.T);
  Eigen::MatrixXd pos, nrm;
  interp::evaluate<double>(solver.bezier(X, solver.solve(X)), interp::embed(m.U, m.T, P), N, pos, nrm);
  CHECK(max_abs(d.normals() - nrm) < 1e-12);
  CHECK((d.normals().rowwise().norm().array() - 1).abs().maxCoeff() < 1e-12);
}

TEST_CASE("pipeline: inconsistent inputs are refused", "[pipeline]") {
  const test::Mesh m = bar();
  const Eigen::MatrixXd P = points_in(m.U, 10, 1);
  CHECK_THROWS_AS(FramePipeline(m.U, m.T, interp::embed(m.U, m.T, P), nullptr), mbi::Error);
  CHECK_THROWS_WITH(FramePipeline(m.U, m.T, interp::embed(m.U, m.T, P), nullptr), "no driver");
  pipeline::PipelineOptions o;
  o.normals = true;  // but no rest normals
  CHECK_THROWS_AS(FramePipeline(m.U, m.T, interp::embed(m.U, m.T, P),
                                std::make_unique<pipeline::GivenDriver>(m.U), o),
                  mbi::Error);
  auto wrong = std::make_unique<pipeline::GivenDriver>(m.U);
  wrong->set(Eigen::MatrixXd::Zero(3, 3));
  FramePipeline pipe(m.U, m.T, interp::embed(m.U, m.T, P), std::move(wrong));
  CHECK_THROWS_AS(pipe.step(), mbi::Error);
  CHECK_THROWS_AS(pipeline::CpuEvaluator(pipeline::Precision::Double, -1), mbi::Error);
  CHECK(pipeline::parse_method("modified-bi") == Method::ModifiedBI);
  CHECK(pipeline::parse_method("bi") == Method::BI);
  CHECK(pipeline::parse_method("phong") == Method::Phong);
  CHECK_FALSE(pipeline::parse_method("Phong").has_value());
  CHECK(pipeline::all_methods().size() == 3);
  CHECK(std::string(pipeline::method_names()) == "bi, modified-bi, phong");
}
