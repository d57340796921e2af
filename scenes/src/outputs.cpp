#include "outputs.hpp"

#include <mbi/raster/raster.hpp>

namespace fs = std::filesystem;

namespace mbi::scenes {

Outputs::Outputs(const Scene& sc, const SceneModels& m, const fs::path& dir) : sc_(sc), m_(m), dir_(dir) {
  if (sc.output.pc2) pc2_ = std::make_unique<io::Pc2Writer>(dir / "dense.pc2", static_cast<int>(m.dense.V.rows()), 0.0f, 1.0f);
  if (sc.output.mesh_format != MeshFormat::Glb) return;
  if (m.dense_parts.empty()) gltf_.push_back(std::make_unique<io::GltfWriter>(dir / "mesh.glb", m.dense));
  for (std::size_t k = 0; k < m.dense_parts.size(); ++k)
    gltf_.push_back(std::make_unique<io::GltfWriter>(dir / ("mesh" + std::to_string(k + 1) + ".glb"), m.dense_parts[k].surface));
}

namespace {

// The rows of one dense model; its normals only when its file had them.
struct PartRows {
  const io::SurfaceMesh& surface;
  Eigen::MatrixXd V, N;
  std::string base;  // "mesh", or "mesh1", "mesh2", ...
};

std::vector<PartRows> part_rows(const SceneModels& m, const Eigen::MatrixXd& V3, const Eigen::MatrixXd* normals) {
  std::vector<PartRows> parts;
  const Eigen::MatrixXd none;
  if (m.dense_parts.empty()) parts.push_back({m.dense, V3, normals ? *normals : none, "mesh"});
  for (std::size_t k = 0; k < m.dense_parts.size(); ++k) {
    const DensePart& p = m.dense_parts[k];
    const bool n = normals && normals->rows() == V3.rows() && p.surface.N.rows() == p.rows;
    parts.push_back({p.surface, V3.middleRows(p.first, p.rows), n ? normals->middleRows(p.first, p.rows) : none,
                     "mesh" + std::to_string(k + 1)});
  }
  return parts;
}

}  // namespace

void Outputs::frame(int f, const Eigen::MatrixXd& Xc, const Eigen::MatrixXd& dense,
                    const std::vector<const Eigen::MatrixXd*>& shown, bool write_now,
                    const Eigen::MatrixXd* normals) {
  std::vector<fs::path> written;  // this frame's files, removed again if a later write fails
  try {
    if (write_now) {
      if (!gltf_.empty()) append_gltf(f, dense, normals);
      else if (sc_.output.mesh_format != MeshFormat::None)
        for (const fs::path& p : write_mesh(f, dense, normals)) written.push_back(p);
      if (sc_.output.control_vtk) {
        const Eigen::MatrixXd disp = Xc - m_.U;
        written.push_back(io::frame_path(dir_ / "control", f, ".vtk"));
        io::write_vtk(written.back(), Xc, m_.T, disp);
      }
      if (sc_.output.image && !shown.empty() && m_.image) written.push_back(write_picture_2d(f, shown));
    }
    // last: a sample is appended whole or not at all
    if (pc2_) append_pc2(dense);
  } catch (...) {
    std::error_code ec;
    for (const fs::path& p : written) fs::remove(p, ec);
    throw;
  }
}

void Outputs::append_pc2(const Eigen::MatrixXd& dense) {
  if (dense.cols() == 2 && m_.flat_z) {  // a flat model keeps its plane's z, as in its meshes
    flat_.resize(dense.rows(), 3);
    flat_.leftCols(2) = dense;
    flat_.col(2).setConstant(*m_.flat_z);
    pc2_->append(flat_);
  } else {
    pc2_->append(dense);
  }
}

std::vector<fs::path> Outputs::write_mesh(int f, const Eigen::MatrixXd& dense, const Eigen::MatrixXd* normals) {
  const std::string ext = std::string(".") + format_name(sc_.output.mesh_format);
  const io::Encoding enc = sc_.output.mesh_format == MeshFormat::Ply ? io::Encoding::binary : io::Encoding::ascii;
  // 2D: z = 0, or the plane of a flat model; no normals
  Eigen::MatrixXd V3 = Eigen::MatrixXd::Constant(dense.rows(), 3, m_.flat_z.value_or(0.0));
  V3.leftCols(dense.cols()) = dense;
  std::vector<fs::path> written;
  for (const PartRows& p : part_rows(m_, V3, dense.cols() == 3 ? normals : nullptr))
    written.push_back(io::write_frame(dir_ / p.base, f, ext, p.surface, p.V, enc, p.N));
  return written;
}

void Outputs::append_gltf(int f, const Eigen::MatrixXd& dense, const Eigen::MatrixXd* normals) {
  // 2D: z = 0, or the plane of a flat model
  Eigen::MatrixXd V3 = Eigen::MatrixXd::Constant(dense.rows(), 3, m_.flat_z.value_or(0.0));
  V3.leftCols(dense.cols()) = dense;
  const double t = f * sc_.simulation.parameters.dt;
  const std::vector<PartRows> parts = part_rows(m_, V3, dense.cols() == 3 ? normals : nullptr);
  for (std::size_t k = 0; k < parts.size(); ++k) gltf_[k]->append(t, parts[k].V, parts[k].N);
}

fs::path Outputs::write_picture_2d(int f, const std::vector<const Eigen::MatrixXd*>& shown) {
  std::vector<io::Image> panels;
  const int W = m_.image->width, H = m_.image->height;
  const int ow = W * 3 / 2, oh = H * 3 / 2;
  const Eigen::RowVector2d off(W / 4.0, H / 4.0);
  for (const Eigen::MatrixXd* p : shown) {
    const Eigen::MatrixXd Dp = p->rowwise() + off;
    panels.push_back(raster::warp_image(*m_.image, m_.dense.V, Dp, m_.dense.F, ow, oh));
  }
  const fs::path p = io::frame_path(dir_ / "frame", f, ".png");
  io::write_png(p, raster::side_by_side(panels));
  return p;
}

void Outputs::finish() {
  if (pc2_) pc2_->finish();
  for (auto& g : gltf_) g->finish();
}

}  // namespace mbi::scenes
