// Real model (Stanford bunny, 35,947 vertices) in a box cage: embedding, evaluation and the
// affine-reproduction / float-double properties on real data. Needs MBI_MODELS_DIR (SKIPs
// otherwise).
#include "common/skip.hpp"
#include <catch2/catch.hpp>

#include "test_support.hpp"

#include <cstdlib>
#include <fstream>
#include <sstream>

using namespace mbi::interp;
using namespace mbi::test;

namespace {
// Vertex positions of an OBJ file ("v x y z" lines only).
Eigen::MatrixXd read_obj_vertices(const std::string& path) {
  std::ifstream in(path);
  std::vector<double> xyz;
  std::string line;
  while (std::getline(in, line)) {
    if (line.size() < 2 || line[0] != 'v' || line[1] != ' ') continue;
    std::istringstream ss(line.substr(2));
    double x, y, z;
    if (ss >> x >> y >> z) xyz.insert(xyz.end(), {x, y, z});
  }
  Eigen::MatrixXd V(xyz.size() / 3, 3);
  for (Eigen::Index i = 0; i < V.rows(); ++i) V.row(i) << xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2];
  return V;
}
}  // namespace

TEST_CASE("bunny in a box cage: embedding, twist, float vs double", "[models]") {
  const std::string dir = mbi::test::models_dir_or_skip().string();
  const Eigen::MatrixXd P = read_obj_vertices(std::string(dir) + "/stanford-bunny.obj");
  REQUIRE(P.rows() == 35947);
  // cage: bounding box grown by 5%, 5x5x5 cells
  const Eigen::RowVector3d lo = P.colwise().minCoeff(), hi = P.colwise().maxCoeff();
  const Eigen::RowVector3d ext = 1.1 * (hi - lo), org = lo - 0.05 * (hi - lo);
  Mesh C = box_tet_mesh(5, 5, 5, ext.transpose());
  C.U.rowwise() += org;
  const Embedding emb = embed(C.U, C.T, P);
  CHECK(emb.outside.empty());
  CHECK((embedded_positions(C.U, C.T, emb) - P).cwiseAbs().maxCoeff() < 1e-12 * ext.maxCoeff());
  const ModifiedBI mbi(C.U, C.T);
  // affine cage motion: the bunny follows it exactly (fact 8)
  const Eigen::Matrix3d A = Eigen::Matrix3d::Identity() + 0.3 * random_matrix(3, 3, 60);
  const Eigen::MatrixXd XA = C.U * A.transpose();
  Eigen::MatrixXd pa;
  evaluate<double>(mbi.bezier(XA, mbi.solve(XA)), emb, pa);
  CHECK(((P * A.transpose()) - pa).cwiseAbs().maxCoeff() < 1e-9 * ext.maxCoeff());
  // a smooth twist of the cage: float and double agree to 1e-5 relative
  Eigen::MatrixXd Ur = C.U.rowwise() - org;  // twist about the cage's x axis
  const Eigen::MatrixXd X = twist_bend(Ur, M_PI / 3, 0.1).rowwise() + org;
  const BezierPoints B = mbi.bezier(X, mbi.solve(X));
  Eigen::MatrixXd pd;
  Eigen::MatrixXf pf;
  evaluate<double>(B, emb, pd);
  evaluate<float>(B, emb, pf);
  CHECK(pd.allFinite());
  CHECK((pf.cast<double>() - pd).cwiseAbs().maxCoeff() < 1e-5 * pd.cwiseAbs().maxCoeff());
  // modified-BI is smoother than BI across the cage's faces on this frame
  const DiscontinuityTable t = discontinuity_table(mbi, X, mbi.solve(X));
  CHECK(t.ratio.mean > 10);
}
