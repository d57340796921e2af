// Animation output: frame sequences of surfaces (one file a frame).
#include "surface.hpp"

#include <cstdio>

namespace mbi::io {

using detail::fail;
using std::filesystem::path;

path frame_path(const path& base, int frame, const std::string& ext, int digits) {
  if (frame < 0) fail(base, 0, "negative frame number " + std::to_string(frame));
  if (digits < 1 || digits > 12) fail(base, 0, "frame digits must be in [1, 12]");
  char num[32];
  std::snprintf(num, sizeof num, "_%0*d", digits, frame);
  path p = base;
  p += num;
  p += ext;
  return p;
}

path write_frame(const path& base, int frame, const std::string& ext, const SurfaceMesh& topology,
                 const Eigen::Ref<const Eigen::MatrixXd>& V, Encoding encoding,
                 const Eigen::Ref<const Eigen::MatrixXd>& N) {
  const path p = frame_path(base, frame, ext);
  const std::string e = lower_extension(p);
  if (e != ".obj" && e != ".ply") fail(p, 0, "frame sequences are .obj or .ply");
  const Eigen::Index n = topology.V.rows() > 0 ? topology.V.rows() : V.rows();
  if (V.rows() != n || V.cols() != 3)
    fail(p, 0, "frame positions must be " + std::to_string(n) + " x 3, got " +
                   std::to_string(V.rows()) + " x " + std::to_string(V.cols()));
  detail::write_surface_positions(p, topology, V, N, encoding);
  return p;
}

}  // namespace mbi::io
