// The page's cameras (see api.h): mbi::interact::PerspectiveCamera behind numbered handles.
#include "api.h"

#include <mbi/interact/camera_perspective.hpp>

#include <exception>
#include <map>
#include <stdexcept>
#include <string>

namespace {

using mbi::interact::PerspectiveCamera;

std::map<int, PerspectiveCamera> g_cameras;
int g_next = 0;
std::string g_error;
double g_pose[12];
float g_matrix[16];
double g_ray[6];

PerspectiveCamera& camera_of(int camera) {
  const auto found = g_cameras.find(camera);
  if (found == g_cameras.end()) throw std::out_of_range("no camera " + std::to_string(camera));
  return found->second;
}

// Runs f; on an exception keeps its message and returns `failed`.
template <class R, class F>
R guarded(F&& f, R failed) {
  g_error.clear();
  try {
    return f();
  } catch (const std::exception& e) {
    g_error = e.what();
  }
  return failed;
}

}  // namespace

extern "C" {

int mbi_camera_new(double cx, double cy, double cz, double size, double ux, double uy, double uz, double yaw,
                   double pitch) {
  return guarded(
      [=] {
        g_cameras.emplace(g_next, PerspectiveCamera({cx, cy, cz}, size, {ux, uy, uz}, yaw, pitch));
        return g_next++;
      },
      -1);
}

void mbi_camera_delete(int camera) { g_cameras.erase(camera); }

const char* mbi_camera_error(void) { return g_error.c_str(); }

int mbi_camera_orbit(int camera, double dx, double dy) {
  return guarded([=] { return camera_of(camera).orbit(dx, dy), 1; }, 0);
}

int mbi_camera_zoom(int camera, double dy) {
  return guarded([=] { return camera_of(camera).zoom(dy), 1; }, 0);
}

const double* mbi_camera_pose(int camera) {
  return guarded(
      [=] {
        const PerspectiveCamera& c = camera_of(camera);
        const PerspectiveCamera::Frame f = c.frame();
        Eigen::Map<Eigen::Vector3d>{g_pose} = c.eye();
        Eigen::Map<Eigen::Vector3d>{g_pose + 3} = f.forward;
        Eigen::Map<Eigen::Vector3d>{g_pose + 6} = f.right;
        Eigen::Map<Eigen::Vector3d>{g_pose + 9} = f.up;
        return static_cast<const double*>(g_pose);
      },
      static_cast<const double*>(nullptr));
}

const float* mbi_camera_matrix(int camera, int width, int height) {
  return guarded(
      [=] {
        Eigen::Map<Eigen::Matrix4f>{g_matrix} = camera_of(camera).view_projection(width, height).cast<float>();
        return static_cast<const float*>(g_matrix);
      },
      static_cast<const float*>(nullptr));
}

const double* mbi_camera_ray(int camera, double x, double y, int width, int height) {
  return guarded(
      [=] {
        const mbi::interact::Ray r = camera_of(camera).ray(x, y, width, height);
        Eigen::Map<Eigen::Vector3d>{g_ray} = r.origin;
        Eigen::Map<Eigen::Vector3d>{g_ray + 3} = r.direction;
        return static_cast<const double*>(g_ray);
      },
      static_cast<const double*>(nullptr));
}

}  // extern "C"
