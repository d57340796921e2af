// The page's model: frames, the two views, pokes (see page_model.hpp).
#include <mbi/web/page_model.hpp>

#include <mbi/base/timer.hpp>
#include <mbi/error.hpp>
#include <mbi/interact/collider.hpp>
#include <mbi/interact/pick.hpp>
#include <mbi/interact/poke.hpp>
#include <mbi/interp/embed.hpp>
#include <mbi/interp/evaluate.hpp>
#include <mbi/pipeline/creases.hpp>

#include <algorithm>
#include <optional>

namespace mbi::web {
namespace {

// The natural period (s) of a poke's spring on the mass it pulls: `mbi view`'s default.
constexpr double kPokePeriod = 0.15;

pipeline::Method method_of(View view) {
  return view == View::BI ? pipeline::Method::BI : pipeline::Method::ModifiedBI;
}

// floats of the doubles a (rows x cols, row-major out)
std::vector<float> floats(const Eigen::MatrixXd& a) {
  std::vector<float> out(static_cast<std::size_t>(a.size()));
  for (Eigen::Index i = 0; i < a.rows(); ++i)
    for (Eigen::Index c = 0; c < a.cols(); ++c) out[static_cast<std::size_t>(i * a.cols() + c)] = static_cast<float>(a(i, c));
  return out;
}

}  // namespace

PageModel::~PageModel() = default;
PageModel::PageModel(PageModel&&) noexcept = default;
PageModel& PageModel::operator=(PageModel&&) noexcept = default;

PageModel::PageModel(Surface dense, pipeline::FramePipeline pipe, std::string description)
    : rest_(std::move(dense)), description_(std::move(description)) {
  pipe_ = std::make_unique<pipeline::FramePipeline>(std::move(pipe));
  sim_ = dynamic_cast<pipeline::SimulatorDriver*>(&pipe_->driver());
  if (!sim_) throw mbi::Error("the page runs simulated scenes only (its pokes pull on the simulation)");
  size_ = (rest_.V.colwise().maxCoeff() - rest_.V.colwise().minCoeff()).norm();
  const interp::Embedding& emb = pipe_->embedding();
  gpu_.elements.assign(emb.element.data(), emb.element.data() + emb.element.size());
  gpu_.bary.assign(4 * gpu_.elements.size(), 0.0f);
  for (Eigen::Index i = 0; i < emb.bary.rows(); ++i)
    for (Eigen::Index k = 0; k < emb.bary.cols(); ++k)
      gpu_.bary[static_cast<std::size_t>(4 * i + k)] = static_cast<float>(emb.bary(i, k));
  gpu_.rest = floats(rest_.V);
  gpu_.rest_bezier = interp::bezier_bi(pipe_->rest_positions(), pipe_->elements());
  step();
}

bool PageModel::step() {
  const pipeline::FrameResult r = pipe_->step(cpu_);
  message_ = r.message;
  fresh_[0] = fresh_[1] = false;
  other_ms_ = 0;
  if (cpu_) {
    const View own = pipe_->method() == pipeline::Method::BI ? View::BI : View::ModifiedBI;
    positions(own);  // the pipeline's evaluation, as floats
    const auto t0 = Clock::now();
    positions(own == View::BI ? View::ModifiedBI : View::BI);
    other_ms_ = ms_since(t0);
  }
  return r.ok;
}

const std::vector<float>& PageModel::positions(View view) {
  const int v = static_cast<int>(view);
  if (!fresh_[v]) {
    pipe_->evaluate_with(method_of(view), views_[v]);
    publish(view, views_[v]);
    fresh_[v] = true;
  }
  return drawn_[v];
}

double PageModel::evaluate_cpu(View view) {
  const int v = static_cast<int>(view);
  const interp::BezierPoints B = pipe_->bezier_with(method_of(view));
  const auto t0 = Clock::now();
  interp::evaluate<double>(B, pipe_->embedding(), views_[v]);
  const double ms = ms_since(t0);
  publish(view, views_[v]);
  fresh_[v] = true;
  return ms;
}

const std::vector<float>& PageModel::bezier_texels(View view) {
  const interp::BezierPoints B = pipe_->bezier_with(method_of(view));
  const interp::BezierPoints& R = gpu_.rest_bezier;
  std::vector<float>& out = gpu_.texels[static_cast<int>(view)];
  out.assign(static_cast<std::size_t>(4 * B.rows()), 0.0f);
  for (Eigen::Index r = 0; r < B.rows(); ++r)
    for (Eigen::Index c = 0; c < B.cols(); ++c)
      out[static_cast<std::size_t>(4 * r + c)] = static_cast<float>(B(r, c) - R(r, c));
  return out;
}

double PageModel::update_creases() {
  // the pipeline's own U and T (heap, so moving the model keeps the references valid)
  if (!creases_) creases_ = std::make_unique<pipeline::Creases>(pipe_->rest_positions(), pipe_->elements());
  const pipeline::Creases& c = *creases_;
  Eigen::VectorXd jumps[2];
  double top = 0;
  for (View v : {View::BI, View::ModifiedBI}) {
    jumps[static_cast<int>(v)] = c.face_jumps(*pipe_, method_of(v));
    if (jumps[static_cast<int>(v)].size()) top = std::max(top, jumps[static_cast<int>(v)].maxCoeff());
  }
  const double scale = pipeline::crease_scale(top);
  for (int v = 0; v < 2; ++v) {
    const Eigen::VectorXd values = c.point_values(pipe_->embedding(), jumps[v]);
    colors_[v].resize(static_cast<std::size_t>(3 * values.size()));
    for (Eigen::Index q = 0; q < values.size(); ++q) {
      const Eigen::Vector3d rgb = pipeline::crease_color(values(q) / scale);
      for (int i = 0; i < 3; ++i) colors_[v][static_cast<std::size_t>(3 * q + i)] = static_cast<float>(rgb(i));
    }
  }
  return top;
}

interp::DiscontinuityTable PageModel::discontinuity() {
  return interp::discontinuity_table(pipe_->solver(), pipe_->control_positions(), pipe_->modified_bi_M());
}

void PageModel::publish(View view, const Eigen::MatrixXd& P) {
  std::vector<float>& out = drawn_[static_cast<int>(view)];
  out.resize(static_cast<std::size_t>(3 * P.rows()));
  for (Eigen::Index i = 0; i < P.rows(); ++i)
    for (int c = 0; c < 3; ++c) out[static_cast<std::size_t>(3 * i + c)] = static_cast<float>(P(i, c));
}

int PageModel::colliders() const {
  return sim_->contact() ? static_cast<int>(sim_->contact()->colliders().size()) : 0;
}

const Triangles& PageModel::update_collider_mesh() {
  collider_mesh_ = {};
  if (!sim_->contact()) return collider_mesh_;
  interact::ColliderMeshOptions o;
  o.plane_half = size_;
  o.plane_center = 0.5 * (rest_.V.colwise().minCoeff() + rest_.V.colwise().maxCoeff()).transpose();
  for (const pipeline::Collider& c : sim_->contact()->colliders()) {
    const interact::ColliderMesh m = interact::collider_mesh(c, sim_->simulator().time(), o);
    const int first = static_cast<int>(collider_mesh_.positions.size() / 3);
    for (Eigen::Index i = 0; i < m.V.rows(); ++i)
      for (int k = 0; k < 3; ++k) collider_mesh_.positions.push_back(static_cast<float>(m.V(i, k)));
    for (Eigen::Index f = 0; f < m.F.rows(); ++f)
      for (int k = 0; k < 3; ++k) collider_mesh_.indices.push_back(first + m.F(f, k));
  }
  return collider_mesh_;
}

void PageModel::reset() {
  release();
  pipe_->reset();
  step();
}

void PageModel::set_method(pipeline::Method method) {
  if (method != pipeline::Method::BI && method != pipeline::Method::ModifiedBI)
    throw mbi::Error("the page shows BI and modified-BI only");
  pipe_->set_method(method);
}

void PageModel::set_alpha(double alpha) {
  pipe_->set_alpha(alpha);
}

double PageModel::alpha() const { return interp::resolve_alpha(pipe_->options().interp, pipe_->dim()); }

bool PageModel::grab(View view, const Ray& ray) {
  positions(view);  // the CPU's positions of this frame (the GPU's stay on the GPU)
  const std::optional<interact::Hit> hit = interact::cast(ray, views_[static_cast<int>(view)], rest_.F);
  if (!hit) return false;
  sim::Simulator& sim = sim_->simulator();
  const interact::Grab g =
      interact::grab(*hit, rest_.V, rest_.F, pipe_->rest_positions(), pipe_->elements(), sim.masses(), kPokePeriod);
  release();
  poke_.handle = sim.add_poke(g.element, g.bary, g.point, g.stiffness);
  poke_.grabbed = g.point;
  return true;
}

void PageModel::move(const Ray& ray) {
  if (poke_.handle < 0) return;
  // a perspective camera: the plane through the grabbed point facing the ray
  sim_->simulator().set_poke_target(poke_.handle, interact::poke_target(ray, poke_.grabbed, ray.direction, 0.5 * size_));
}

void PageModel::release() {
  sim::Simulator& sim = sim_->simulator();
  if (poke_.handle >= 0 && sim.has_handle(poke_.handle)) sim.remove(poke_.handle);
  poke_.handle = -1;
}

}  // namespace mbi::web
