#pragma once
// A triangle surface drawn from a GpuEvaluator's buffers: the one place that binds them to a
// vertex array and draws the triangles (the Renderer, the viewer's material and crease colours).
// Attribute locations, as in gpu/gl/shaders/: 0 rest, 1 displacement, 2 normal, 3 colour.
#include <mbi/gpu/evaluator.hpp>

#include <Eigen/Core>

#include <span>

namespace mbi::gpu {

/// World -> clip `view_projection` composed with the translation by `origin` (the evaluator's
/// positions are relative to it), in float: the large parts cancel in double first.
Eigen::Matrix4f relative_to(const Eigen::Matrix4d& view_projection, const Eigen::Vector3d& origin);

/// What Surface::draw feeds the program besides the positions (rest + displacement).
struct SurfaceInputs {
  bool normals = true;                         ///< the evaluator's normals (needs a pass with them)
  std::span<const float> colors = {};  ///< RGB per point, 0..1, uploaded at each draw; empty: none
  float offset = 0;  ///< > 0: pushed back by glPolygonOffset(offset, offset), behind lines drawn there
};

class Surface {
 public:
  /// Needs a current context; so do the members.
  Surface();
  ~Surface();
  Surface(const Surface&) = delete;
  Surface& operator=(const Surface&) = delete;

  /// The triangles (t x 3 indices into the evaluator's points), once per mesh. Throws Error for
  /// another shape or a negative index.
  void set_faces(const Eigen::Ref<const Eigen::MatrixXi>& F);
  /// Draws the triangles with the program in use, whose uniforms the caller has set. Throws
  /// Error when normals are asked of a pass without them, or colours are not 3 per point.
  void draw(const GpuEvaluator& evaluator, const SurfaceInputs& inputs = {});

 private:
  unsigned vao_ = 0, index_ = 0, colors_ = 0;
  long long indices_ = 0;
};

}  // namespace mbi::gpu
