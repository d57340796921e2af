#pragma once
// Node positions as the simulator's flat vectors and back (3-D, node-major: x0 y0 z0 x1 ...).
#include <Eigen/Core>

namespace mbi::test {

inline Eigen::VectorXd flat(const Eigen::MatrixXd& X) {  // n x 3 -> 3n
  Eigen::VectorXd q(X.size());
  for (Eigen::Index i = 0; i < X.rows(); ++i) q.segment<3>(3 * i) = X.row(i).transpose();
  return q;
}

inline Eigen::MatrixXd unflat(const Eigen::VectorXd& q) {  // 3n -> n x 3
  Eigen::MatrixXd X(q.size() / 3, 3);
  for (Eigen::Index i = 0; i < X.rows(); ++i) X.row(i) = q.segment<3>(3 * i).transpose();
  return X;
}

}  // namespace mbi::test
