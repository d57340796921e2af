#include "pictures.hpp"

#include "crease_pictures.hpp"
#include "picture_colliders.hpp"

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
namespace {

const Eigen::Vector3d kModelColor{0.85, 0.62, 0.35};  // the renderers' default

}  // namespace

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
    throw Error(m.dense_name + ": a " + std::to_string(m.image->width) + " x " +
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
  if (sc.output.creases) creases_ = std::make_unique<pipeline::Creases>(m.U, m.T);
  if (context_ && !creases_) {
    renderer_ = std::make_unique<gpu::Renderer>(*context_);
    renderer_->set_faces(m.dense.F);
  }
}

Pictures3D::~Pictures3D() = default;

const char* Pictures3D::renderer() const { return renderer_ ? "gpu" : "cpu"; }

void Pictures3D::add(int f, pipeline::FramePipeline& pipe, const std::vector<interp::BezierPoints>& panels) {
  const Eigen::MatrixXd& X = pipe.control_positions();
  if (X.cols() != 3) throw Error("3D pictures need 3D control positions");
  std::vector<Eigen::VectorXd> jumps;
  if (creases_)
    for (pipeline::Method k : picture_methods(pipe.method())) jumps.push_back(creases_->face_jumps(pipe, k));
  if (!stored_) stored_ = std::make_unique<io::ScratchFile>(dir_, "pictures");
  // one record: frame, panel count, the time (the colliders' pose), then each panel's rows,
  // columns and values
  const long at = stored_->size();
  const double time = picture_time(pipe);
  try {
    const std::int64_t head[2] = {f, static_cast<std::int64_t>(panels.size())};
    stored_->append(head, sizeof head);
    stored_->append(&time, sizeof time);
    for (size_t k = 0; k < panels.size(); ++k) {
      const interp::BezierPoints& B = panels[k];
      const std::int64_t shape[2] = {B.rows(), B.cols()};
      stored_->append(shape, sizeof shape);
      stored_->append(B.data(), static_cast<std::size_t>(B.size()) * sizeof(double));
      if (creases_) stored_->append(jumps[k].data(), static_cast<std::size_t>(jumps[k].size()) * sizeof(double));
    }
  } catch (...) {
    stored_->truncate(at);
    throw;
  }
  last_at_ = at;
  lo_before_ = lo_;
  hi_before_ = hi_;
  top_before_ = top_;
  near_before_ = near_;
  for (const Eigen::VectorXd& j : jumps)
    if (j.size()) top_ = std::max(top_, j.maxCoeff());
  lo_ = lo_.cwiseMin(X.colwise().minCoeff().transpose());
  hi_ = hi_.cwiseMax(X.colwise().maxCoeff().transpose());
  near_.extend(near_bounds(picture_colliders(pipe), time, Eigen::AlignedBox3d(lo_, hi_)));
}

void Pictures3D::discard_last() {
  if (!stored_) return;
  stored_->truncate(last_at_);
  lo_ = lo_before_;
  hi_ = hi_before_;
  top_ = top_before_;
  near_ = near_before_;
}

int Pictures3D::read_frame(long& at, double& time, std::vector<interp::BezierPoints>& panels,
                           std::vector<Eigen::VectorXd>& jumps) const {
  std::int64_t head[2];
  stored_->read(at, head, sizeof head);
  at += sizeof head;
  stored_->read(at, &time, sizeof time);
  at += sizeof time;
  panels.resize(static_cast<std::size_t>(head[1]));
  jumps.resize(creases_ ? panels.size() : 0);
  for (size_t k = 0; k < panels.size(); ++k) {
    interp::BezierPoints& B = panels[k];
    std::int64_t shape[2];
    stored_->read(at, shape, sizeof shape);
    at += sizeof shape;
    B.resize(shape[0], shape[1]);
    const std::size_t bytes = static_cast<std::size_t>(B.size()) * sizeof(double);
    stored_->read(at, B.data(), bytes);
    at += static_cast<long>(bytes);
    if (!creases_) continue;
    jumps[k].resize(creases_->faces());
    const std::size_t jb = static_cast<std::size_t>(jumps[k].size()) * sizeof(double);
    stored_->read(at, jumps[k].data(), jb);
    at += static_cast<long>(jb);
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
  // the model over the run, and the colliders near it (a collider far around it or a plane does
  // not move the camera)
  Eigen::AlignedBox3d framed(lo_, hi_);
  if (!near_.isEmpty()) framed.extend(near_);
  Eigen::MatrixXd corners(2, 3);
  corners.row(0) = framed.min().transpose();
  corners.row(1) = framed.max().transpose();
  raster::View view = raster::frame_points(corners, -(0.75 * front + 0.6 * side + 0.45 * up), up);
  view.bounds_min = framed.min();
  view.bounds_max = framed.max();
  const int h = 480;
  const int w = std::clamp(static_cast<int>(h * raster::view_aspect(view)), 160, 960);
  // the GPU renderer draws from the evaluator's buffers: the run's evaluator is the GPU's
  auto* gpu = renderer_ ? dynamic_cast<gpu::GpuEvaluator*>(&pipe.evaluator()) : nullptr;
  const std::vector<pipeline::Collider> colliders = picture_colliders(pipe);
  Eigen::MatrixXd V;
  std::vector<interp::BezierPoints> frame;
  std::vector<Eigen::VectorXd> jumps;
  for (long at = 0; at < stored_->size();) {
    double time = 0;
    const int f = read_frame(at, time, frame, jumps);
    const std::vector<raster::Solid> solids = picture_solids(colliders, time, view);
    std::vector<io::Image> panels;
    for (size_t k = 0; k < frame.size(); ++k) {
      const interp::BezierPoints& B = frame[k];
      if (creases_) {
        panels.push_back(crease_panel(pipe, B, jumps[k], view, w, h));
      } else if (gpu) {
        gpu->evaluate(B, true);
        panels.push_back(renderer_->render(*gpu, view, w, h, kModelColor, nullptr, nullptr, solids));
      } else {
        interp::evaluate<double>(B, pipe.embedding(), V);
        panels.push_back(raster::render_mesh(V, m_.dense.F, view, w, h, kModelColor, solids));
      }
    }
    io::Image picture = raster::side_by_side(panels);
    if (creases_) picture = stack(picture, crease_legend(picture.width, pipeline::crease_scale(top_)));
    io::write_png(io::frame_path(dir_ / "frame", f, ".png"), picture);
  }
}

io::Image Pictures3D::crease_panel(pipeline::FramePipeline& pipe, const interp::BezierPoints& B,
                                   const Eigen::VectorXd& jumps, const raster::View& view, int w, int h) const {
  Eigen::MatrixXd V;
  interp::evaluate<double>(B, pipe.embedding(), V);
  const Eigen::VectorXd v = creases_->point_values(pipe.embedding(), jumps);
  const double top = pipeline::crease_scale(top_);
  Eigen::MatrixXd C(v.size(), 3);
  for (Eigen::Index q = 0; q < v.size(); ++q) C.row(q) = pipeline::crease_color(v(q) / top).transpose();
  return render_colored(V, m_.dense.F, C, view, w, h);
}

}  // namespace mbi::scenes
