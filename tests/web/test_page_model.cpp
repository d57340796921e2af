// The page's pokes pick as the viewer does (mbi::interact): rays through the shared vertices
// and edges of the drawn surface grab, where an exact ray cast loses some of them.
#include <catch2/catch.hpp>

#include <mbi/interact/error.hpp>
#include <mbi/interact/pick.hpp>
#include <mbi/web/page_model.hpp>

#include "common/tilted_grid.hpp"

using mbi::web::PageModel;
using mbi::web::View;

TEST_CASE("page pokes: rays through shared vertices and edges grab (the viewer's pick slack)", "[web]") {
  const mbi::test::TiltedGrid g = mbi::test::tilted_grid(8);
  PageModel page = PageModel::surface(g.V, g.F, 60);  // frame 1 without gravity: at rest
  const Eigen::Vector3d eye = mbi::test::TiltedGrid::kEye;
  int exact_misses = 0;
  for (const Eigen::Vector3d& p : g.shared_points()) {
    const mbi::interact::Ray ray{eye, p - eye};
    exact_misses += !mbi::interact::cast(ray, g.V, g.F, 0.0);
    INFO("through " << p.transpose());
    CHECK(page.grab(View::ModifiedBI, ray));
    page.release();
  }
  CHECK(exact_misses > 0);  // the rays the slack is for
  CHECK_FALSE(page.grab(View::BI, {eye, -(g.at(4, 4) - eye)}));  // away from the model
  CHECK_THROWS_AS(page.grab(View::BI, {eye, Eigen::Vector3d::Zero()}), mbi::interact::Error);
}
