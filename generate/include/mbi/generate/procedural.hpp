#pragma once
// Built-in procedural meshes, so that the shipped scenes need no downloads.
// Units are whatever the scene uses (metres in the shipped scenes). All outputs are plain
// Eigen matrices: V n x 3 (or n x 2 in 2D), F f x 3 triangles (outward, counter-clockwise seen
// from outside), T m x 4 tetrahedra (positive volume) or m x 3 triangles in 2D.
#include <mbi/io/image.hpp>

#include <Eigen/Core>

namespace mbi::generate {

/// Triangulated surface of the box [lo, hi] with n = (nx, ny, nz) cells per side; vertices on
/// shared edges and corners are welded. Vertex count 2(nx ny + ny nz + nz nx) + 2.
void box_surface(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, const Eigen::Vector3i& n,
                 Eigen::MatrixXd& V, Eigen::MatrixXi& F);

/// Tetrahedral mesh of the box [lo, hi] with n cells per side, each cell split into 6
/// tetrahedra sharing its main diagonal (conforming across cells).
void box_tets(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, const Eigen::Vector3i& n,
              Eigen::MatrixXd& V, Eigen::MatrixXi& T);

/// The paper's bar (Figure 1): a 1 x 1 x 6 bar along +z from z = 0.
/// Control mesh: 7 cross-sections of 5 vertices (4 corners + centre) = 35 vertices, each of the
/// 6 segments split into 4 prisms around the centre line, 3 tetrahedra each = 72 tetrahedra.
void paper_bar_control(Eigen::MatrixXd& U, Eigen::MatrixXi& T);
/// Dense surface of the same bar: 30 x 30 x 180 cells, 23,402 vertices.
void paper_bar_surface(Eigen::MatrixXd& V, Eigen::MatrixXi& F);

/// Closed cylinder along +z from z = 0 to length, radius r: `around` segments, `along` rings of
/// the side, `cap_rings` concentric rings on each cap.
void cylinder_surface(double radius, double length, int around, int along, int cap_rings,
                      Eigen::MatrixXd& V, Eigen::MatrixXi& F);

/// Dense bumpy sphere of radius r for throughput tests: a cube grid of n x n cells per face
/// projected to the sphere, with a smooth radial bump pattern of relative amplitude `bump`.
/// Vertex count 6 n^2 + 2 (n = 205 gives 252,152).
void bumpy_sphere(double radius, int n, double bump, Eigen::MatrixXd& V, Eigen::MatrixXi& F);

/// 2D grid over [0, width] x [0, height] with nx x ny cells, each split into two triangles
/// (counter-clockwise). V is (nx+1)(ny+1) x 2, row-major from the bottom-left corner.
void grid_2d(double width, double height, int nx, int ny, Eigen::MatrixXd& V,
             Eigen::MatrixXi& F);

/// Smooth twist-and-bend of points about the z axis through (cx, cy): a point at height z is
/// rotated by angle * (z - z0) / (z1 - z0) (radians, clamped to [0, 1] of the range), then
/// bent: x += bend * ((z - z0) / (z1 - z0))^2 * (z1 - z0). Used by the built-in examples.
Eigen::MatrixXd twist_bend(const Eigen::Ref<const Eigen::MatrixXd>& P, double cx, double cy,
                           double z0, double z1, double angle, double bend);

/// Jacobian of twist_bend at each point: (p 3) x 3, rows [i 3, i 3 + 3) hold dX_i / dP_i. At
/// heights in [z0, z1] (ends included) the twisting branch is differentiated; outside it, the
/// clamped rigid one. For accuracy checks against the closed form.
Eigen::MatrixXd twist_bend_jacobian(const Eigen::Ref<const Eigen::MatrixXd>& P, double cx,
                                    double cy, double z0, double z1, double angle, double bend);

/// A procedural checkerboard-with-rings test picture (when a scene names no image).
io::Image test_pattern(int width, int height);

}  // namespace mbi::generate
