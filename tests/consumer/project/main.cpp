// A downstream program using the installed mbi::interp: 2D control mesh of two triangles, one
// dense point, an affine deformation. Modified-BI reproduces affine maps exactly (method.md
// fact 8), so the evaluated point must equal A u + b to 1e-12.
#include <mbi/interp.hpp>

#include <cmath>
#include <cstdio>

int main() {
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
  const double err = (out.row(0).transpose() - expected).norm();
  std::printf("consumer: error %.3g\n", err);
  return err < 1e-12 ? 0 : 1;
}
