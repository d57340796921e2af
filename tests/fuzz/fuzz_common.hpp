#pragma once
// Shared by the libFuzzer targets (tests/fuzz/fuzz_*.cpp, docs/hardening.md): what a reader
// may do with any bytes is return a valid result or throw mbi::io::Error. Any other
// exception escapes LLVMFuzzerTestOneInput and libFuzzer reports it; a result that breaks the
// readers' guarantees (mbi/io/parse.hpp) is reported by invariant() as a crash.
#include <mbi/io/parse.hpp>

#include <Eigen/Core>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string_view>

namespace mbi::fuzz {

inline std::string_view bytes(const std::uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

[[noreturn]] inline void broken(const char* what) {
  std::fprintf(stderr, "fuzz invariant broken: %s\n", what);
  std::abort();
}
inline void invariant(bool ok, const char* what) {
  if (!ok) broken(what);
}

/// Positions: finite, at most kMaxCoordinate in magnitude.
inline void check_positions(const Eigen::MatrixXd& P) {
  for (Eigen::Index i = 0; i < P.size(); ++i)
    invariant(std::isfinite(P.data()[i]) && std::abs(P.data()[i]) <= io::kMaxCoordinate,
              "coordinate not finite or above kMaxCoordinate");
}

/// Indices: in [0, n).
inline void check_indices(const Eigen::MatrixXi& E, Eigen::Index n) {
  for (Eigen::Index i = 0; i < E.size(); ++i)
    invariant(E.data()[i] >= 0 && E.data()[i] < n, "index out of range");
}

inline void check_surface(const io::SurfaceMesh& m) {
  invariant(m.V.cols() == 3 || m.V.size() == 0, "V not n x 3");
  check_positions(m.V);
  invariant(m.F.cols() == 3 || m.F.rows() == 0, "F not t x 3");
  check_indices(m.F, m.V.rows());
  invariant(m.N.size() == 0 || (m.N.rows() == m.V.rows() && m.N.cols() == 3), "N shape");
  for (Eigen::Index i = 0; i < m.N.size(); ++i) invariant(std::isfinite(m.N.data()[i]), "N finite");
  for (const auto& p : m.polygons) {
    invariant(p.size() >= 3, "polygon with fewer than 3 corners");
    for (int v : p) invariant(v >= 0 && v < m.V.rows(), "polygon index out of range");
  }
}

inline void check_control(const io::ControlMesh& m) {
  invariant(m.dim() == 2 || m.dim() == 3, "control mesh dimension");
  check_positions(m.U);
  invariant(m.T.cols() == m.dim() + 1, "T columns");
  check_indices(m.T, m.U.rows());
}

}  // namespace mbi::fuzz
