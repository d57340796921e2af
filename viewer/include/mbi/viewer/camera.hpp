#pragma once
// The viewer's camera, picking and pokes: those of mbi::interact (the page's too), by the
// viewer's names.
#include <mbi/interact/camera.hpp>
#include <mbi/interact/pick.hpp>
#include <mbi/interact/poke.hpp>

namespace mbi::viewer {

using interact::Camera;
using interact::cast;
using interact::Hit;
using interact::poke_stiffness;
using interact::poke_target;
using interact::Ray;
using interact::window_from_framebuffer;

}  // namespace mbi::viewer
