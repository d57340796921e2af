#pragma once
// The evaluator interface: turns a frame's element Bezier control points into dense positions
// (and, when asked, normals), given each dense point's element and barycentric coordinates.
// The CPU evaluator (here) and the GPU transform-feedback evaluator (gpu/) implement it, so
// every user of the frame pipeline switches between them with one setting.
#include <mbi/interp/embed.hpp>
#include <mbi/interp/modified_bi.hpp>

#include <memory>
#include <string>

namespace mbi::pipeline {

class Evaluator {
 public:
  virtual ~Evaluator() = default;
  /// Short description for logs and HUDs, e.g. "cpu double, 2 threads".
  virtual std::string name() const = 0;
  /// Static per-point data, once per embedding: element ids and barycentric coordinates, and
  /// unit rest normals (p x d) when normals will be asked for (else empty).
  virtual void set_points(std::shared_ptr<const interp::Embedding> embedding,
                          const Eigen::MatrixXd& rest_normals) = 0;
  /// Evaluates every point from B ((m K) x d, interp::BezierPoints layout); normals too when
  /// `normals` is true (needs rest normals from set_points).
  virtual void evaluate(const interp::BezierPoints& B, bool normals) = 0;
  /// Results of the last evaluate() as p x d doubles on the CPU. A GPU evaluator reads back
  /// here, only when asked.
  virtual const Eigen::MatrixXd& positions() = 0;
  virtual const Eigen::MatrixXd& normals() = 0;
};

enum class Precision { Float, Double };

/// Multithreaded CPU evaluation (interp::evaluate). Double is exact at rest; float moves half
/// the bytes.
class CpuEvaluator final : public Evaluator {
 public:
  explicit CpuEvaluator(Precision precision = Precision::Double, int threads = 0);
  std::string name() const override;
  void set_points(std::shared_ptr<const interp::Embedding> embedding,
                  const Eigen::MatrixXd& rest_normals) override;
  void evaluate(const interp::BezierPoints& B, bool normals) override;
  const Eigen::MatrixXd& positions() override;
  const Eigen::MatrixXd& normals() override;

 private:
  Precision precision_;
  int threads_;
  std::shared_ptr<const interp::Embedding> embedding_;
  Eigen::MatrixXd rest_normals_, positions_, normals_;
  Eigen::MatrixXf rest_normals_f_, positions_f_, normals_f_;
  bool stale_ = false;  // float results not yet widened
};

}  // namespace mbi::pipeline
