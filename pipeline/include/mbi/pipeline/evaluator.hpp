#pragma once
// The evaluator interface: turns a frame's element Bezier control points into dense positions
// (and, when asked, normals), given each dense point's element and barycentric coordinates.
// The CPU evaluator (here) and the GPU transform-feedback evaluator (gpu/) implement it, so
// every user of the frame pipeline switches between them with one setting.
#include <mbi/interp/embed.hpp>
#include <mbi/interp/fast_evaluate.hpp>
#include <mbi/interp/modified_bi.hpp>

#include <memory>
#include <string>

namespace mbi::pipeline {

/// What an evaluator gets once per embedding (FramePipeline fills it).
struct PointSet {
  std::shared_ptr<const interp::Embedding> embedding;  ///< element + barycentric coordinates
  /// Bezier points of the rest pose (BI of the rest control mesh): an evaluator may evaluate the
  /// displacement B - rest_bezier and add it to rest_positions, so that float evaluation keeps
  /// its accuracy wherever the model sits in space and reproduces the rest pose exactly.
  interp::BezierPoints rest_bezier;
  Eigen::MatrixXd rest_positions;  ///< p x d, the dense rest points
  Eigen::MatrixXd rest_normals;    ///< p x d unit normals, or empty (no normals)
};

/// Time of the last evaluate(), as the evaluator measured it (ms): uploading the frame's data
/// and the evaluation pass itself (a GPU pass: timer query, or a CPU clock around glFinish).
struct EvaluatorTimings {
  double upload_ms = 0;
  double pass_ms = 0;
};

class Evaluator {
 public:
  virtual ~Evaluator() = default;
  /// Short description for logs and HUDs, e.g. "cpu double, 2 threads".
  virtual std::string name() const = 0;
  /// Static per-point data, once per embedding.
  virtual void set_points(const PointSet& points) = 0;
  /// Evaluates every point from B ((m K) x d, interp::BezierPoints layout); normals too when
  /// `normals` is true (needs rest normals from set_points).
  virtual void evaluate(const interp::BezierPoints& B, bool normals) = 0;
  /// Results of the last evaluate() as p x d doubles on the CPU. A GPU evaluator reads back
  /// here, only when asked.
  virtual const Eigen::MatrixXd& positions() = 0;
  virtual const Eigen::MatrixXd& normals() = 0;
  /// Upload and pass times of the last evaluate().
  virtual EvaluatorTimings timings() const = 0;
};

enum class Precision { Float, Double };

/// Multithreaded CPU evaluation. Double: interp::evaluate<double>, exact at rest. Float: the
/// compact kernel interp::FastEvaluator (28 B a point in 3D), float round-off. Both run on the
/// library's threads (mbi/interp/threads.hpp); `threads` > 0 limits this evaluator to that many,
/// 0 takes the library's count.
class CpuEvaluator final : public Evaluator {
 public:
  explicit CpuEvaluator(Precision precision = Precision::Double, int threads = 0);
  std::string name() const override;
  void set_points(const PointSet& points) override;
  void evaluate(const interp::BezierPoints& B, bool normals) override;
  const Eigen::MatrixXd& positions() override;
  const Eigen::MatrixXd& normals() override;
  EvaluatorTimings timings() const override { return timings_; }

 private:
  Precision precision_;
  int threads_;
  std::shared_ptr<const interp::Embedding> embedding_;
  Eigen::MatrixXd rest_normals_, positions_, normals_;
  std::unique_ptr<interp::FastEvaluator> fast_;  // float path
  interp::RowMatrixXf positions_f_, normals_f_;
  bool stale_ = false;  // float results not yet widened
  bool float_normals_ = false;
  EvaluatorTimings timings_;
};

}  // namespace mbi::pipeline
