// The page's scenes: the scene files of scenes/ built in verbatim, the page running those it can
// as `mbi run` builds them, and saying why not the others; contact at the dense surface on the
// page as in `mbi run` (tests/data/scenes/page-contact.toml), its colliders drawn where they are.
#include <catch2/catch.hpp>

#include <mbi/interp/embed.hpp>
#include <mbi/io/io.hpp>
#include <mbi/scenes/models.hpp>
#include <mbi/web/page_model.hpp>
#include <mbi/web/scene_files.hpp>

#include "common/files.hpp"
#include "common/run_mbi.hpp"
#include "common/temp_dir.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
#include <string>

using mbi::web::PageModel;
using mbi::pipeline::ColliderShape;

namespace {

const mbi::web::SceneFile* find(const std::string& name) {
  for (const mbi::web::SceneFile& f : mbi::web::scene_files())
    if (f.name == name) return &f;
  return nullptr;
}

bool has_mesh_collider(const mbi::scenes::Scene& s) {
  return std::any_of(s.colliders.begin(), s.colliders.end(), [](const mbi::pipeline::Collider& c) { return c.shape == ColliderShape::Mesh; });
}

// The page's contact scene: the paper bar sagging onto a capsule and a box, a sphere rising into
// it, a ground plane; its messages name "page-contact.toml" as the page's file input does.
mbi::scenes::Scene contact_scene() {
  const std::string text = mbi::test::slurp(mbi::test::source_dir() / "tests/data/scenes/page-contact.toml");
  REQUIRE_FALSE(text.empty());
  return mbi::scenes::parse_scene(text, "page-contact.toml");
}

// Largest difference of the page's floats (x y z per vertex) and P (n x 3).
double largest_difference(const std::vector<float>& drawn, const Eigen::MatrixXd& P) {
  REQUIRE(drawn.size() == static_cast<std::size_t>(P.size()));
  double worst = 0;
  for (Eigen::Index i = 0; i < P.rows(); ++i)
    for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(drawn[static_cast<std::size_t>(3 * i + c)] - P(i, c)));
  return worst;
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
    const bool runs = s.mode == mbi::scenes::Mode::Simulate && s.dense.builtin != mbi::scenes::DenseBuiltin::ImageGrid &&
                      !has_mesh_collider(s);
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
  const double worst = largest_difference(page.positions(mbi::web::View::ModifiedBI), P);
  CHECK(worst <= 1e-6 * (1 + P.cwiseAbs().maxCoeff()));  // float round-off
  CHECK((P - rest).cwiseAbs().maxCoeff() > 1e-3);       // the scripted spring pulled (from frame 1)
}

TEST_CASE("the page runs contact at the dense surface as mbi run does: positions and touching points", "[web][contact]") {
  const mbi::scenes::Scene s = contact_scene();
  REQUIRE(mbi::web::page_problem(s).empty());
  const int frames = 12;
  PageModel page = PageModel::scene(s);  // frame 0 computed
  for (int k = 0; k < frames; ++k) REQUIRE(page.step());
  REQUIRE(page.frame() == frames);

  // `mbi run` as a user runs it, on the same file
  const mbi::test::TempDir dir("page-contact");
  const std::filesystem::path out = dir / "run";
  const mbi::test::Result r =
      mbi::test::run_mbi("run " + mbi::test::q(mbi::test::source_dir() / "tests/data/scenes/page-contact.toml") +
                             " --out " + mbi::test::q(out) + " --frames " + std::to_string(frames) + " --gpu off",
                         dir);
  REQUIRE(r.code == 0);
  const mbi::io::PointCache cache = mbi::io::read_pc2(out / "dense.pc2");
  REQUIRE(cache.frames.size() == static_cast<std::size_t>(frames + 1));
  std::ifstream in(out / "metrics.json");
  const nlohmann::json metrics = nlohmann::json::parse(in);

  const Eigen::MatrixXd& P = cache.frames.back();
  const double worst = largest_difference(page.positions(mbi::web::View::ModifiedBI), P);
  CHECK(worst <= 1e-6 * (1 + P.cwiseAbs().maxCoeff()));  // float round-off: the same computation
  CHECK((P - cache.frames.front()).cwiseAbs().maxCoeff() > 0.05);  // the bar moved
  const int touching = metrics["frames"].back()["contact_points"].get<int>();
  CHECK(page.touching_points() == touching);
  CHECK(touching > 0);
  CHECK(page.colliders() == 4);  // sphere, capsule, box, then the ground
}

TEST_CASE("the page draws the colliders where they are, the moving sphere where it has moved", "[web][contact]") {
  const mbi::scenes::Scene s = contact_scene();
  PageModel page = PageModel::scene(s);
  for (int k = 0; k < 9; ++k) REQUIRE(page.step());  // 0.3 s: the sphere has risen 0.27 m
  const double t = 9 * s.simulation.parameters.dt;
  const mbi::web::Triangles& drawn = page.update_collider_mesh();
  REQUIRE(drawn.positions.size() % 3 == 0);
  const std::size_t vertices = drawn.positions.size() / 3;
  REQUIRE(vertices > 100);
  // the distance of vertex v to the nearest collider surface at time `when`
  const auto nearest = [&](std::size_t v, double when) {
    const Eigen::Vector3d p(drawn.positions[3 * v], drawn.positions[3 * v + 1], drawn.positions[3 * v + 2]);
    double d = std::numeric_limits<double>::infinity();
    for (const mbi::pipeline::Collider& c : s.colliders) d = std::min(d, std::abs(mbi::pipeline::signed_distance(c, p, when).value));
    return d;
  };
  double off = 0, off_at_rest = 0;
  for (std::size_t v = 0; v < vertices; ++v) {
    off = std::max(off, nearest(v, t));
    off_at_rest = std::max(off_at_rest, nearest(v, 0));
  }
  CHECK(off <= 1e-5);          // every vertex on a collider's surface now (float round-off)
  CHECK(off_at_rest > 0.2);    // the sphere's not where it started
  REQUIRE(drawn.indices.size() % 3 == 0);
  for (const int i : drawn.indices) REQUIRE((i >= 0 && static_cast<std::size_t>(i) < vertices));
}

TEST_CASE("a mesh collider is refused on the page, naming its key", "[web][contact]") {
  mbi::scenes::Scene s = contact_scene();
  mbi::pipeline::Collider mesh;
  mesh.shape = ColliderShape::Mesh;  // as a scene file's shape = "mesh" gives it (no OpenVDB here)
  s.colliders.insert(s.colliders.begin() + 1, mesh);
  const std::string why = mbi::web::page_problem(s);
  CHECK_THAT(why, Catch::Contains("colliders[1].shape = \"mesh\"") && Catch::Contains("OpenVDB"));
  CHECK_THROWS_WITH(PageModel::scene(s), Catch::Contains("page-contact.toml: the page cannot run this scene") &&
                                             Catch::Contains("colliders[1].shape"));
}
