// The page's model: frames, the two views, pokes (see page_model.hpp).
#include <mbi/web/page_model.hpp>

#include <mbi/base/timer.hpp>
#include <mbi/error.hpp>
#include <mbi/interp/embed.hpp>

#include <Eigen/Geometry>

#include <cmath>
#include <limits>
#include <optional>

namespace mbi::web {
namespace {

// The natural period (s) of a poke's spring on the mass it pulls: `mbi view`'s default.
constexpr double kPokePeriod = 0.15;

struct Hit {
  int face = -1;
  Eigen::Vector3d bary;  // of the face's corners
  Eigen::Vector3d point;
};

// The first triangle of (P, F) that the ray hits (Moller-Trumbore), if any.
std::optional<Hit> cast(const Ray& ray, const Eigen::MatrixXd& P, const Eigen::MatrixXi& F) {
  std::optional<Hit> best;
  double best_t = std::numeric_limits<double>::infinity();
  const Eigen::Vector3d& o = ray.origin;
  const Eigen::Vector3d& d = ray.direction;
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d a = P.row(F(f, 0)).transpose(), e1 = P.row(F(f, 1)).transpose() - a,
                          e2 = P.row(F(f, 2)).transpose() - a;
    const Eigen::Vector3d p = d.cross(e2);
    const double det = e1.dot(p);
    if (std::abs(det) < 1e-300) continue;
    const Eigen::Vector3d s = o - a;
    const double u = s.dot(p) / det;
    if (u < 0 || u > 1) continue;
    const Eigen::Vector3d q = s.cross(e1);
    const double v = d.dot(q) / det;
    if (v < 0 || u + v > 1) continue;
    const double t = e2.dot(q) / det;
    if (t <= 0 || t >= best_t) continue;
    best_t = t;
    best = Hit{static_cast<int>(f), Eigen::Vector3d(1 - u - v, u, v), o + t * d};
  }
  return best;
}

pipeline::Method method_of(View view) {
  return view == View::BI ? pipeline::Method::BI : pipeline::Method::ModifiedBI;
}

}  // namespace

PageModel::PageModel(Eigen::MatrixXd U, Eigen::MatrixXi T, Surface dense, sim::Simulator simulator,
                     double alpha, std::string description)
    : U_(std::move(U)), T_(std::move(T)), rest_(std::move(dense)), description_(std::move(description)) {
  auto driver = std::make_unique<pipeline::SimulatorDriver>(std::move(simulator));
  sim_ = driver.get();
  pipeline::PipelineOptions po;
  po.method = pipeline::Method::ModifiedBI;
  po.interp.alpha = alpha;
  pipe_ = std::make_unique<pipeline::FramePipeline>(U_, T_, interp::embed(U_, T_, rest_.V),
                                                    std::move(driver), po);
  size_ = (rest_.V.colwise().maxCoeff() - rest_.V.colwise().minCoeff()).norm();
  step();
}

bool PageModel::step() {
  const pipeline::FrameResult r = pipe_->step();
  message_ = r.message;
  const pipeline::Method own = pipe_->method();
  for (View v : {View::BI, View::ModifiedBI}) {
    if (method_of(v) != own) continue;
    views_[static_cast<int>(v)] = pipe_->positions();
    publish(v, views_[static_cast<int>(v)]);
  }
  const auto t0 = Clock::now();
  const View other = own == pipeline::Method::BI ? View::ModifiedBI : View::BI;
  pipe_->evaluate_with(method_of(other), views_[static_cast<int>(other)]);
  publish(other, views_[static_cast<int>(other)]);
  other_ms_ = ms_since(t0);
  return r.ok;
}

void PageModel::publish(View view, const Eigen::MatrixXd& P) {
  std::vector<float>& out = drawn_[static_cast<int>(view)];
  out.resize(static_cast<std::size_t>(3 * P.rows()));
  for (Eigen::Index i = 0; i < P.rows(); ++i)
    for (int c = 0; c < 3; ++c) out[static_cast<std::size_t>(3 * i + c)] = static_cast<float>(P(i, c));
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
  if (!(alpha > 0) || !std::isfinite(alpha)) throw mbi::Error("alpha must be a positive number");
  pipe_->set_alpha(alpha);
}

bool PageModel::grab(View view, const Ray& ray) {
  const std::optional<Hit> hit = cast(ray, views_[static_cast<int>(view)], rest_.F);
  if (!hit) return false;
  // the material point under the cursor: its rest position, then its control element
  Eigen::Vector3d rest = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k) rest += hit->bary(k) * rest_.V.row(rest_.F(hit->face, k)).transpose();
  const interp::Embedding e = interp::embed(U_, T_, rest.transpose());
  const int element = e.element(0);
  sim::Simulator& sim = sim_->simulator();
  double mass = 0;
  for (int k = 0; k < 4; ++k) mass += sim.masses()(T_(element, k));
  const double w = 2 * std::acos(-1.0) / kPokePeriod;
  release();
  poke_.handle = sim.add_poke(element, e.bary.row(0).transpose(), hit->point, mass * w * w);
  poke_.grabbed = hit->point;
  return true;
}

void PageModel::move(const Ray& ray) {
  const Eigen::Vector3d& o = ray.origin;
  const Eigen::Vector3d& d = ray.direction;
  if (poke_.handle < 0 || !o.allFinite() || !d.allFinite() || !(d.squaredNorm() > 0)) return;
  Eigen::Vector3d to = o + ((poke_.grabbed - o).dot(d) / d.squaredNorm()) * d - poke_.grabbed;
  const double reach = 0.5 * size_;
  if (to.norm() > reach) to *= reach / to.norm();
  sim_->simulator().set_poke_target(poke_.handle, poke_.grabbed + to);
}

void PageModel::release() {
  sim::Simulator& sim = sim_->simulator();
  if (poke_.handle >= 0 && sim.has_handle(poke_.handle)) sim.remove(poke_.handle);
  poke_.handle = -1;
}

}  // namespace mbi::web
