// Deformer (see deformer.hpp): one embedding and one precompute, then any number of poses.
#include <mbi/error.hpp>
#include <mbi/interp/evaluate.hpp>
#include <mbi/interp/threads.hpp>
#include <mbi/pipeline/deformer.hpp>
#include <mbi/pipeline/precompute.hpp>

#include <algorithm>
#include <cmath>
#include <exception>
#include <mutex>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace mbi::pipeline {
namespace {

std::string shape(Eigen::Index rows, Eigen::Index cols) {
  return std::to_string(rows) + " x " + std::to_string(cols);
}

// One call's temporaries of the mesh's size, kept for the next call (deform() and vjp() are const
// and may run on several threads at once: each call takes a scratch of its own from a pool).
struct Scratch {
  Precompute::PoseScratch pose;  // deform(): M and the Bezier points
  Eigen::MatrixXd X;             // deform_batch(): a frame whose columns are not contiguous, copied
  interp::VertexMatrices Ms;     // deform_batch(): modified-BI's M of a block of frames
  interp::BezierPoints GB;       // vjp(): dL/dB, dL/dX through B, dL/dM and dL/dX through M
  Eigen::MatrixXd GX, GMX;
  interp::VertexMatrices GM;
};

// Frame k (n rows) of the poses X as the methods read a pose (contiguous columns): in place when
// they are (Fortran order), else copied into `copy` (a C-order numpy array; no allocation after
// the first frame, where Eigen::Ref would allocate a temporary every time).
Eigen::Map<const Eigen::MatrixXd, 0, Eigen::OuterStride<>> frame(const interp::ConstPointsRef<double>& X, Eigen::Index k,
                                                                 Eigen::Index n, Eigen::MatrixXd& copy) {
  const auto f = X.middleRows(k * n, n);
  if (f.innerStride() == 1) return {f.data(), f.rows(), f.cols(), Eigen::OuterStride<>(f.outerStride())};
  copy = f;
  return {copy.data(), copy.rows(), copy.cols(), Eigen::OuterStride<>(copy.rows())};
}

// Throws unless every coordinate of the poses X ((frames n) x d) is finite, naming the first bad one.
void check_poses(const interp::ConstPointsRef<double>& X, Eigen::Index n) {
  for (Eigen::Index i = 0; i < X.rows(); ++i)
    for (Eigen::Index c = 0; c < X.cols(); ++c)
      if (!std::isfinite(X(i, c)))
        throw Error("control vertex " + std::to_string(i % n) + " of pose " + std::to_string(i / n) +
                    " has a non-finite coordinate (column " + std::to_string(c) + ")");
}

}  // namespace

struct Deformer::Impl {
  Precompute pre;
  interp::Embedding embedding;
  DeformerOptions options;
  Eigen::MatrixXd rest_normals;
  std::unique_ptr<interp::FastEvaluator> fast;  // deform_float(), built on its first call
  mutable std::mutex pool_mutex;
  mutable std::vector<std::unique_ptr<Scratch>> pool;  // scratches not in use

  // A scratch for one call, given back to the pool when the lease ends.
  class Lease {
   public:
    explicit Lease(const Impl& impl) : impl_(impl) {
      std::lock_guard<std::mutex> lock(impl_.pool_mutex);
      if (impl_.pool.empty()) {
        scratch_ = std::make_unique<Scratch>();
      } else {
        scratch_ = std::move(impl_.pool.back());
        impl_.pool.pop_back();
      }
    }
    ~Lease() {
      std::lock_guard<std::mutex> lock(impl_.pool_mutex);
      impl_.pool.push_back(std::move(scratch_));
    }
    Lease(const Lease&) = delete;
    Lease& operator=(const Lease&) = delete;
    Scratch& operator*() const { return *scratch_; }

   private:
    const Impl& impl_;
    std::unique_ptr<Scratch> scratch_;
  };

  const interp::BezierPoints& bezier(const Eigen::Ref<const Eigen::MatrixXd>& X, Scratch& s) const {
    return pre.bezier(options.method, X, s.pose);
  }

  // dL/dX of one frame into s.GX.
  void vjp(const interp::ConstPointsRef<double>& G, Scratch& s) const {
    check_points("dL/dpositions", G.rows(), G.cols());
    const Eigen::Index n = pre.rest_positions().rows(), d = pre.dim();
    const int m = static_cast<int>(pre.elements().rows());
    s.GB.resize(static_cast<Eigen::Index>(m) * ((d + 1) * (d + 2) / 2), d);
    s.GX.resize(n, d);
    s.GM.resize(n * d, d);
    interp::evaluate_transpose(embedding, G, m, s.GB, options.threads);
    interp::bezier_transpose(pre.rest_positions(), pre.elements(), s.GB, s.GX, s.GM);
    if (options.method == Method::BI) return;  // M = 0
    s.GMX.resize(n, d);
    pre.M_transpose(options.method, s.GM, s.GMX);
    s.GX += s.GMX;
  }

  Impl(const Eigen::Ref<const Eigen::MatrixXd>& U, const Eigen::Ref<const Eigen::MatrixXi>& T,
       const DeformerOptions& o)
      : pre(U, T, o.method, o.interp), options(o) {}

  void check_points(const char* what, Eigen::Index rows, Eigen::Index cols) const {
    if (rows != embedding.size() || cols != pre.dim())
      throw Error(std::string(what) + " must be " + shape(embedding.size(), pre.dim()) + ", got " +
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
                   const Eigen::MatrixXd& rest_normals) {
  interp::check_threads(options.threads);
  // The precompute does not depend on the points: it runs on a thread of its own while this one
  // embeds (the embedding's threads share the cores poorly), unless one thread was asked for.
  std::unique_ptr<Impl> impl;
  std::exception_ptr failed;
  auto precompute = [&] {
    try {
      impl = std::make_unique<Impl>(U, T, options);
    } catch (...) {
      failed = std::current_exception();
    }
  };
  interp::Embedding embedding;
  if (options.threads != 1 && interp::threads() > 1) {
    std::thread beside(precompute);
    try {
      embedding = interp::embed(U, T, P);
    } catch (...) {
      beside.join();
      throw;  // the embedding's error first, as when the two run one after the other
    }
    beside.join();
  } else {
    embedding = interp::embed(U, T, P);
    precompute();
  }
  if (failed) std::rethrow_exception(failed);
  impl_ = std::move(impl);
  attach(std::move(embedding), rest_normals);
}

Deformer::Deformer(const Eigen::Ref<const Eigen::MatrixXd>& U, const Eigen::Ref<const Eigen::MatrixXi>& T,
                   interp::Embedding embedding, const DeformerOptions& options,
                   const Eigen::MatrixXd& rest_normals)
    : impl_(std::make_unique<Impl>(U, T, options)) {
  attach(std::move(embedding), rest_normals);
}

void Deformer::attach(interp::Embedding embedding, const Eigen::MatrixXd& rest_normals) {
  const Eigen::Index d = impl_->pre.dim();
  const DeformerOptions& options = impl_->options;
  const Eigen::MatrixXi& T = impl_->pre.elements();
  if (embedding.dim() != d || embedding.bary.rows() != embedding.element.size())
    throw Error("the embedding must have " + std::to_string(d + 1) + " barycentric coordinates a point");
  for (Eigen::Index p = 0; p < embedding.size(); ++p)
    if (embedding.element(p) < 0 || embedding.element(p) >= T.rows())
      throw Error("point " + std::to_string(p) + " refers to element " + std::to_string(embedding.element(p)) +
                  " outside [0, " + std::to_string(T.rows()) + ")");
  interp::check_threads(options.threads);
  Impl& I = *impl_;
  I.embedding = std::move(embedding);
  if (rest_normals.size() != 0) {
    I.check_points("rest normals", rest_normals.rows(), rest_normals.cols());
    if (I.embedding.gradients.rows() != T.rows() * (d + 1))
      throw Error("normals need the embedding's basis gradients (filled by interp::embed())");
    I.rest_normals = rest_normals;
  }
}

Deformer::~Deformer() = default;
Deformer::Deformer(Deformer&&) noexcept = default;
Deformer& Deformer::operator=(Deformer&&) noexcept = default;

int Deformer::dim() const { return impl_->pre.dim(); }
int Deformer::vertices() const { return static_cast<int>(impl_->pre.rest_positions().rows()); }
int Deformer::elements() const { return static_cast<int>(impl_->pre.elements().rows()); }
long long Deformer::points() const { return impl_->embedding.size(); }
Method Deformer::method() const { return impl_->options.method; }
const DeformerOptions& Deformer::options() const { return impl_->options; }
const interp::Embedding& Deformer::embedding() const { return impl_->embedding; }
const Eigen::MatrixXd& Deformer::rest_positions() const { return impl_->pre.rest_positions(); }
const Eigen::MatrixXi& Deformer::elements_matrix() const { return impl_->pre.elements(); }
bool Deformer::has_rest_normals() const { return impl_->rest_normals.size() != 0; }

const interp::ModifiedBI& Deformer::solver() const {
  const interp::ModifiedBI* s = impl_->pre.built_solver();
  if (!s) throw Error(std::string("the ") + method_name(method()) + " method has no modified-BI solver");
  return *s;
}

const interp::Phong& Deformer::phong() const {
  const interp::Phong* p = impl_->pre.built_phong();
  if (!p) throw Error(std::string("the ") + method_name(method()) + " method has no Phong weights");
  return *p;
}

void Deformer::set_alpha(double alpha) {
  if (!impl_->pre.built_solver())
    throw Error(std::string("alpha is a parameter of modified-BI, not of ") + method_name(method()));
  impl_->pre.set_alpha(alpha);
  impl_->options.interp = impl_->pre.options();
}

interp::VertexMatrices Deformer::M(const Eigen::Ref<const Eigen::MatrixXd>& X) const {
  return std::as_const(impl_->pre).M(method(), X);
}

interp::BezierPoints Deformer::bezier(const Eigen::Ref<const Eigen::MatrixXd>& X) const {
  return impl_->pre.bezier(method(), X);
}

void Deformer::deform(const Eigen::Ref<const Eigen::MatrixXd>& X, interp::PointsRef<double> positions) const {
  const Impl& I = *impl_;
  I.check_points("positions", positions.rows(), positions.cols());
  const Impl::Lease s(I);
  interp::evaluate<double>(I.bezier(X, *s), I.embedding, positions, I.options.threads);
}

void Deformer::deform(const Eigen::Ref<const Eigen::MatrixXd>& X, interp::PointsRef<double> positions,
                      interp::PointsRef<double> normals) const {
  const Impl& I = *impl_;
  if (!has_rest_normals()) throw Error("normals asked for, but no rest normals were given");
  I.check_points("positions", positions.rows(), positions.cols());
  I.check_points("normals", normals.rows(), normals.cols());
  const Impl::Lease s(I);
  interp::evaluate<double>(I.bezier(X, *s), I.embedding, I.rest_normals, positions, normals, I.options.threads);
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
  const Impl& I = *impl_;
  const Impl::Lease s(I);
  const interp::ModifiedBI* solver = I.options.method == Method::ModifiedBI ? I.pre.built_solver() : nullptr;
  // one frame, or BI and Phong (their M costs about what reading a pose does: nothing to share)
  if (!solver || frames == 1) {
    for (Eigen::Index k = 0; k < frames; ++k)
      interp::evaluate<double>(I.bezier(frame(X, k, n, (*s).X), *s), I.embedding, positions.middleRows(k * p, p),
                               I.options.threads);
    return;
  }
  // modified-BI: the M of a block of frames in one solve (one pass over the operator or the factor
  // for all of them), then each frame's Bezier points and evaluation
  check_poses(X, n);  // all of them before any is written
  const Eigen::Index block = solver->dense_operator() ? 8 : 8 / d, nd = n * d;
  Scratch& t = *s;
  t.pose.B.resize(I.pre.elements().rows() * ((d + 1) * (d + 2) / 2), d);
  for (Eigen::Index k0 = 0; k0 < frames; k0 += block) {
    const Eigen::Index count = std::min(block, frames - k0);
    t.Ms.resize(block * nd, d);
    solver->solve_batch(X.middleRows(k0 * n, count * n), t.Ms.topRows(count * nd));
    for (Eigen::Index k = 0; k < count; ++k) {
      interp::bezier_points(I.pre.rest_positions(), I.pre.elements(), frame(X, k0 + k, n, t.X),
                            t.Ms.middleRows(k * nd, nd), t.pose.B);
      interp::evaluate<double>(t.pose.B, I.embedding, positions.middleRows((k0 + k) * p, p), I.options.threads);
    }
  }
}

void Deformer::deform_float(const Eigen::Ref<const Eigen::MatrixXd>& X, Eigen::Ref<interp::RowMatrixXf> positions) {
  Impl& I = *impl_;
  I.check_packed("positions", positions);
  const Impl::Lease s(I);
  I.fast_evaluator().evaluate(I.bezier(X, *s), positions.data(), nullptr);
}

void Deformer::deform_float(const Eigen::Ref<const Eigen::MatrixXd>& X, Eigen::Ref<interp::RowMatrixXf> positions,
                            Eigen::Ref<interp::RowMatrixXf> normals) {
  Impl& I = *impl_;
  if (!has_rest_normals()) throw Error("normals asked for, but no rest normals were given");
  I.check_packed("positions", positions);
  I.check_packed("normals", normals);
  const Impl::Lease s(I);
  I.fast_evaluator().evaluate(I.bezier(X, *s), positions.data(), normals.data());
}

Eigen::MatrixXd Deformer::vjp(const interp::ConstPointsRef<double>& G) const {
  const Impl::Lease s(*impl_);
  impl_->vjp(G, *s);
  return (*s).GX;
}

void Deformer::vjp_batch(const interp::ConstPointsRef<double>& G, interp::PointsRef<double> out) const {
  const Eigen::Index n = vertices(), p = points(), d = dim();
  if (G.cols() != d || (p > 0 ? G.rows() % p != 0 : G.rows() != 0))
    throw Error("dL/dpositions must be (frames " + std::to_string(p) + ") x " + std::to_string(d) +
                ", got " + shape(G.rows(), G.cols()));
  const Eigen::Index frames = p > 0 ? G.rows() / p : out.rows() / n;
  if (out.rows() != frames * n || out.cols() != d)
    throw Error("dL/dX must be " + shape(frames * n, d) + ", got " + shape(out.rows(), out.cols()));
  const Impl::Lease s(*impl_);
  for (Eigen::Index k = 0; k < frames; ++k) {
    impl_->vjp(G.middleRows(k * p, p), *s);
    out.middleRows(k * n, n) = (*s).GX;
  }
}

}  // namespace mbi::pipeline
