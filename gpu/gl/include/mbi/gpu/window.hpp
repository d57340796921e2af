#pragma once
// Drawing into a window's framebuffer (the viewer's, made by GLFW): clearing it, the viewport of
// each view, waiting for the frame, reading its back buffer. Needs the window's context current.
#include <mbi/gpu/context.hpp>
#include <mbi/io/image.hpp>

#include <Eigen/Core>

namespace mbi::gpu {

/// Binds the window's framebuffer, sets the viewport to all of it (width x height pixels) and
/// clears its colour to `rgb` (0..1, opaque) and its depth. Throws Error for a negative size.
void clear_window(int width, int height, const Eigen::Vector3d& rgb);
/// Later draws go into the pixels [x, x + width) x [y, y + height) of the bound framebuffer,
/// from its lower left corner. Throws Error for a negative size.
void viewport(int x, int y, int width, int height);
/// Waits until every command so far has run (a frame timed whole).
void finish();
/// The window's back buffer as read_picture gives it: width x height pixels from the lower left
/// corner, RGB with the top row first. Throws Error for a negative size.
io::Image read_window(int width, int height);

}  // namespace mbi::gpu
