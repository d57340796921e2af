// The 3D pictures of `mbi run` show the scene's colliders and ground: a contact scene's pictures
// have collider-coloured pixels where the collider stands at that frame, above the model, and the
// ground's grey under it, in both panels (BI, modified-BI), drawn by the CPU and by the GPU; the
// ground neither moves the camera nor covers the model, and a scene without colliders draws the
// model alone.
#include <catch2/catch.hpp>

#include <mbi/io/io.hpp>
#include <mbi/scenes/runner.hpp>

#include "common/temp_dir.hpp"
#include "scenes/contact_ball.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using namespace mbi::scenes;
using mbi::io::Image;

namespace {

// The ball (radius 0.5 about the origin) held still (no gravity) in a generated cage, two frames
// written, with `more` (colliders, ground) and `gpu` ("off" or "on").
std::string still_ball(const std::string& contact, const std::string& more, const std::string& gpu) {
  return "[dense]\npath = \"" + mbi::test::ball_file() + "\"\n[control]\ngenerate_vertices = 60\n"
         "[simulation]\ndt = 0.0333333\nframes = 2\ngravity = [0, 0, 0]\ncontact = \"" + contact + "\"\n" + more +
         "[interpolation]\nmethod = \"modified-bi\"\ngpu = \"" + gpu + "\"\n"
         "[output]\nevery = 1\nmesh_format = \"none\"\ncontrol_vtk = false\n";
}

// A sphere collider 0.05 above the ball's top, rising at 3 m/s; the ground 0.05 under the ball.
const std::string kRising = "ground = -0.55\n[[colliders]]\nshape = \"sphere\"\ncenter = [0, 0.95, 0]\nradius = 0.4\n"
                            "motion = { velocity = [0, 3, 0] }\n";

// Runs `text`; the pictures' folder.
fs::path run_picture_text(const std::string& text, const mbi::test::TempDir& dir, const std::string& name) {
  return mbi::test::run_scene_text(text, dir, name);
}

Image picture(const fs::path& out, int frame) { return mbi::io::read_png(mbi::io::frame_path(out / "frame", frame, ".png")); }

// The model is orange (red well above blue), a collider slate grey (blue above red), the ground
// grey (red = green = blue); the background white.
bool model(const std::uint8_t* p) { return p[0] > p[2] + 15; }
bool collider(const std::uint8_t* p) { return p[2] > p[0] + 4 && p[2] < 250; }
bool ground(const std::uint8_t* p) { return p[0] == p[1] && p[1] == p[2] && p[0] < 250; }
bool white(const std::uint8_t* p) { return p[0] == 255 && p[1] == 255 && p[2] == 255; }

// What a panel (columns x0 .. x0 + width - 1) shows: the model's top and bottom rows, the
// collider's lowest row, and the collider pixels above the model and the ground pixels below it.
struct Panel {
  int model_top = 1 << 30, model_bottom = -1, collider_bottom = -1;
  int collider_above = 0, ground_below = 0, model_pixels = 0, other = 0;
};

Panel look(const Image& img, int x0, int width) {
  Panel p;
  for (int y = 0; y < img.height; ++y)
    for (int x = x0; x < x0 + width; ++x)
      if (model(img.at(x, y))) p.model_top = std::min(p.model_top, y), p.model_bottom = std::max(p.model_bottom, y), ++p.model_pixels;
  for (int y = 0; y < img.height; ++y)
    for (int x = x0; x < x0 + width; ++x) {
      const std::uint8_t* c = img.at(x, y);
      if (collider(c)) p.collider_bottom = std::max(p.collider_bottom, y);
      if (collider(c) && y < p.model_top) ++p.collider_above;
      if (ground(c) && y > p.model_bottom) ++p.ground_below;
      if (!model(c) && !white(c)) ++p.other;
    }
  return p;
}

// The panels of a BI | modified-BI picture: their left columns and width (8 pixels between).
std::vector<int> panel_starts(const Image& img, int& width) {
  width = (img.width - 8) / 2;
  return {0, width + 8};
}

}  // namespace

TEST_CASE("pictures: a contact scene shows its collider at each frame's pose above the model and the ground under it",
          "[scenes][pictures]") {
  mbi::test::TempDir dir("pictures-contact");
  for (const std::string gpu : {"off", "on"}) {  // the CPU rasteriser, the GPU renderer (CI: Mesa llvmpipe)
    INFO("gpu = " << gpu);
    const fs::path out = run_picture_text(still_ball("surface", kRising, gpu), dir, "rising-" + gpu);
    const Image first = picture(out, 0), last = picture(out, 2);
    int width = 0;
    for (int x0 : panel_starts(first, width)) {
      INFO("panel at column " << x0);
      const Panel a = look(first, x0, width), b = look(last, x0, width);
      CHECK(a.model_pixels > 5000);
      CHECK(a.collider_above > 500);
      CHECK(a.ground_below > 500);
      CHECK(b.collider_above > 500);
      // the collider rose 0.2 m between the frames: its lowest pixels are higher up the picture
      CHECK(b.collider_bottom < a.collider_bottom - 5);
    }
  }
}

// The model's pixels of `a` are those of `b`; where `a` is white, `b` is white or ground.
void same_model(const Image& a, const Image& b, bool background_kept) {
  REQUIRE(a.width == b.width);
  REQUIRE(a.height == b.height);
  long model_same = 0, model_total = 0, background_ok = 0, background = 0;
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x) {
      const std::uint8_t *p = a.at(x, y), *q = b.at(x, y);
      if (model(p)) ++model_total, model_same += std::equal(p, p + 3, q);
      if (white(p)) ++background, background_ok += white(q) || ground(q);
    }
  CHECK(model_total > 10000);
  CHECK(model_same == model_total);
  if (background_kept) CHECK(background_ok == background);
}

TEST_CASE("pictures: the ground and a large collider far from the model move neither the camera nor the model, "
          "and without colliders the model is alone",
          "[scenes][pictures]") {
  mbi::test::TempDir dir("pictures-ground");
  const fs::path bare = run_picture_text(still_ball("control", "", "off"), dir, "bare");
  const fs::path floor = run_picture_text(still_ball("surface", "ground = -0.55\n", "off"), dir, "floor");
  const fs::path far = run_picture_text(still_ball("surface", "[[colliders]]\nshape = \"box\"\ncenter = [0, -30, 0]\n"
                                                      "half_extents = [20, 20, 20]\n", "off"), dir, "far");
  const Image a = picture(bare, 2), b = picture(floor, 2);
  int width = 0;
  for (int x0 : panel_starts(a, width)) {
    INFO("panel at column " << x0);
    const Panel p = look(a, x0, width);
    CHECK(p.model_pixels > 5000);
    CHECK(p.other == 0);  // nothing but the model on white
    CHECK(look(b, x0, width).ground_below > 500);
  }
  same_model(a, b, true);
  same_model(a, picture(far, 2), false);  // the box may show far behind the model
}
