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
#include <cstdint>

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

void Pictures3D::add(int f, const Eigen::MatrixXd& X, const std::vector<interp::BezierPoints>& panels) {
  if (X.cols() != 3) throw SceneError("3D pictures need 3D control positions");
  if (!stored_) stored_ = std::make_unique<io::ScratchFile>(dir_, "pictures");
  // one record: frame, panel count, then each panel's rows, columns and values
  const long at = stored_->size();
  try {
    const std::int64_t head[2] = {f, static_cast<std::int64_t>(panels.size())};
    stored_->append(head, sizeof head);
    for (const interp::BezierPoints& B : panels) {
      const std::int64_t shape[2] = {B.rows(), B.cols()};
      stored_->append(shape, sizeof shape);
      stored_->append(B.data(), static_cast<std::size_t>(B.size()) * sizeof(double));
    }
  } catch (...) {
    stored_->truncate(at);
    throw;
  }
  last_at_ = at;
  lo_before_ = lo_;
  hi_before_ = hi_;
  lo_ = lo_.cwiseMin(X.colwise().minCoeff().transpose());
  hi_ = hi_.cwiseMax(X.colwise().maxCoeff().transpose());
}

void Pictures3D::discard_last() {
  if (!stored_) return;
  stored_->truncate(last_at_);
  lo_ = lo_before_;
  hi_ = hi_before_;
}

int Pictures3D::read_frame(long& at, std::vector<interp::BezierPoints>& panels) const {
  std::int64_t head[2];
  stored_->read(at, head, sizeof head);
  at += sizeof head;
  panels.resize(static_cast<std::size_t>(head[1]));
  for (interp::BezierPoints& B : panels) {
    std::int64_t shape[2];
    stored_->read(at, shape, sizeof shape);
    at += sizeof shape;
    B.resize(shape[0], shape[1]);
    const std::size_t bytes = static_cast<std::size_t>(B.size()) * sizeof(double);
    stored_->read(at, B.data(), bytes);
    at += static_cast<long>(bytes);
  }
  return static_cast<int>(head[0]);
}

void Pictures3D::write(pipeline::FramePipeline& pipe) {
  if (!stored_ || stored_->size() == 0) return;
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
  std::vector<interp::BezierPoints> frame;
  for (long at = 0; at < stored_->size();) {
    const int f = read_frame(at, frame);
    std::vector<io::Image> panels;
    for (const interp::BezierPoints& B : frame) {
      if (gpu) {
        gpu->evaluate(B, true);
        panels.push_back(renderer_->render(*gpu, view, w, h));
      } else {
        interp::evaluate<double>(B, pipe.embedding(), V);
        panels.push_back(raster::render_mesh(V, m_.dense.F, view, w, h));
      }
    }
    io::write_png(io::frame_path(dir_ / "frame", f, ".png"), raster::side_by_side(panels));
  }
}

}  // namespace mbi::scenes
