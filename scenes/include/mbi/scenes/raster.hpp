#pragma once
// A small CPU rasteriser for headless pictures: shaded triangle meshes (the paper's Figure 1,
// BI beside modified-BI) and textured 2D warps (image-warp scene). PNG via stb.
// The GPU path (gpu/) renders the same pictures faster; this one needs no GL at all.
#include <Eigen/Core>

#include <cstdint>
#include <filesystem>
#include <vector>

namespace mbi::scenes {

/// 8-bit RGB image, row 0 at the top.
struct Image {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;  ///< width * height * 3
  Image() = default;
  Image(int w, int h, Eigen::Vector3i background = {255, 255, 255});
  std::uint8_t* at(int x, int y) { return rgb.data() + (static_cast<size_t>(y) * width + x) * 3; }
  const std::uint8_t* at(int x, int y) const {
    return rgb.data() + (static_cast<size_t>(y) * width + x) * 3;
  }
};

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

/// Renders V (n x 3), F (f x 3) with a z-buffer and per-vertex normals (area weighted) under a
/// headlight with Lambert + ambient shading in `color` (0..1). Shading reveals creases, so BI's
/// first-order discontinuities show up.
Image render_mesh(const Eigen::Ref<const Eigen::MatrixXd>& V,
                  const Eigen::Ref<const Eigen::MatrixXi>& F, const View& view, int width,
                  int height, const Eigen::Vector3d& color = {0.85, 0.62, 0.35});

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

/// A procedural checkerboard-with-rings test picture (when a scene names no image).
Image test_pattern(int width, int height);

/// PNG read/write (stb). write_png is atomic. Throws IoError naming the file.
Image read_png(const std::filesystem::path& file);
void write_png(const std::filesystem::path& file, const Image& img);

}  // namespace mbi::scenes
