#pragma once
// The ImGui windows (internal): the panel (statistics and phase times, playback, method and view
// switches, alpha, the simulation's parameters and material, the poke's response) and the help.
#include "interaction.hpp"

namespace mbi::viewer {

/// Draws this frame's ImGui windows over the views: the panel when options.panel, the help when
/// controls.help. Edits through them take effect at once.
void draw_gui(Stage& stage, Interaction& in, ViewerOptions& options, Controls& controls, const FrameTimes& times,
              const WindowSize& window);

}  // namespace mbi::viewer
