#pragma once
// The pictures of `output.creases` (internal): the dense surface shaded like raster::render_mesh
// but coloured per vertex, and the legend bar drawn under the panels. CPU only: the GPU
// renderer draws one colour.
#include <mbi/io/image.hpp>
#include <mbi/raster/raster.hpp>

#include <Eigen/Core>

namespace mbi::scenes {

/// V n x 3, F f x 3, C n x 3 colours (0..1) through `view` (raster's framing) into width x
/// height, white background, headlight Lambert + ambient shading.
io::Image render_colored(const Eigen::Ref<const Eigen::MatrixXd>& V, const Eigen::Ref<const Eigen::MatrixXi>& F,
                         const Eigen::Ref<const Eigen::MatrixXd>& C, const raster::View& view, int width, int height);

/// The legend under the panels: a strip `width` wide, the colour bar from 0 (left end, "0")
/// to `top` (right end, its value), crease_color's scale.
io::Image crease_legend(int width, double top);

/// `top` above `bottom`, left-aligned, on white; as wide as the wider.
io::Image stack(const io::Image& top, const io::Image& bottom);

}  // namespace mbi::scenes
