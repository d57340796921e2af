#include <mbi/viewer/layout.hpp>

#include <algorithm>
#include <cmath>

namespace mbi::viewer {

Layout make_layout(int width, int height, int fb_width, int fb_height, int views, bool panel, bool collapsed) {
  Layout l;
  const double w = std::max(width, 1), h = std::max(height, 1);
  const double pw = !panel ? 0 : collapsed ? std::min(kCollapsedWidth, w * kPanelShare) : std::min(kPanelWidth, w * kPanelShare);
  l.panel = {0, 0, pw, h};
  const int n = std::max(views, 1);
  const double sx = fb_width / w;
  // framebuffer columns are whole pixels: the views' edges are rounded there, then mapped back
  const double left_fb = std::ceil(pw * sx);
  for (int k = 0; k < n; ++k) {
    const double x0 = left_fb + std::floor((fb_width - left_fb) * k / n);
    const double x1 = left_fb + std::floor((fb_width - left_fb) * (k + 1) / n);
    l.view_viewports.push_back({x0, 0, x1 - x0, static_cast<double>(fb_height)});
    l.views.push_back({x0 / sx, 0, (x1 - x0) / sx, h});
  }
  return l;
}

bool overlap(const Rect& a, const Rect& b) {
  return a.x < b.x + b.w && b.x < a.x + a.w && a.y < b.y + b.h && b.y < a.y + a.h;
}

}  // namespace mbi::viewer
