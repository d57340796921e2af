// Deformer (see deformer.hpp): one embedding and one precompute, then any number of poses.
#include <mbi/error.hpp>
#include <mbi/interp/evaluate.hpp>
#include <mbi/pipeline/deformer.hpp>

#include <cmath>
#include <optional>
#include <string>

namespace mbi::pipeline {
namespace {

std::string shape(Eigen::Index rows, Eigen::Index cols) {
  return std::to_string(rows) + " x " + std::to_string(cols);
}

}  // namespace

struct Deformer::Impl {
  Eigen::MatrixXd U;
  Eigen::MatrixXi T;
  interp::Embedding embedding;
  DeformerOptions options;
  Eigen::MatrixXd rest_normals;
  std::optional<interp::ModifiedBI> solver;
  std::optional<interp::Phong> phong;
  std::unique_ptr<interp::FastEvaluator> fast;  // deform_float(), built on its first call

  // X must be n x d and finite (BI and the float kernel would carry a NaN into every point).
  void check_pose(const Eigen::Ref<const Eigen::MatrixXd>& X) const {
    if (X.rows() != U.rows() || X.cols() != U.cols())
      throw Error("X must be " + shape(U.rows(), U.cols()) + ", got " + shape(X.rows(), X.cols()));
    for (Eigen::Index i = 0; i < X.rows(); ++i)
      for (Eigen::Index c = 0; c < X.cols(); ++c)
        if (!std::isfinite(X(i, c)))
          throw Error("control vertex " + std::to_string(i) + " has a non-finite coordinate (column " +
                      std::to_string(c) + ")");
  }

  void check_points(const char* what, Eigen::Index rows, Eigen::Index cols) const {
    if (rows != embedding.size() || cols != U.cols())
      throw Error(std::string(what) + " must be " + shape(embedding.size(), U.cols()) + ", got " +
                  shape(rows, cols));
  }

  // the float kernel writes p d contiguous floats
  void check_packed(const char* what, const Eigen::Ref<interp::RowMatrixXf>& A) const {
    check_points(what, A.rows(), A.cols());
    if (A.outerStride() != A.cols()) throw Error(std::string(what) + " must be contiguous (p x d floats, row after row)");
  }

  interp::FastEvaluator& fast_evaluator() {
    if (!fast) {
      auto f = std::make_unique<interp::FastEvaluator>(embedding, options.threads);
      if (rest_normals.size() != 0) f->set_rest_normals(rest_normals);
      fast = std::move(f);
    }
    return *fast;
  }
};

Deformer::Deformer(const Eigen::Ref<const Eigen::MatrixXd>& U, const Eigen::Ref<const Eigen::MatrixXi>& T,
                   const Eigen::Ref<const Eigen::MatrixXd>& P, const DeformerOptions& options,
                   const Eigen::MatrixXd& rest_normals)
    : Deformer(U, T, interp::embed(U, T, P), options, rest_normals) {}

Deformer::Deformer(const Eigen::Ref<const Eigen::MatrixXd>& U, const Eigen::Ref<const Eigen::MatrixXi>& T,
                   interp::Embedding embedding, const DeformerOptions& options,
                   const Eigen::MatrixXd& rest_normals)
    : impl_(std::make_unique<Impl>()) {
  interp::validate_mesh(U, T);
  const int d = static_cast<int>(U.cols());
  if (embedding.dim() != d || embedding.bary.rows() != embedding.element.size())
    throw Error("the embedding must have " + std::to_string(d + 1) + " barycentric coordinates a point");
  for (Eigen::Index p = 0; p < embedding.size(); ++p)
    if (embedding.element(p) < 0 || embedding.element(p) >= T.rows())
      throw Error("point " + std::to_string(p) + " refers to element " + std::to_string(embedding.element(p)) +
                  " outside [0, " + std::to_string(T.rows()) + ")");
  if (options.threads < 0) throw Error("threads must be >= 0 (0 = all cores)");
  Impl& I = *impl_;
  I.U = U;
  I.T = T;
  I.embedding = std::move(embedding);
  I.options = options;
  if (rest_normals.size() != 0) {
    I.check_points("rest normals", rest_normals.rows(), rest_normals.cols());
    if (I.embedding.gradients.rows() != T.rows() * (d + 1))
      throw Error("normals need the embedding's basis gradients (filled by interp::embed())");
    I.rest_normals = rest_normals;
  }
  if (needs_solve(options.method)) I.solver.emplace(I.U, I.T, options.interp);
  if (needs_phong(options.method)) I.phong.emplace(I.U, I.T);
}

Deformer::~Deformer() = default;
Deformer::Deformer(Deformer&&) noexcept = default;
Deformer& Deformer::operator=(Deformer&&) noexcept = default;

int Deformer::dim() const { return static_cast<int>(impl_->U.cols()); }
int Deformer::vertices() const { return static_cast<int>(impl_->U.rows()); }
int Deformer::elements() const { return static_cast<int>(impl_->T.rows()); }
long long Deformer::points() const { return impl_->embedding.size(); }
Method Deformer::method() const { return impl_->options.method; }
const DeformerOptions& Deformer::options() const { return impl_->options; }
const interp::Embedding& Deformer::embedding() const { return impl_->embedding; }
const Eigen::MatrixXd& Deformer::rest_positions() const { return impl_->U; }
const Eigen::MatrixXi& Deformer::elements_matrix() const { return impl_->T; }
bool Deformer::has_rest_normals() const { return impl_->rest_normals.size() != 0; }

const interp::ModifiedBI& Deformer::solver() const {
  if (!impl_->solver) throw Error(std::string("the ") + method_name(method()) + " method has no modified-BI solver");
  return *impl_->solver;
}

const interp::Phong& Deformer::phong() const {
  if (!impl_->phong) throw Error(std::string("the ") + method_name(method()) + " method has no Phong weights");
  return *impl_->phong;
}

void Deformer::set_alpha(double alpha) {
  if (!impl_->solver) throw Error(std::string("alpha is a parameter of modified-BI, not of ") + method_name(method()));
  impl_->solver->set_alpha(alpha);
  impl_->options.interp.alpha = alpha;
}

interp::VertexMatrices Deformer::M(const Eigen::Ref<const Eigen::MatrixXd>& X) const {
  const Impl& I = *impl_;
  I.check_pose(X);
  switch (I.options.method) {
    case Method::ModifiedBI: return I.solver->solve(X);
    case Method::Phong: return I.phong->M(X);
    case Method::BI: break;
  }
  return interp::VertexMatrices::Zero(I.U.rows() * I.U.cols(), I.U.cols());
}

interp::BezierPoints Deformer::bezier(const Eigen::Ref<const Eigen::MatrixXd>& X) const {
  const Impl& I = *impl_;
  I.check_pose(X);
  switch (I.options.method) {
    case Method::ModifiedBI: return I.solver->bezier(X, I.solver->solve(X));
    case Method::Phong: return interp::bezier_points(I.U, I.T, X, I.phong->M(X));
    case Method::BI: break;
  }
  return interp::bezier_bi(X, I.T);
}

void Deformer::deform(const Eigen::Ref<const Eigen::MatrixXd>& X, interp::PointsRef<double> positions) const {
  impl_->check_points("positions", positions.rows(), positions.cols());
  interp::evaluate<double>(bezier(X), impl_->embedding, positions, impl_->options.threads);
}

void Deformer::deform(const Eigen::Ref<const Eigen::MatrixXd>& X, interp::PointsRef<double> positions,
                      interp::PointsRef<double> normals) const {
  const Impl& I = *impl_;
  if (!has_rest_normals()) throw Error("normals asked for, but no rest normals were given");
  I.check_points("positions", positions.rows(), positions.cols());
  I.check_points("normals", normals.rows(), normals.cols());
  interp::evaluate<double>(bezier(X), I.embedding, I.rest_normals, positions, normals, I.options.threads);
}

Eigen::MatrixXd Deformer::deform(const Eigen::Ref<const Eigen::MatrixXd>& X) const {
  Eigen::MatrixXd positions(points(), dim());
  deform(X, positions);
  return positions;
}

void Deformer::deform_batch(const interp::ConstPointsRef<double>& X, interp::PointsRef<double> positions) const {
  const Eigen::Index n = vertices(), p = points(), d = dim();
  if (X.cols() != d || X.rows() % n != 0)
    throw Error("poses must be (frames " + std::to_string(n) + ") x " + std::to_string(d) + ", got " +
                shape(X.rows(), X.cols()));
  const Eigen::Index frames = X.rows() / n;
  if (positions.rows() != frames * p || positions.cols() != d)
    throw Error("positions must be " + shape(frames * p, d) + ", got " + shape(positions.rows(), positions.cols()));
  for (Eigen::Index k = 0; k < frames; ++k) deform(X.middleRows(k * n, n), positions.middleRows(k * p, p));
}

void Deformer::deform_float(const Eigen::Ref<const Eigen::MatrixXd>& X, Eigen::Ref<interp::RowMatrixXf> positions) {
  impl_->check_packed("positions", positions);
  const interp::BezierPoints B = bezier(X);
  impl_->fast_evaluator().evaluate(B, positions.data(), nullptr);
}

void Deformer::deform_float(const Eigen::Ref<const Eigen::MatrixXd>& X, Eigen::Ref<interp::RowMatrixXf> positions,
                            Eigen::Ref<interp::RowMatrixXf> normals) {
  Impl& I = *impl_;
  if (!has_rest_normals()) throw Error("normals asked for, but no rest normals were given");
  I.check_packed("positions", positions);
  I.check_packed("normals", normals);
  const interp::BezierPoints B = bezier(X);
  I.fast_evaluator().evaluate(B, positions.data(), normals.data());
}

Eigen::MatrixXd Deformer::vjp(const interp::ConstPointsRef<double>& G) const {
  const Impl& I = *impl_;
  I.check_points("dL/dpositions", G.rows(), G.cols());
  const interp::BezierPoints GB = interp::evaluate_transpose(I.embedding, G, elements(), I.options.threads);
  interp::BezierTranspose t = interp::bezier_transpose(I.U, I.T, GB);
  if (I.solver) t.X += I.solver->solve_transpose(t.M);
  else if (I.phong) t.X += I.phong->M_transpose(t.M);
  return std::move(t.X);
}

void Deformer::vjp_batch(const interp::ConstPointsRef<double>& G, interp::PointsRef<double> out) const {
  const Eigen::Index n = vertices(), p = points(), d = dim();
  if (G.cols() != d || (p > 0 ? G.rows() % p != 0 : G.rows() != 0))
    throw Error("dL/dpositions must be (frames " + std::to_string(p) + ") x " + std::to_string(d) +
                ", got " + shape(G.rows(), G.cols()));
  const Eigen::Index frames = p > 0 ? G.rows() / p : out.rows() / n;
  if (out.rows() != frames * n || out.cols() != d)
    throw Error("dL/dX must be " + shape(frames * n, d) + ", got " + shape(out.rows(), out.cols()));
  for (Eigen::Index k = 0; k < frames; ++k) out.middleRows(k * n, n) = vjp(G.middleRows(k * p, p));
}

}  // namespace mbi::pipeline
