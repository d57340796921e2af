#pragma once
// Drawing a frame (internal): every view from the GPU evaluator's buffers, with the colliders of
// surface contact, the control wireframe, handle and poke markers; the frame's times.
#include "interaction.hpp"

#include <mbi/gpu/renderer.hpp>

namespace mbi::viewer {

/// Draws the views side by side into the window's framebuffer (fb_width x fb_height pixels);
/// X3 the control positions, n x 3. `looks`: the ground and material in 3D (scenery.hpp), false
/// for the plain looks. Updates `times`.
void draw_views(gpu::Renderer& renderer, Stage& stage, const Interaction& in, const Camera& camera,
                const ViewerOptions& options, const Eigen::MatrixXd& X3, int fb_width, int fb_height,
                FrameTimes& times, bool looks);

}  // namespace mbi::viewer
