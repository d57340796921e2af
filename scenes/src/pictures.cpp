#include "pictures.hpp"

#include <mbi/gpu/context.hpp>
#include <mbi/gpu/evaluator.hpp>
#include <mbi/gpu/renderer.hpp>
#include <mbi/interp/evaluate.hpp>
#include <mbi/io/parse.hpp>
#include <mbi/io/io.hpp>
#include <mbi/raster/raster.hpp>

#include <Eigen/Geometry>

#include <algorithm>

namespace fs = std::filesystem;

namespace mbi::scenes {

std::vector<pipeline::Method> picture_methods(pipeline::Method method) {
  std::vector<pipeline::Method> panels{pipeline::Method::BI, pipeline::Method::ModifiedBI};
  if (method == pipeline::Method::Phong) panels.insert(panels.begin() + 1, pipeline::Method::Phong);
  return panels;
}

void check_picture_size(const Scene& sc, const SceneModels& m) {
  if (!sc.output.image || !m.image || m.dim() != 2) return;
  const bool pinned = sc.mode == Mode::Drag && sc.interpolation.compare_pinned &&
                      !sc.interpolation.options.pin_boundary;
  const auto panels =
      static_cast<long long>(picture_methods(sc.interpolation.method).size() + (pinned ? 1 : 0));
  const long long ow = static_cast<long long>(m.image->width) * 3 / 2;
  const long long oh = static_cast<long long>(m.image->height) * 3 / 2;
  const long long w = panels * ow + 8 * (panels - 1);
  if (w > io::kMaxImageSide || oh > io::kMaxImageSide)
    throw SceneError(m.dense_name + ": a " + std::to_string(m.image->width) + " x " +
                     std::to_string(m.image->height) + " image makes " + std::to_string(w) + " x " +
                     std::to_string(oh) + " pictures (" + std::to_string(panels) +
                     " panels at 1.5 times its size), more than " + std::to_string(io::kMaxImageSide) +
                     " pixels a side; use a smaller "
                     "image or output.image = false");
}

Pictures3D::Pictures3D(const Scene& sc, const SceneModels& m, const fs::path& dir,
                       std::shared_ptr<gpu::Context> context)
    : sc_(sc), m_(m), dir_(dir), context_(std::move(context)) {
  lo_.setZero();
  hi_.setZero();
  if (m.dim() != 3 || !sc.output.image) return;  // 2D pictures are written as the frames come
  lo_ = m.U.colwise().minCoeff().transpose();
  hi_ = m.U.colwise().maxCoeff().transpose();
  if (context_) {
    renderer_ = std::make_unique<gpu::Renderer>(*context_);
    renderer_->set_faces(m.dense.F);
  }
}

Pictures3D::~Pictures3D() = default;

const char* Pictures3D::renderer() const { return renderer_ ? "gpu" : "cpu"; }

void Pictures3D::add(int f, const Eigen::MatrixXd& X, std::vector<interp::BezierPoints> panels) {
  if (X.cols() != 3) throw SceneError("3D pictures need 3D control positions");
  lo_ = lo_.cwiseMin(X.colwise().minCoeff().transpose());
  hi_ = hi_.cwiseMax(X.colwise().maxCoeff().transpose());
  frames_.push_back({f, std::move(panels)});
}

void Pictures3D::write(pipeline::FramePipeline& pipe) {
  if (frames_.empty()) return;
  const Eigen::Vector3d up = sc_.output.up.normalized();
  Eigen::Vector3d side = up.cross(Eigen::Vector3d::UnitX());
  if (side.norm() < 0.5) side = up.cross(Eigen::Vector3d::UnitY());
  side.normalize();
  const Eigen::Vector3d front = side.cross(up);
  Eigen::MatrixXd corners(2, 3);
  corners.row(0) = lo_.transpose();
  corners.row(1) = hi_.transpose();
  raster::View view = raster::frame_points(corners, -(0.75 * front + 0.6 * side + 0.45 * up), up);
  view.bounds_min = lo_;
  view.bounds_max = hi_;
  const int h = 480;
  const int w = std::clamp(static_cast<int>(h * raster::view_aspect(view)), 160, 960);
  // the GPU renderer draws from the evaluator's buffers: the run's evaluator is the GPU's
  auto* gpu = renderer_ ? dynamic_cast<gpu::GpuEvaluator*>(&pipe.evaluator()) : nullptr;
  Eigen::MatrixXd V;
  for (const Frame& fr : frames_) {
    std::vector<io::Image> panels;
    for (const interp::BezierPoints& B : fr.panels) {
      if (gpu) {
        gpu->evaluate(B, true);
        panels.push_back(renderer_->render(*gpu, view, w, h));
      } else {
        interp::evaluate<double>(B, pipe.embedding(), V);
        panels.push_back(raster::render_mesh(V, m_.dense.F, view, w, h));
      }
    }
    io::write_png(io::frame_path(dir_ / "frame", fr.f, ".png"), raster::side_by_side(panels));
  }
}

}  // namespace mbi::scenes
