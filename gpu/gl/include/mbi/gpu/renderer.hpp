#pragma once
// Offscreen renderer: the dense mesh straight from a GpuEvaluator's buffers (rest + displacement,
// the evaluator's analytic normals; nothing goes through the CPU), shaded under a headlight, with
// an optional control-mesh wireframe, into an RGB image. The camera is the CPU rasteriser's
// orthographic raster::View, so GPU and CPU pictures frame the same region.
#include <mbi/gpu/evaluator.hpp>
#include <mbi/gpu/surface.hpp>
#include <mbi/io/image.hpp>
#include <mbi/raster/raster.hpp>

#include <span>
#include <utility>
#include <vector>

namespace mbi::gpu {

/// The viewer's ground: a square of half side `half` in the plane through `center` spanned by
/// the unit vectors e1, e2, with grid lines `spacing` apart (every tenth darker) and a shadow, a
/// rectangle of half sides `shadow_half` around center + shadow_center (in (e1, e2)) whose edge
/// fades over `shadow_soft`; the square's edge fades into `background` (RGB, 0..1). World units.
struct Ground {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Vector3d e1 = Eigen::Vector3d::UnitX(), e2 = Eigen::Vector3d::UnitZ();
  double half = 1, spacing = 1;
  Eigen::Vector2d shadow_center = Eigen::Vector2d::Zero(), shadow_half = Eigen::Vector2d::Zero();
  double shadow_soft = 0.1;
  Eigen::Vector3d background = Eigen::Vector3d::Ones();
};

class Renderer {
 public:
  /// Needs `context` current whenever a member is called. Throws Error.
  explicit Renderer(Context& context);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  /// The dense mesh's triangles (t x 3 indices into the evaluator's points), once.
  void set_faces(const Eigen::Ref<const Eigen::MatrixXi>& F);

  /// Renders the evaluator's last pass (3D, evaluated with normals) seen through `view` into a
  /// width x height picture (white background). `wire_X` (n x 3 control positions) with
  /// `wire_T` (m x 4) adds the control mesh's edges in dark grey; `solids` (colliders, the
  /// ground) are drawn with it by draw_mesh, their normals raster::vertex_normals (an unlit
  /// solid's toward the eye: its colour as it is).
  io::Image render(const GpuEvaluator& evaluator, const raster::View& view, int width, int height,
                   const Eigen::Vector3d& color = {0.85, 0.62, 0.35},
                   const Eigen::MatrixXd* wire_X = nullptr, const Eigen::MatrixXi* wire_T = nullptr,
                   const std::vector<raster::Solid>& solids = {});

  /// Draws into the bound framebuffer and viewport (a window): world -> clip matrix
  /// `view_projection`, `eye_direction` from the eye into the scene (headlight). Depth test on;
  /// the caller clears.
  void draw(const GpuEvaluator& evaluator, const Eigen::Matrix4d& view_projection,
            const Eigen::Vector3d& eye_direction, const Eigen::Vector3d& color,
            const Eigen::MatrixXd* wire_X = nullptr, const Eigen::MatrixXi* wire_T = nullptr);
  /// Draws the surface as draw() does, with a colour per point (`rgb`: 3 floats a point, 0..1)
  /// and slightly in front of a surface that draw() drew there (its wireframe stays in front).
  void draw_colors(const GpuEvaluator& evaluator, const Eigen::Matrix4d& view_projection,
                   const Eigen::Vector3d& eye_direction, std::span<const float> rgb);
  /// 2D: draws the evaluator's triangles textured with `image`, texture coordinates from the rest
  /// positions (pixels: x right, y down, as the scene's image grid). Uploads the image once per
  /// new image pointer.
  void draw_textured(const GpuEvaluator& evaluator, const Eigen::Matrix4d& view_projection,
                     const io::Image& image);
  /// Draws `ground` into the bound framebuffer and viewport, depth written; the depth test stays
  /// on. Throws Error naming the field for a value not finite, half, spacing or shadow_soft not
  /// positive, a negative shadow_half, or e1, e2 not of unit length.
  void draw_ground(const Ground& ground, const Eigen::Matrix4d& view_projection);
  /// Draws the surface (3D, evaluated with normals) in the viewer's clay material, a matcap of the
  /// normal in camera space (`view_rotation`: world -> camera, rows right, up, toward the eye),
  /// slightly in front of a surface that draw() drew there; the depth test stays on.
  void draw_material(const GpuEvaluator& evaluator, const Eigen::Matrix4d& view_projection,
                     const Eigen::Matrix3d& view_rotation, const Eigen::Vector3d& color);
  /// Draws a triangle mesh given on the CPU (V n x 3 world, N n x 3 unit normals, F t x 3 rows
  /// of V) shaded as draw() shades the surface, in `color`; depth test on, as draw(). Throws
  /// Error on shapes that disagree or an index outside V.
  void draw_mesh(const Eigen::MatrixXd& V, const Eigen::MatrixXd& N, const Eigen::MatrixXi& F,
                 const Eigen::Matrix4d& view_projection, const Eigen::Vector3d& eye_direction,
                 const Eigen::Vector3d& color);
  /// Draws points (k x 3, world) as squares of `size` pixels in a flat colour, over everything.
  void draw_points(const Eigen::MatrixXd& points, const Eigen::Matrix4d& view_projection,
                   const Eigen::Vector3d& color, float size);

  /// The orthographic world -> clip matrix of a raster::View at width x height (the CPU
  /// rasteriser's framing).
  static Eigen::Matrix4d view_matrix(const raster::View& view, int width, int height);

 private:
  void ensure_target(int width, int height);
  Context& context_;
  Surface surface_;
  unsigned mesh_program_ = 0, line_program_ = 0, colors_program_ = 0;
  unsigned line_vao_ = 0, line_buffer_ = 0;
  unsigned mesh_vao_ = 0, mesh_buffers_[3] = {0, 0, 0};  // draw_mesh: positions, normals, indices
  unsigned fbo_ = 0, color_ = 0, depth_ = 0;
  unsigned texture_program_ = 0, texture_ = 0;
  unsigned material_program_ = 0, ground_program_ = 0, ground_vao_ = 0, ground_corners_ = 0;
  const io::Image* texture_image_ = nullptr;
  int width_ = 0, height_ = 0;
  std::vector<std::pair<int, int>> edges_;  // unique control-mesh edges (wireframe)
  long long edges_of_ = -1;                 // element count they were built from
};

/// The picture of the bound read framebuffer's read buffer, width x height pixels from the
/// lower left corner, as RGB with the top row first. Throws Error for a negative size.
io::Image read_picture(int width, int height);

}  // namespace mbi::gpu
