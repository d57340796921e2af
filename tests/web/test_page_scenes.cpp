// The page's scenes: the scene files of scenes/ built in verbatim, the page running those it can
// as `mbi run` builds them, and saying why not the others.
#include <catch2/catch.hpp>

#include <mbi/interp/embed.hpp>
#include <mbi/scenes/models.hpp>
#include <mbi/web/page_model.hpp>
#include <mbi/web/scene_files.hpp>

#include "common/files.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>
#include <string>

using mbi::web::PageModel;

namespace {

const mbi::web::SceneFile* find(const std::string& name) {
  for (const mbi::web::SceneFile& f : mbi::web::scene_files())
    if (f.name == name) return &f;
  return nullptr;
}

}  // namespace

TEST_CASE("the page's scene files are the files of scenes/, verbatim", "[web]") {
  std::set<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(mbi::test::source_dir() / "scenes")) {
    if (e.path().extension() != ".toml") continue;
    const std::string name = e.path().stem().string();
    names.insert(name);
    const mbi::web::SceneFile* f = find(name);
    INFO(name);
    REQUIRE(f != nullptr);
    CHECK(f->text == mbi::test::slurp(e.path()));
  }
  CHECK(names.size() == mbi::web::scene_files().size());
  CHECK(names.count("twist-bar") == 1);
}

TEST_CASE("the page runs the simulated 3D scenes and says why not the others", "[web]") {
  for (const mbi::web::SceneFile& f : mbi::web::scene_files()) {
    const mbi::scenes::Scene s = mbi::web::parse(f);
    const bool runs = s.mode == mbi::scenes::Mode::Simulate && s.dense.builtin != mbi::scenes::DenseBuiltin::ImageGrid;
    INFO(f.name);
    CHECK(mbi::web::page_problem(s).empty() == runs);
  }
  CHECK_THAT(mbi::web::page_problem(mbi::web::parse(*find("image-warp"))), Catch::Contains("2D"));
  CHECK_THAT(mbi::web::page_problem(mbi::web::parse(*find("drag"))), Catch::Contains("keyframes"));
  CHECK_THROWS_WITH(PageModel::scene(mbi::web::parse(*find("drag"))),
                    Catch::Contains("scenes/drag.toml: the page cannot run this scene"));
}

TEST_CASE("a scene that names a model file is refused on the page, naming the scene", "[web]") {
  const mbi::scenes::Scene s =
      mbi::scenes::parse_scene("[dense]\npath = \"bunny.obj\"\n[control]\ngenerate_vertices = 100\n", "scenes/mine.toml");
  CHECK_THAT(mbi::web::page_problem(s), Catch::Contains("model files"));
  CHECK_THROWS_WITH(PageModel::scene(s), Catch::Contains("scenes/mine.toml") && Catch::Contains("file system"));
}

TEST_CASE("the page's poke scene moves as mbi run builds it, scripted pokes included", "[web]") {
  const mbi::scenes::Scene s = mbi::web::parse(*find("poke"));
  PageModel page = PageModel::scene(s);  // frame 0 computed
  const mbi::scenes::SceneModels m = mbi::scenes::load_models(s);
  mbi::pipeline::FramePipeline run = mbi::scenes::make_pipeline(s, m, mbi::interp::embed(m.U, m.T, m.dense.V));
  run.step();
  const Eigen::MatrixXd rest = run.positions();
  for (int k = 0; k < 6; ++k) {
    REQUIRE(page.step());
    run.step();
  }
  REQUIRE(page.frame() == run.frame());
  const Eigen::MatrixXd& P = run.positions();
  const std::vector<float>& drawn = page.positions(mbi::web::View::ModifiedBI);
  REQUIRE(drawn.size() == static_cast<std::size_t>(P.size()));
  double worst = 0;
  for (Eigen::Index i = 0; i < P.rows(); ++i)
    for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(drawn[static_cast<std::size_t>(3 * i + c)] - P(i, c)));
  CHECK(worst <= 1e-6 * (1 + P.cwiseAbs().maxCoeff()));  // float round-off
  CHECK((P - rest).cwiseAbs().maxCoeff() > 1e-3);       // the scripted spring pulled (from frame 1)
}
