// The page's perspective orbit camera: the ray through the pixel where a point appears passes
// through it, at any pose and viewport; the matrix agrees with project() and puts the centre
// at the view's centre; orbit and zoom stay in their ranges; bad input throws; and its numbers
// are those of the page's former JavaScript camera.
#include <catch2/catch.hpp>

#include <mbi/interact/camera_perspective.hpp>
#include <mbi/interact/error.hpp>

#include <Eigen/Geometry>

#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

using namespace mbi::interact;

namespace {

// A random camera: centre, size over six decades, up in any direction, a few drags and wheel turns.
PerspectiveCamera random_camera(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  const double size = std::pow(10.0, 3 * u(rng));
  PerspectiveCamera cam(10 * size * Eigen::Vector3d(u(rng), u(rng), u(rng)), size,
                        Eigen::Vector3d(u(rng), u(rng), u(rng)) + 0.1 * Eigen::Vector3d::UnitZ(), 3 * u(rng), u(rng));
  cam.orbit(300 * u(rng), 100 * u(rng));
  cam.zoom(500 * u(rng));
  return cam;
}

}  // namespace

TEST_CASE("perspective camera: the ray through a point's pixel passes through the point, for any pose", "[interact]") {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int pose = 0; pose < 60; ++pose) {
    const PerspectiveCamera cam = random_camera(rng);
    const int w = 200 + pose * 23, h = 150 + pose * 7;
    const auto [f, r, up] = cam.frame();
    for (int k = 0; k < 10; ++k) {
      const Eigen::Vector3d p = cam.center() + 0.5 * cam.size() * Eigen::Vector3d(u(rng), u(rng), u(rng));
      const std::optional<Eigen::Vector2d> px = cam.project(p, w, h);
      INFO("pose " << pose << " point " << k);
      REQUIRE(px.has_value());  // the model's box is in front of the eye at every distance
      const Ray ray = cam.ray(px->x(), px->y(), w, h);
      CHECK((ray.origin - cam.eye()).norm() < 1e-12 * cam.size() * 100);
      const Eigen::Vector3d d = ray.direction.normalized();
      const Eigen::Vector3d off = (p - ray.origin) - (p - ray.origin).dot(d) * d;
      CHECK(off.norm() < 1e-12 * cam.size() * 100);
      CHECK((p - ray.origin).dot(d) > 0);
      CHECK(ray.direction.dot(f) == Approx(1));  // forward plus offsets across it
      // the clip transform puts p at the same pixel
      const Eigen::Vector4d clip = cam.view_projection(w, h) * p.homogeneous();
      REQUIRE(clip.w() > 0);
      CHECK((clip.x() / clip.w() + 1) * 0.5 * w == Approx(px->x()).margin(1e-9 * w));
      CHECK((1 - clip.y() / clip.w()) * 0.5 * h == Approx(px->y()).margin(1e-9 * h));
      CHECK(std::abs(clip.z() / clip.w()) <= 1);  // between the clip planes
    }
  }
}

TEST_CASE("perspective camera: the matrix maps the centre to the view's centre, the frame is orthonormal", "[interact]") {
  std::mt19937 rng(5);
  for (int pose = 0; pose < 40; ++pose) {
    const PerspectiveCamera cam = random_camera(rng);
    const Eigen::Vector4d clip = cam.view_projection(640, 360) * cam.center().homogeneous();
    INFO("pose " << pose);
    CHECK(std::abs(clip.x() / clip.w()) < 1e-12);
    CHECK(std::abs(clip.y() / clip.w()) < 1e-12);
    CHECK(clip.w() == Approx(cam.distance()));  // w: the depth in front of the eye
    const std::optional<Eigen::Vector2d> px = cam.project(cam.center(), 640, 360);
    REQUIRE(px.has_value());
    CHECK((*px - Eigen::Vector2d(320, 180)).norm() < 1e-9);
    CHECK((cam.eye() - cam.center()).norm() == Approx(cam.distance()));
    const auto [f, r, u] = cam.frame();
    CHECK(f.norm() == Approx(1));
    CHECK(r.norm() == Approx(1));
    CHECK(u.norm() == Approx(1));
    CHECK(std::abs(f.dot(r)) < 1e-12);
    CHECK(std::abs(f.dot(u)) < 1e-12);
    CHECK(r.cross(u).dot(-f) == Approx(1));  // right-handed: right x up points back at the eye
  }
}

TEST_CASE("perspective camera: orbit and zoom stay in range, NaN and huge moves leave it finite", "[interact]") {
  const Eigen::Vector3d up(0, 0, 2);
  PerspectiveCamera cam(Eigen::Vector3d(1, 2, 3), 4, up);
  CHECK(cam.yaw() == PerspectiveCamera::kDefaultYaw);
  CHECK(cam.pitch() == PerspectiveCamera::kDefaultPitch);
  CHECK(cam.distance() == Approx(1.8 * 4));
  cam.orbit(10, 20);
  CHECK(cam.yaw() == Approx(0.6 - 0.1));
  CHECK(cam.pitch() == Approx(0.25 + 0.2));
  cam.orbit(0, 1e9);
  CHECK(cam.pitch() == 1.5);
  CHECK(cam.eye().z() > 3);  // above the centre, along up
  cam.orbit(0, -std::numeric_limits<double>::infinity());
  CHECK(cam.pitch() == -1.5);
  cam.orbit(std::numeric_limits<double>::max(), 0);
  CHECK(std::abs(cam.yaw()) <= std::acos(-1.0));
  const double yaw = cam.yaw(), pitch = cam.pitch();
  cam.orbit(std::nan(""), 5);
  cam.zoom(std::nan(""));
  CHECK(cam.yaw() == yaw);
  CHECK(cam.pitch() == pitch);
  CHECK(cam.distance() == Approx(1.8 * 4));
  cam.zoom(100);
  CHECK(cam.distance() == Approx(7.2 * std::exp(0.1)));
  cam.zoom(1e300);
  CHECK(cam.distance() == Approx(50 * 4));
  cam.zoom(-1e300);
  CHECK(cam.distance() == Approx(0.05 * 4));
  CHECK(cam.view_projection(10, 10).allFinite());
  CHECK(cam.frame().forward.allFinite());
  CHECK(PerspectiveCamera(Eigen::Vector3d::Zero(), 1, up, 0, 7).pitch() == 1.5);
}

TEST_CASE("perspective camera: bad input throws Error naming the argument", "[interact]") {
  const Eigen::Vector3d c(0, 0, 0), up(0, 1, 0);
  const double inf = std::numeric_limits<double>::infinity(), nan = std::nan("");
  CHECK_THROWS_WITH(PerspectiveCamera(c, 1, Eigen::Vector3d::Zero()), Catch::Contains("up"));
  CHECK_THROWS_AS(PerspectiveCamera(c, 1, Eigen::Vector3d(nan, 1, 0)), Error);
  for (double size : {0.0, -1.0, nan, inf, 1e-200, 1e200})
    CHECK_THROWS_WITH(PerspectiveCamera(c, size, up), Catch::Contains("size"));
  CHECK_THROWS_WITH(PerspectiveCamera(Eigen::Vector3d(inf, 0, 0), 1, up), Catch::Contains("center"));
  CHECK_THROWS_WITH(PerspectiveCamera(c, 1, up, nan, 0), Catch::Contains("yaw"));
  const PerspectiveCamera cam(c, 1, up);
  for (const auto& [w, h] : std::vector<std::array<int, 2>>{{0, 10}, {10, 0}, {-5, 10}, {10, -1}}) {
    CHECK_THROWS_WITH(cam.view_projection(w, h), Catch::Contains("viewport"));
    CHECK_THROWS_WITH(cam.ray(1, 1, w, h), Catch::Contains("viewport"));
    CHECK_THROWS_WITH(cam.project(c, w, h), Catch::Contains("viewport"));
  }
  CHECK_THROWS_WITH(cam.ray(nan, 1, 10, 10), Catch::Contains("pixel"));
  CHECK_THROWS_WITH(cam.ray(1e308, 1e308, 10, 10), Catch::Contains("pixel"));
  CHECK_THROWS_WITH(cam.project(Eigen::Vector3d(0, inf, 0), 10, 10), Catch::Contains("point"));
  CHECK_FALSE(cam.project(cam.eye(), 10, 10).has_value());  // at the eye
  CHECK_FALSE(cam.project(cam.eye() - cam.frame().forward, 10, 10).has_value());  // behind it
}

namespace {

// One pose of the page's former camera.js and what it computed there (node, doubles; the page
// rounds the matrix to floats): a 640 x 480 viewport, the ray through pixel (100, 350).
struct JsPose {
  std::array<double, 3> center;
  double size;
  std::array<double, 3> up;
  double yaw, pitch;
  std::array<double, 2> orbit;
  double zoom;
  std::array<double, 3> eye, f, r, u;
  std::array<double, 16> matrix;  // column-major
  std::array<double, 3> direction;
};

const JsPose kJsPoses[] = {
    {{0, 0, 0}, 1, {0, 1, 0}, 0.6, 0.25, {0, 0}, 0,
     {-0.98476039133616966, 0.44532712665814128, -1.4394202728591250},
     {0.54708910629787211, -0.24740395925452294, 0.79967792936618054},
     {-0.82533561490967822, 0.0000000000000000, 0.56464247339503537},
     {0.13969478348119838, 0.96891242171064484, 0.20419129884242065},
     {-2.0010642527780940, 0.45159525809694362, 0.54719853506200811, 0.54708910629787211, 0.0000000000000000,
      3.1322304545083055, -0.24745344499494790, -0.24740395925452294, 1.3690017111822588, 0.66009495847999189,
      0.79983788094721198, 0.79967792936618054, 2.6917869131719237e-16, -1.7945246087812825e-16,
      1.7803580358035807, 1.8000000000000003},
     {0.76131400874561972, -0.38477550434009100, 0.61061884818108758}},
    {{0.5, -0.25, 2}, 3, {0, 0, 1}, 0.6, 0.25, {40, -30}, 120,
     {-0.70808316429360496, 5.7096613520494417, 1.6957026776148905},
     {0.19842104586406101, -0.97884174982334360, 0.049979169270678331},
     {-0.98006657784124185, -0.19866933079506116, 0.0000000000000000},
     {-0.0099293281126987491, 0.048982913390461867, 0.99875026039496639},
     {-2.3762166067137334, -0.032098818438606472, 0.19846073404205158, 0.19842104586406101, -0.48168295272323791,
      0.15834844268099008, -0.97903753775210101, -0.97884174982334360, 0.0000000000000000, 3.2286880753722564,
      0.049989166104215811, 0.049979169270678331, 1.0676875651760569, -6.4017396308549621, 5.5857267326426303,
      5.6446036995994069},
     {0.47773476013789562, -0.92945218034590982, -0.091622758159294521}},
    {{1, 2, 3}, 0.5, {1, 1, 0}, -1.2, 0.9, {-15, 500}, -300,
     {1.4992008092477334, 2.4413448518862930, 2.9765330232872738},
     {-0.74872289901346789, -0.66194803944115466, 0.035196783558727199},
     {-0.35183586208633671, 0.35183586208633671, -0.86742322559401663},
     {-0.56180561286163078, 0.66184312282441637, 0.49632462575132374},
     {-0.85304227001445976, -1.8161648160234027, -0.74887265856922625, -0.74872289901346789, 0.85304227001445976,
      2.1395588899123541, -0.66208044228932772, -0.66194803944115466, -2.1031076054504338, 1.6044825861103458,
      0.035203823619445018, 0.035196783558727199, 5.4562805463368429, -7.2764007221323430, 2.6242908314188664,
      2.6337650258331413},
     {-0.56930464286989235, -0.85554952515447635, 0.21079331113967797}},
    {{-2, 0.1, 0.3}, 10, {1, 0, 0}, 0.6, 0.25, {250, -900}, 0,
     {-19.954909758872979, 1.3048951625363725, -0.11163478718918329},
     {0.99749498660405433, -0.066938620140909580, 0.022868599288287959},
     {0.0000000000000000, 0.32328956686350341, 0.94630008768741469},
     {0.070737201667702920, 0.94392959329117321, -0.32247972216774085},
     {0.0000000000000000, 0.22867414264242225, 0.99769450555327011, 0.99749498660405433, 0.78383046103913379,
      3.0514677619658070, -0.066952009203844060, -0.066938620140909580, 2.2943481944363819, -1.0424892736454408,
      0.022873173465563345, 0.022868599288287959, -0.76668750443482792, 0.46494829118189568, 19.798802618023053,
      19.994823255435708},
     {0.98746592879616124, -0.29243953891003366, -0.19974168807566495}},
};

Eigen::Vector3d vec(const std::array<double, 3>& a) { return {a[0], a[1], a[2]}; }

}  // namespace

TEST_CASE("perspective camera: the numbers of the page's former JavaScript camera", "[interact]") {
  int pose = 0;
  for (const JsPose& js : kJsPoses) {
    INFO("pose " << pose++);
    PerspectiveCamera cam(vec(js.center), js.size, vec(js.up), js.yaw, js.pitch);
    cam.orbit(js.orbit[0], js.orbit[1]);
    cam.zoom(js.zoom);
    const double tol = 1e-12 * js.size;
    CHECK((cam.eye() - vec(js.eye)).norm() < tol * 100);
    const auto [f, r, u] = cam.frame();
    CHECK((f - vec(js.f)).norm() < 1e-12);
    CHECK((r - vec(js.r)).norm() < 1e-12);
    CHECK((u - vec(js.u)).norm() < 1e-12);
    const Eigen::Matrix4d m = cam.view_projection(640, 480);
    const Eigen::Map<const Eigen::Matrix4d> expected(js.matrix.data());
    CHECK((m - expected).cwiseAbs().maxCoeff() < 1e-12 * expected.cwiseAbs().maxCoeff());
    const Ray ray = cam.ray(100, 350, 640, 480);
    CHECK((ray.origin - vec(js.eye)).norm() < tol * 100);
    CHECK((ray.direction - vec(js.direction)).norm() < 1e-12);
  }
}
