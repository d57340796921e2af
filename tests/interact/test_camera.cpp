// The orbit camera's maths: the ray under a projected point passes through it, at any pose,
// window and scale; the frame is orthonormal; the clip transform agrees with project().
#include <catch2/catch.hpp>

#include <mbi/interact/camera.hpp>

#include <Eigen/Geometry>

#include <cmath>
#include <random>

using namespace mbi::interact;

TEST_CASE("camera: project then ray passes through the point (round trip), for any pose", "[interact]") {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int pose = 0; pose < 50; ++pose) {
    Camera cam;
    const Eigen::Vector3d lo(u(rng), u(rng), u(rng));
    const double scale = std::pow(10.0, 3 * u(rng));  // boxes from 1e-3 to 1e3
    cam.frame(lo * scale, (lo + Eigen::Vector3d(1.5, 1, 0.5) + Eigen::Vector3d::Constant(1 + u(rng))) * scale,
              pose % 2 ? Eigen::Vector3d::UnitY() : Eigen::Vector3d::UnitZ());
    cam.orbit(300 * u(rng), 100 * u(rng));
    cam.zoom(5 * u(rng));
    const int w = 300 + pose * 17, h = 200 + pose * 11;
    cam.pan(40 * u(rng), 40 * u(rng), h);
    for (int k = 0; k < 10; ++k) {
      const Eigen::Vector3d p = cam.target + cam.radius * Eigen::Vector3d(u(rng), u(rng), u(rng));
      const Eigen::Vector2d px = cam.project(p, w, h);
      const Ray r = cam.ray(px.x(), px.y(), w, h);
      INFO("pose " << pose << " point " << k);
      CHECK((r.direction - cam.direction()).norm() < 1e-12);
      // p lies on the ray: its distance from the line, relative to the view's size
      const Eigen::Vector3d off = (p - r.origin) - (p - r.origin).dot(r.direction) * r.direction;
      CHECK(off.norm() < 1e-12 * cam.radius * 10);
      CHECK((p - r.origin).dot(r.direction) > 0);  // in front of the eye
      // unproject: the ray's points project back to the same pixel
      const Eigen::Vector2d back = cam.project(r.origin + 3 * cam.radius * r.direction, w, h);
      CHECK((back - px).norm() < 1e-9 * (w + h));
      // the clip transform agrees with project() (orthographic: w = 1)
      const Eigen::Vector4d clip = cam.view_projection(double(w) / h) * p.homogeneous();
      CHECK((clip.x() + 1) * 0.5 * w == Approx(px.x()).margin(1e-9 * w));
      CHECK((1 - clip.y()) * 0.5 * h == Approx(px.y()).margin(1e-9 * h));
      // HiDPI: a framebuffer pixel at scale 2 is the same window point
      CHECK((window_from_framebuffer(2 * px, 2) - px).norm() < 1e-12 * (w + h));
    }
  }
}

TEST_CASE("camera: direction, up and right are an orthonormal frame, up toward the world's up", "[interact]") {
  Camera cam;
  for (double yaw : {-3.0, -1.0, 0.0, 0.6, 2.5})
    for (double pitch : {-1.5, -0.4, 0.0, 0.35, 1.5}) {
      cam.yaw = yaw, cam.pitch = pitch;
      const Eigen::Vector3d f = cam.direction(), u = cam.up(), r = cam.right();
      INFO(yaw << " " << pitch);
      CHECK(std::abs(f.norm() - 1) < 1e-12);
      CHECK(std::abs(u.norm() - 1) < 1e-12);
      CHECK(std::abs(r.norm() - 1) < 1e-12);
      CHECK(std::abs(f.dot(u)) < 1e-12);
      CHECK(std::abs(f.dot(r)) < 1e-12);
      CHECK(u.dot(cam.world_up) > 0);
      CHECK(r.cross(u).dot(f) < 0);  // right-handed: right x up points toward the eye
    }
}
