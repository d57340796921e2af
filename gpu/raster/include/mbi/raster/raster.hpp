#pragma once
// mbi::raster -- the CPU rasteriser: the fallback renderer for headless pictures when no OpenGL
// context is available (the GPU renderer of gpu/ draws the same pictures). Shaded triangle
// meshes (the paper's Figure 1, BI beside modified-BI) and textured 2D warps (image-warp scene).
#include <mbi/io/image.hpp>

#include <Eigen/Core>

#include <vector>

namespace mbi::raster {

using io::Image;


/// Orthographic view: looks along `direction` (from the eye into the scene) with `up` roughly
/// up; the picture frames `bounds_min`..`bounds_max` with a margin.
struct View {
  Eigen::Vector3d direction{-1.0, -0.6, -0.8};
  Eigen::Vector3d up{0.0, 1.0, 0.0};
  Eigen::Vector3d bounds_min = Eigen::Vector3d::Zero(), bounds_max = Eigen::Vector3d::Ones();
  double margin = 0.05;  ///< fraction of the framed size
};

/// Width / height of the framed region as seen from the view (for choosing a picture size).
double view_aspect(const View& view);

/// View direction + up that frame the given points.
View frame_points(const Eigen::Ref<const Eigen::MatrixXd>& V, const Eigen::Vector3d& direction,
                  const Eigen::Vector3d& up);

/// A triangle mesh in one colour (0..1) drawn beside the model: a collider, the ground.
struct Solid {
  Eigen::MatrixXd V;  ///< n x 3, world
  Eigen::MatrixXi F;  ///< t x 3 rows of V
  Eigen::Vector3d color = {0.6, 0.6, 0.6};
  bool shaded = true;  ///< false: the colour as it is, unlit (a floor seen at a slant stays light)
};

/// Unit vertex normals of V (n x 3), F (f x 3), area weighted; a vertex of no triangle gets 0.
Eigen::MatrixXd vertex_normals(const Eigen::Ref<const Eigen::MatrixXd>& V, const Eigen::Ref<const Eigen::MatrixXi>& F);

/// Renders V (n x 3), F (f x 3) with a z-buffer and per-vertex normals (area weighted) under a
/// headlight with Lambert + ambient shading in `color` (0..1). Shading reveals creases, so BI's
/// first-order discontinuities show up. `solids` are drawn into the same z-buffer after it,
/// shaded alike, each in its colour; without them the picture is the model's alone. Throws
/// std::invalid_argument on shapes that are not n x 3 and f x 3 or an index outside V.
Image render_mesh(const Eigen::Ref<const Eigen::MatrixXd>& V,
                  const Eigen::Ref<const Eigen::MatrixXi>& F, const View& view, int width,
                  int height, const Eigen::Vector3d& color = {0.85, 0.62, 0.35},
                  const std::vector<Solid>& solids = {});

/// Draws the control mesh's edges (U n x 3, T m x 4) as thin dark lines over an image rendered
/// with the same view.
void draw_edges(Image& img, const Eigen::Ref<const Eigen::MatrixXd>& U,
                const Eigen::Ref<const Eigen::MatrixXi>& T, const View& view,
                const Eigen::Vector3i& rgb = {40, 40, 40});

/// Textured 2D warp: triangles F with rest pixel coordinates `rest` (n x 2, x right, y down,
/// in src pixels) are drawn at `deformed` (n x 2, pixels of an out_w x out_h image), sampling src
/// bilinearly.
Image warp_image(const Image& src, const Eigen::Ref<const Eigen::MatrixXd>& rest,
                 const Eigen::Ref<const Eigen::MatrixXd>& deformed,
                 const Eigen::Ref<const Eigen::MatrixXi>& F, int out_w, int out_h);

/// Images next to each other (same height; a gap of `gap` background pixels).
Image side_by_side(const std::vector<Image>& images, int gap = 8);



}  // namespace mbi::raster
