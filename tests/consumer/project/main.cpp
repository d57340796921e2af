// A downstream program using the installed libraries (find_package(mbi)):
// 1. mbi::interp: 2D control mesh of two triangles, one dense point, an affine deformation.
//    Modified-BI reproduces affine maps exactly (docs/method.md fact 8): error < 1e-12.
// 2. mbi::pipeline: the README's snippet, verbatim between the markers, on a 3D box of
//    tetrahedra deformed affinely: the dense points follow the affine map to 1e-12.
#include <mbi/interp.hpp>
#include <mbi/pipeline/frame_pipeline.hpp>

#include <Eigen/Geometry>

#include <cmath>
#include <cstdio>

namespace {

double interp_2d() {
  Eigen::MatrixXd U(4, 2);
  U << 0, 0, 1, 0, 1, 1, 0, 1;
  Eigen::MatrixXi T(2, 3);
  T << 0, 1, 2, 0, 2, 3;
  Eigen::Matrix2d A;
  A << 1.5, 0.2, -0.3, 0.8;
  const Eigen::Vector2d b(0.25, -1.0);
  Eigen::MatrixXd X = (U * A.transpose()).rowwise() + b.transpose();
  Eigen::MatrixXd P(1, 2);
  P << 0.3, 0.6;
  const mbi::interp::Embedding emb = mbi::interp::embed(U, T, P);
  const mbi::interp::ModifiedBI solver(U, T);
  const mbi::interp::VertexMatrices M = solver.solve(X);
  Eigen::MatrixXd out;
  mbi::interp::evaluate<double>(solver.bezier(X, M), emb, out);
  const Eigen::Vector2d expected = A * P.row(0).transpose() + b;
  return (out.row(0).transpose() - expected).norm();
}

double pipeline_3d() {
  // a unit cube of 2 x 2 x 2 cells, 6 tetrahedra per cell (Kuhn split)
  const int n = 2;
  auto id = [&](int i, int j, int k) { return (k * (n + 1) + j) * (n + 1) + i; };
  Eigen::MatrixXd U((n + 1) * (n + 1) * (n + 1), 3);
  for (int k = 0; k <= n; ++k)
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) U.row(id(i, j, k)) << double(i) / n, double(j) / n, double(k) / n;
  const int paths[6][2] = {{0, 1}, {0, 2}, {1, 0}, {1, 2}, {2, 0}, {2, 1}};
  Eigen::MatrixXi T(6 * n * n * n, 4);
  int e = 0;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        for (const auto& p : paths) {
          int c[3] = {i, j, k};
          int v[4];
          v[0] = id(c[0], c[1], c[2]);
          for (int s = 0; s < 3; ++s) {
            const int axis = s < 2 ? p[s] : 3 - p[0] - p[1];
            ++c[axis];
            v[s + 1] = id(c[0], c[1], c[2]);
          }
          const Eigen::Vector3d a = U.row(v[1]) - U.row(v[0]), b = U.row(v[2]) - U.row(v[0]),
                                d = U.row(v[3]) - U.row(v[0]);
          if (a.cross(b).dot(d) < 0) std::swap(v[2], v[3]);
          T.row(e++) << v[0], v[1], v[2], v[3];
        }
  Eigen::MatrixXd P(3, 3);
  P << 0.2, 0.3, 0.4, 0.5, 0.5, 0.5, 0.9, 0.1, 0.7;
  Eigen::Matrix3d A;
  A << 1.1, 0.2, 0.0, -0.1, 0.9, 0.3, 0.05, 0.0, 1.2;
  const Eigen::RowVector3d t(0.5, -0.2, 1.0);
  const Eigen::MatrixXd X = (U * A.transpose()).rowwise() + t;

  // --- README snippet (section "Library") ---
  namespace pl = mbi::pipeline;
  // U n x 3 rest control vertices, T m x 4 tetrahedra, P p x 3 dense rest points
  auto driver = std::make_unique<pl::GivenDriver>(U);       // or SimulatorDriver, HandleDriver
  pl::GivenDriver& given = *driver;
  pl::FramePipeline pipe(U, T, mbi::interp::embed(U, T, P), std::move(driver),
                         {.method = pl::Method::ModifiedBI, .interp = {.alpha = 0.1}});
  given.set(X);                                             // your simulator's positions, n x 3
  pipe.step();                                              // drive, solve M, Bezier, evaluate
  const Eigen::MatrixXd& dense = pipe.positions();          // p x 3
  double ms = pipe.timings().total_ms();                    // per phase: drive/solve/bezier/evaluate
  // --- end of README snippet ---

  const Eigen::MatrixXd expected = (P * A.transpose()).rowwise() + t;
  return std::isfinite(ms) ? (dense - expected).cwiseAbs().maxCoeff() : 1.0;
}

}  // namespace

int main() {
  const double e2 = interp_2d(), e3 = pipeline_3d();
  std::printf("consumer: interp 2D error %.3g, pipeline 3D error %.3g\n", e2, e3);
  return e2 < 1e-12 && e3 < 1e-12 ? 0 : 1;
}
