#pragma once
// Drawing a frame (internal): every view from the GPU evaluator's buffers, with the control
// wireframe, handle and poke markers; the frame's times; the picture read back.
#include "interaction.hpp"

#include <mbi/gpu/renderer.hpp>

namespace mbi::viewer {

class Scenery;

/// Draws the views side by side into the window's framebuffer (fb_width x fb_height pixels);
/// X3 the control positions, n x 3. `scenery`: the looks' ground and material (3D), nullptr for
/// the plain looks. Updates `times`.
void draw_views(gpu::Renderer& renderer, Stage& stage, const Interaction& in, const Camera& camera,
                const ViewerOptions& options, const Eigen::MatrixXd& X3, int fb_width, int fb_height,
                FrameTimes& times, Scenery* scenery);

/// The framebuffer's picture (RGB, top row first).
io::Image read_framebuffer(int width, int height);

}  // namespace mbi::viewer
