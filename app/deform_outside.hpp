#pragma once
// mbi deform --max-outside: dense points outside the control mesh are extrapolated from their
// nearest element; beyond a tolerance relative to the model's size the command refuses them.
#include <mbi/interp/embed.hpp>

#include <Eigen/Core>

#include <string>

namespace mbi::cli {

/// Distance (in P's units) from point p to the nearest element emb.element(p) of (U, T): 0 for
/// a point inside. The embedding attaches an outside point to its nearest element, so this is
/// its distance to the mesh.
double outside_distance(const interp::Embedding& emb, const Eigen::MatrixXd& U, const Eigen::MatrixXi& T,
                        const Eigen::MatrixXd& P, int p);

/// Throws naming how many points lie farther than `tolerance` x the model size (the diagonal of
/// P's bounding box) outside the control mesh, and the worst of them.
void refuse_far_points(const interp::Embedding& emb, const Eigen::MatrixXd& U, const Eigen::MatrixXi& T,
                       const Eigen::MatrixXd& P, double tolerance, const std::string& mesh_name,
                       const std::string& control_name);

}  // namespace mbi::cli
