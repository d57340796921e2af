// TetGen's call for the cage's TetGen mesher (see tetrahedralize.hpp).
#include "tetrahedralize.hpp"

#include <tetgen.h>

#include <new>
#include <stdexcept>

namespace mbi::generate::detail {

bool have_tetgen() { return true; }

bool tetrahedralize(const Eigen::MatrixXd& X, const std::vector<std::array<int, 3>>& B,
                    const std::string& switches, Eigen::MatrixXd& points, Eigen::MatrixXi& tets,
                    std::string& why) {
  const int nb = static_cast<int>(X.rows());
  tetgenio in, out;
  in.firstnumber = 0;
  in.numberofpoints = nb;
  in.pointlist = new REAL[static_cast<std::size_t>(3 * nb)];
  for (int v = 0; v < nb; ++v)
    for (int c = 0; c < 3; ++c) in.pointlist[3 * v + c] = X(v, c);
  in.numberoffacets = static_cast<int>(B.size());
  in.facetlist = new tetgenio::facet[B.size()];
  for (std::size_t t = 0; t < B.size(); ++t) {
    tetgenio::facet& f = in.facetlist[t];
    tetgenio::init(&f);
    f.numberofpolygons = 1;
    f.polygonlist = new tetgenio::polygon[1];
    tetgenio::init(&f.polygonlist[0]);
    f.polygonlist[0].numberofvertices = 3;
    f.polygonlist[0].vertexlist = new int[3];
    for (int c = 0; c < 3; ++c) f.polygonlist[0].vertexlist[c] = B[t][static_cast<std::size_t>(c)];
  }
  std::vector<char> sw(switches.begin(), switches.end());
  sw.push_back('\0');
  try {
    ::tetrahedralize(sw.data(), &in, &out);
  } catch (int code) {
    why = "TetGen -" + switches + " failed with code " + std::to_string(code);
    return false;
  } catch (const std::bad_alloc&) {
    why = "TetGen -" + switches + " ran out of memory";
    return false;
  } catch (const std::exception& e) {
    why = "TetGen -" + switches + " failed: " + e.what();
    return false;
  } catch (...) {
    why = "TetGen -" + switches + " failed with an unknown exception";
    return false;
  }
  if (out.numberofpoints <= 0 || out.numberoftetrahedra <= 0 || out.numberofcorners != 4) {
    why = "TetGen -" + switches + " returned no tetrahedra";
    return false;
  }
  points.resize(out.numberofpoints, 3);
  for (int v = 0; v < out.numberofpoints; ++v)
    for (int c = 0; c < 3; ++c) points(v, c) = out.pointlist[3 * v + c];
  tets.resize(out.numberoftetrahedra, 4);
  for (int e = 0; e < out.numberoftetrahedra; ++e)
    for (int c = 0; c < 4; ++c) tets(e, c) = out.tetrahedronlist[4 * e + c];
  return true;
}

}  // namespace mbi::generate::detail
