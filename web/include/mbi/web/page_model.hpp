#pragma once
// The browser page's model: a scene on the one frame pipeline (mbi::pipeline), the dense
// positions of BI and modified-BI for the page's two views, and mouse pokes as in `mbi view`.
// Plain C++ without Emscripten: the page's module and its native twin compile the same code
// (web/api). Scenes: the scene files the page can run (scenes/*.toml, embedded at build time:
// web/include/mbi/web/scene_files.hpp) and a user's surface in a generated control mesh.
// Contact at the dense surface is the pipeline's, as in `mbi run`; the page counts the touching
// vertices and draws the colliders (interact::collider_mesh).
//
// Two evaluators of the dense points: the CPU (here, double) and the page's WebGL2 pass
// (web/page/gpu_evaluator.js) from bezier_texels(); with the GPU one, step() leaves the CPU
// positions to be evaluated on demand (positions(), picking).
#include <mbi/interact/pick.hpp>
#include <mbi/interp/metrics.hpp>
#include <mbi/pipeline/creases.hpp>
#include <mbi/pipeline/driver.hpp>
#include <mbi/pipeline/frame_pipeline.hpp>
#include <mbi/scenes/scene.hpp>

#include <Eigen/Core>

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace mbi::web {

/// A half-line in model coordinates (m); direction need not be unit length.
using interact::Ray;

/// Triangles to draw (the colliders): x, y, z floats per vertex (m), 3 vertex indices each.
struct Triangles {
  std::vector<float> positions;
  std::vector<int> indices;
};

/// The two views: BI (left) and modified-BI (right).
enum class View { BI = 0, ModifiedBI = 1 };

class PageModel {
 public:
  ~PageModel();
  PageModel(PageModel&&) noexcept;
  PageModel& operator=(PageModel&&) noexcept;

  /// A scene at frame 0, as `mbi run` builds it (its models, simulation, constraints, scripted
  /// pokes, alpha; mbi/scenes/models.hpp); the timed method modified-BI unless the scene says
  /// BI. Throws mbi::Error naming the scene when the page cannot run it (page_problem()).
  static PageModel scene(const scenes::Scene& scene);
  /// A dense surface (V n x 3, F t x 3, y up) in a generated control mesh of about
  /// `control_vertices` vertices, as `mbi view MODEL` sets it up (mbi/scenes/model_scene.hpp:
  /// material fitted to its size, its bottom held). Throws mbi::Error on a bad surface or cage.
  static PageModel surface(const Eigen::MatrixXd& V, const Eigen::MatrixXi& F,
                           int control_vertices);

  /// Computes the next frame: the pipeline's step with its method, then the other view's
  /// method on the same control positions. False (message()) when the simulation failed.
  bool step();
  /// Back to frame 0, pokes released.
  void reset();
  /// The pipeline's method (BI or modified-BI), the one the phase times measure.
  void set_method(pipeline::Method method);
  /// alpha of modified-BI (refactors; interp checks it and throws mbi::Error when it is not > 0).
  void set_alpha(double alpha);
  /// The current alpha (interp's default until set_alpha()).
  double alpha() const;

  /// Starts a poke where `ray` first hits the dense surface as drawn in `view` (interact::cast,
  /// the viewer's picking: a ray through a shared edge or vertex hits): a spring from the
  /// material point under the cursor to a target at the hit point. False on a miss; throws
  /// interact::Error on a zero or non-finite ray.
  bool grab(View view, const Ray& ray);
  /// Moves the poke's target to where `ray` meets the plane through the grabbed point facing
  /// the ray, kept within half the model's size of that point (interact::poke_target).
  void move(const Ray& ray);
  void release();

  /// Whether step() evaluates the dense points on the CPU (on at first).
  void set_cpu_evaluation(bool on) { cpu_ = on; }
  bool cpu_evaluation() const { return cpu_; }
  /// Evaluates a view's dense points of the current frame on the CPU now; the milliseconds.
  double evaluate_cpu(View view);

  int vertices() const { return static_cast<int>(rest_.V.rows()); }
  const Eigen::MatrixXi& triangles() const { return rest_.F; }
  /// Dense positions of a view as x, y, z floats per vertex (vertices() x 3), evaluated on the
  /// CPU now if step() left them to the GPU.
  const std::vector<float>& positions(View view);

  // The GPU pass's inputs (gpu/gl/shaders/evaluate.glsl): per dense point its element and its
  // barycentric coordinates (4 floats), its rest position (3 floats); per frame and view the
  // Bezier control points minus those of the rest shape, x y z 0 floats, K = 10 per element.
  const std::vector<int>& point_elements() const { return gpu_.elements; }
  const std::vector<float>& point_bary() const { return gpu_.bary; }
  const std::vector<float>& rest_positions() const { return gpu_.rest; }
  const std::vector<float>& bezier_texels(View view);

  /// The crease colours of the native viewer (mbi/pipeline/creases.hpp) for both views of the current
  /// frame, one scale for both: RGB floats per dense vertex (crease_colors()). Returns the
  /// largest gradient jump, the scale's top.
  double update_creases();
  const std::vector<float>& crease_colors(View view) const { return colors_[static_cast<int>(view)]; }
  /// The paper's Table 2 for the current frame, as `mbi run` prints it: the face discontinuity
  /// energies E_F of BI against modified-BI. Throws interp::OverflowError (positions too large).
  interp::DiscontinuityTable discontinuity();
  /// Contact at the dense surface (a scene with contact = "surface"): the dense vertices inside a
  /// collider at the current frame, as `mbi run` counts them (metrics.json's contact_points); 0
  /// without contact.
  int touching_points() const { return sim_->touching_points(); }
  /// The number of colliders (the scene's [[colliders]], then its ground plane).
  int colliders() const;
  /// Builds the colliders as they stand at the current frame as triangles (collider_mesh(); the
  /// viewer's, interact::collider_mesh): a plane as a square twice the model's size about the
  /// point nearest the model's rest centre.
  const Triangles& update_collider_mesh();
  const Triangles& collider_mesh() const { return collider_mesh_; }
  /// Control positions (n x 3) of the current frame.
  const Eigen::MatrixXd& control_positions() const { return pipe_->control_positions(); }
  const Eigen::MatrixXi& control_elements() const { return pipe_->elements(); }
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
  // pipe's driver must be a SimulatorDriver (the pokes pull on the simulation)
  PageModel(Surface dense, pipeline::FramePipeline pipe, std::string description);
  struct GpuInputs {
    std::vector<int> elements;
    std::vector<float> bary, rest, texels[2];
    interp::BezierPoints rest_bezier;
  };
  void publish(View view, const Eigen::MatrixXd& P);

  Surface rest_;
  pipeline::SimulatorDriver* sim_ = nullptr;  // owned by pipe_
  std::unique_ptr<pipeline::FramePipeline> pipe_;
  Eigen::MatrixXd views_[2];         // dense positions per view (double, for picking)
  std::vector<float> drawn_[2];      // the same as floats for the page
  double other_ms_ = 0, size_ = 1;
  Poke poke_;
  bool cpu_ = true;
  bool fresh_[2] = {false, false};   // views_ and drawn_ hold the current frame
  GpuInputs gpu_;
  std::unique_ptr<pipeline::Creases> creases_;  // built on first use
  std::vector<float> colors_[2];
  Triangles collider_mesh_;
  std::string message_, description_;
};

}  // namespace mbi::web
