#pragma once
// The browser page's model: a scene on the one frame pipeline (mbi::pipeline), the dense
// positions of BI and modified-BI for the page's two views, and mouse pokes as in `mbi view`.
// Plain C++ without Emscripten: the page's module and its native twin compile the same code
// (web/api). Scenes: the paper's twisting bar (scenes/twist-bar.toml), the poke cylinder
// (scenes/poke.toml, without its scripted pokes) and a user's surface in a generated voxel cage.
#include <mbi/pipeline/driver.hpp>
#include <mbi/pipeline/frame_pipeline.hpp>

#include <Eigen/Core>

#include <memory>
#include <string>
#include <vector>

namespace mbi::web {

enum class SceneKind { TwistBar, Poke };

/// A half-line in model coordinates (m); direction need not be unit length.
struct Ray {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();
};

/// The two views: BI (left) and modified-BI (right).
enum class View { BI = 0, ModifiedBI = 1 };

class PageModel {
 public:
  /// A built-in scene, at frame 0.
  static PageModel builtin(SceneKind kind);
  /// A dense surface (V n x 3, F t x 3, y up) in a voxel cage of about `control_vertices`
  /// vertices, its bottom tenth in y held, as `mbi run scenes/poke.toml --mesh` sets it up.
  /// Throws mbi::Error on a bad surface or cage.
  static PageModel surface(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                           int control_vertices);

  /// Computes the next frame: the pipeline's step with its method, then the other view's
  /// method on the same control positions. False (message()) when the simulation failed.
  bool step();
  /// Back to frame 0, pokes released.
  void reset();
  /// The pipeline's method (BI or modified-BI), the one the phase times measure.
  void set_method(pipeline::Method method);
  /// alpha > 0 of modified-BI (refactors; throws mbi::Error otherwise).
  void set_alpha(double alpha);

  /// Starts a poke where `ray` first hits the dense surface as drawn in `view`: a spring from
  /// the material point under the cursor to a target at the hit point. False on a miss.
  bool grab(View view, const Ray& ray);
  /// Moves the poke's target to where `ray` meets the plane through the grabbed point facing
  /// the ray, kept within half the model's size of that point.
  void move(const Ray& ray);
  void release();

  int vertices() const { return static_cast<int>(rest_.V.rows()); }
  const Eigen::MatrixXi& triangles() const { return rest_.F; }
  /// Dense positions of a view as x, y, z floats per vertex (vertices() x 3).
  const std::vector<float>& positions(View view) const { return drawn_[static_cast<int>(view)]; }
  /// Control positions (n x 3) of the current frame.
  const Eigen::MatrixXd& control_positions() const { return pipe_->control_positions(); }
  const Eigen::MatrixXi& control_elements() const { return T_; }
  /// The pipeline's phases of the last frame, then the other view's evaluation (ms).
  const pipeline::FrameTimings& timings() const { return pipe_->timings(); }
  double other_view_ms() const { return other_ms_; }
  int frame() const { return pipe_->frame(); }
  const std::string& message() const { return message_; }
  /// One line: the scene, its vertex counts.
  const std::string& description() const { return description_; }

 private:
  struct Surface {
    Eigen::MatrixXd V;
    Eigen::MatrixXi F;
  };
  struct Poke {
    int handle = -1;
    Eigen::Vector3d grabbed = Eigen::Vector3d::Zero();
  };
  PageModel(Eigen::MatrixXd U, Eigen::MatrixXi T, Surface dense, sim::Simulator simulator,
            double alpha, std::string description);
  void publish(View view, const Eigen::MatrixXd& P);

  Eigen::MatrixXd U_;
  Eigen::MatrixXi T_;
  Surface rest_;
  pipeline::SimulatorDriver* sim_ = nullptr;  // owned by pipe_
  std::unique_ptr<pipeline::FramePipeline> pipe_;
  Eigen::MatrixXd views_[2];         // dense positions per view (double, for picking)
  std::vector<float> drawn_[2];      // the same as floats for the page
  double other_ms_ = 0, size_ = 1;
  Poke poke_;
  std::string message_, description_;
};

}  // namespace mbi::web
