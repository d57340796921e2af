#pragma once
// Where the viewer puts things: the panel docked at the left edge, the 3D views side by side in
// the rest of the window, never under the panel. A pure function of the window's size (logical
// pixels, as GLFW and ImGui count them) and its framebuffer's (pixels: HiDPI screens have more),
// so it is the same on every screen and testable without one.
#include <vector>

namespace mbi::viewer {

/// A rectangle: x, y from the window's top-left corner, width w, height h.
struct Rect {
  double x = 0, y = 0, w = 0, h = 0;
};

struct Layout {
  Rect panel;               ///< logical pixels; w = 0 without a panel
  std::vector<Rect> views;  ///< logical pixels, left to right
  /// The views in framebuffer pixels for gpu::viewport: x, y from the bottom-left corner.
  std::vector<Rect> view_viewports;
};

/// Panel width (logical pixels) when open, at most kPanelShare of the window; a strip of
/// kCollapsedWidth when collapsed.
inline constexpr double kPanelWidth = 380, kPanelShare = 0.4, kCollapsedWidth = 60;

/// The layout of `views` views (>= 1) in a window of `width` x `height` logical pixels whose
/// framebuffer is `fb_width` x `fb_height` pixels, with the panel open, collapsed or absent.
Layout make_layout(int width, int height, int fb_width, int fb_height, int views, bool panel, bool collapsed);

/// True when the two rectangles share an area (touching edges do not).
bool overlap(const Rect& a, const Rect& b);

}  // namespace mbi::viewer
