#include <mbi/error.hpp>
#include <mbi/interp/evaluate.hpp>
#include <mbi/interp/threads.hpp>
#include <mbi/pipeline/evaluator.hpp>

#include <algorithm>
#include <chrono>

namespace mbi::pipeline {

CpuEvaluator::CpuEvaluator(Precision precision, int threads)
    : precision_(precision), threads_(threads) {
  interp::check_threads(threads);
}

std::string CpuEvaluator::name() const {
  // the count the library's loops run on (mbi/interp/threads.hpp): this evaluator's, at most
  // the library's
  const int lib = interp::threads();
  const int t = threads_ > 0 ? std::min(threads_, lib) : lib;
  return std::string("cpu ") + (precision_ == Precision::Float ? "float" : "double") + ", " +
         std::to_string(t) + (t == 1 ? " thread" : " threads");
}

void CpuEvaluator::set_points(const PointSet& points) {
  const auto& embedding = points.embedding;
  const Eigen::MatrixXd& rest_normals = points.rest_normals;
  if (!embedding) throw Error("no embedding");
  if (rest_normals.size() != 0 &&
      (rest_normals.rows() != embedding->size() || rest_normals.cols() != embedding->dim()))
    throw Error("rest normals must be " + std::to_string(embedding->size()) + " x " +
                std::to_string(embedding->dim()));
  // everything built before anything is replaced: a throw leaves the evaluator as it was
  std::unique_ptr<interp::FastEvaluator> fast;
  if (precision_ == Precision::Float) {
    fast = std::make_unique<interp::FastEvaluator>(*embedding, threads_);
    // normals need the embedding's basis gradients; without them evaluate(B, true) reports it
    if (rest_normals.size() != 0 && embedding->gradients.rows() > 0) fast->set_rest_normals(rest_normals);
  }
  embedding_ = embedding;
  rest_normals_ = rest_normals;
  fast_ = std::move(fast);
  stale_ = false;
  float_normals_ = false;
  positions_.resize(0, 0);
  normals_.resize(0, 0);
}

void CpuEvaluator::evaluate(const interp::BezierPoints& B, bool normals) {
  if (!embedding_) throw Error("evaluate() before set_points()");
  if (normals && rest_normals_.size() == 0)
    throw Error("normals asked for, but no rest normals were given");
  const auto t0 = std::chrono::steady_clock::now();
  if (precision_ == Precision::Double) {
    if (normals)
      interp::evaluate<double>(B, *embedding_, rest_normals_, positions_, normals_, threads_);
    else
      interp::evaluate<double>(B, *embedding_, positions_, threads_);
  } else {
    if (normals && !fast_->has_rest_normals())
      throw Error("normals need the embedding's basis gradients (filled by interp::embed())");
    if (normals) fast_->evaluate(B, positions_f_, normals_f_);
    else fast_->evaluate(B, positions_f_);
    float_normals_ = normals;
    stale_ = true;
  }
  if (!normals && precision_ == Precision::Double) normals_.resize(0, 0);
  timings_.upload_ms = 0;  // nothing to upload: the kernel reads B where it is
  timings_.pass_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

const Eigen::MatrixXd& CpuEvaluator::positions() {
  if (stale_) {
    positions_ = positions_f_.cast<double>();
    if (float_normals_) normals_ = normals_f_.cast<double>();
    else normals_.resize(0, 0);
    stale_ = false;
  }
  return positions_;
}

const Eigen::MatrixXd& CpuEvaluator::normals() {
  positions();
  return normals_;
}

}  // namespace mbi::pipeline
