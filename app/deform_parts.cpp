#include "deform_parts.hpp"

#include <stdexcept>

namespace mbi::cli {

std::string DenseParts::names() const {
  std::string s;
  for (const DensePart& p : parts) s += (s.empty() ? "" : ", ") + p.file;
  return s;
}

namespace {

bool has_normals(const DensePart& p) { return p.surface && p.surface->N.rows() == p.rows && p.surface->N.cols() == 3; }

}  // namespace

bool DensePart::has_normals() const { return mbi::cli::has_normals(*this); }

Eigen::MatrixXd DenseParts::normals() const {
  bool any = false;
  for (const DensePart& p : parts) any |= has_normals(p);
  if (!any || P.cols() != 3) return {};
  Eigen::MatrixXd N(P.rows(), 3);
  for (const DensePart& p : parts) {
    if (has_normals(p)) N.middleRows(p.first, p.rows) = p.surface->N;
    else if (p.surface) N.middleRows(p.first, p.rows) = io::vertex_normals(p.surface->V, p.surface->F);
    else N.middleRows(p.first, p.rows).rowwise() = Eigen::RowVector3d(0, 0, 1);
  }
  return N;
}

io::SurfaceMesh DenseParts::joined() const {
  if (parts.size() == 1 && parts[0].surface) return *parts[0].surface;
  io::SurfaceMesh s;
  s.V = P;
  Eigen::Index faces = 0;
  for (const DensePart& p : parts) faces += p.surface ? p.surface->F.rows() : 0;
  s.F.resize(faces, 3);
  faces = 0;
  for (const DensePart& p : parts) {
    if (!p.surface) continue;
    s.F.middleRows(faces, p.surface->F.rows()) = p.surface->F.array() + static_cast<int>(p.first);
    faces += p.surface->F.rows();
  }
  return s;
}

DenseParts read_dense_parts(const std::vector<std::string>& files) {
  DenseParts d;
  std::vector<Eigen::MatrixXd> points;
  Eigen::Index rows = 0;
  for (const std::string& file : files) {
    DensePart part{.file = file, .surface = std::nullopt, .first = rows, .rows = 0};
    const io::FileFormat* f = io::file_format(file);
    Eigen::MatrixXd P;
    if (f && f->kind == io::FileKind::points) {
      P = io::read_points(file);
    } else {
      part.surface = io::read_surface(file);
      P = part.surface->V;
    }
    if (P.rows() == 0) throw std::runtime_error(file + ": no points");
    if (!points.empty() && P.cols() != points.front().cols())
      throw std::runtime_error(file + ": points have " + std::to_string(P.cols()) + " coordinates, " + files.front() +
                               "'s have " + std::to_string(points.front().cols()));
    part.rows = P.rows();
    rows += P.rows();
    points.push_back(std::move(P));
    d.parts.push_back(std::move(part));
  }
  if (points.empty()) throw std::runtime_error("no dense model given");
  d.P.resize(rows, points.front().cols());
  for (std::size_t k = 0; k < points.size(); ++k) d.P.middleRows(d.parts[k].first, d.parts[k].rows) = points[k];
  return d;
}

}  // namespace mbi::cli
