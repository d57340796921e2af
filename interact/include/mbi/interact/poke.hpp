#pragma once
// The poke: a spring from a grabbed material point of the simulated control mesh to a target
// that the cursor moves over the drag plane.
#include <mbi/interact/pick.hpp>

#include <Eigen/Core>

namespace mbi::interact {

/// Stiffness (N/m) of a poke spring that pulls a grabbed region of mass `mass` (kg) with a
/// natural period `response` (s): k = m (2 pi / response)^2, so the response does not depend on
/// the model's mass or size. A negative mass counts as 0, a response below 1e-6 s as 1e-6 s.
double poke_stiffness(double mass, double response);

/// The drag plane: where the ray meets the plane through `grab` with normal `normal` (the view
/// direction; the ray's own direction for a perspective camera), moved back toward `grab` to at
/// most `max_distance` (model units) from it, so that a flick or a drag far off screen never asks
/// for an unbounded force. A ray parallel to the plane, or one gone non-finite (a cursor
/// far outside the window), leaves `grab`. O(1).
/// Throws Error on a zero or non-finite direction of the ray or the normal, on a non-finite
/// grab, on a max_distance that is negative or NaN.
Eigen::Vector3d poke_target(const Ray& ray, const Eigen::Vector3d& grab, const Eigen::Vector3d& normal,
                            double max_distance);

/// A poke spring's attachment to the control mesh.
struct Grab {
  int element = -1;                                  ///< row of T
  Eigen::Vector4d bary = Eigen::Vector4d::Zero();    ///< the material point in that element (sum 1)
  Eigen::Vector3d point = Eigen::Vector3d::Zero();   ///< the hit point (deformed): the first target
  double stiffness = 0;                              ///< N/m, poke_stiffness of the element's mass
};

/// The material point under `hit` of the deformed dense surface (rest positions V n x 3, F t x 3):
/// its rest position, embedded in the control mesh (U m x 3 rest, T k x 4 tetrahedra), with the
/// spring of poke_stiffness(mass of the element's four vertices, response). `masses` (m, kg) are
/// the simulator's lumped masses. O(k) (the embedding). Throws Error on a hit whose face is not a
/// row of F, on masses of the wrong size or a T without 4 columns; interp::Error from embedding.
Grab grab(const Hit& hit, const Eigen::Ref<const Eigen::MatrixXd>& V, const Eigen::Ref<const Eigen::MatrixXi>& F,
          const Eigen::Ref<const Eigen::MatrixXd>& U, const Eigen::Ref<const Eigen::MatrixXi>& T,
          const Eigen::Ref<const Eigen::VectorXd>& masses, double response);

}  // namespace mbi::interact
