// MeshLevelSet in a build without OpenVDB (MBI_WITH_OPENVDB=OFF, e.g. the browser's): the
// constructor refuses, so no object exists and the other members are never reached.
#include <mbi/error.hpp>
#include <mbi/pipeline/mesh_level_set.hpp>

namespace mbi::pipeline {

struct MeshLevelSet::Grid {
  Eigen::AlignedBox3d bounds;
  Eigen::MatrixXd vertices;
  Eigen::MatrixXi triangles;
};

namespace {
[[noreturn]] void unavailable() {
  throw Error("MeshLevelSet: this build has no OpenVDB (configure with MBI_WITH_OPENVDB=ON)");
}
}  // namespace

MeshLevelSet::MeshLevelSet(const Eigen::Ref<const Eigen::MatrixXd>&, const Eigen::Ref<const Eigen::MatrixXi>&,
                           const MeshLevelSetOptions&) {
  unavailable();
}
double MeshLevelSet::default_voxel_size(const Eigen::Ref<const Eigen::MatrixXd>&) { unavailable(); }
LevelSetSample MeshLevelSet::sample(const Eigen::Vector3d&) const { unavailable(); }
LevelSetSample MeshLevelSet::sample(const Eigen::Vector3d&, const sim::RigidMotion&, double) const { unavailable(); }
double MeshLevelSet::voxel_size() const { unavailable(); }
double MeshLevelSet::band() const { unavailable(); }
const Eigen::AlignedBox3d& MeshLevelSet::bounds() const { return grid_->bounds; }
const Eigen::MatrixXd& MeshLevelSet::vertices() const { return grid_->vertices; }
const Eigen::MatrixXi& MeshLevelSet::triangles() const { return grid_->triangles; }
long MeshLevelSet::active_voxels() const { unavailable(); }
double MeshLevelSet::lipschitz() const { unavailable(); }

}  // namespace mbi::pipeline
