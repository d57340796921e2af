#pragma once
// The files a run writes frame by frame into its folder: the point cache of every frame
// (dense.pc2) and, at the written frames, the dense mesh (one file a frame, or the frames of one
// animated mesh.glb), the control mesh as VTK and the 2D pictures (3D pictures: Pictures3D).
// Several dense models ([[dense]]) are written each on its own: mesh1_NNNN.obj, mesh2_NNNN.obj
// (or mesh1.glb, mesh2.glb), numbered in the scene's order; dense.pc2 holds all their points.
#include <mbi/io/io.hpp>
#include <mbi/scenes/runner.hpp>

#include <Eigen/Core>

#include <filesystem>
#include <memory>
#include <vector>

namespace mbi::scenes {

class Outputs {
 public:
  Outputs(const Scene& sc, const SceneModels& m, const std::filesystem::path& dir);
  /// Frame `frame` of frames 0..last is written (meshes, VTK, pictures): every output.every, and
  /// the last.
  bool due(int frame, int last) const { return frame % sc_.output.every == 0 || frame == last; }

  /// Every frame: the point cache of `dense` (the run's method). Written frames: mesh (with
  /// `normals` when given), control VTK of Xc, and in 2D the picture (`shown`: the panels'
  /// positions, BI | the run's method | boundary-pinned). All of them or, when one cannot be
  /// written (throws), none: the frame's files written before are removed again.
  void frame(int f, const Eigen::MatrixXd& Xc, const Eigen::MatrixXd& dense,
             const std::vector<const Eigen::MatrixXd*>& shown, bool write_now,
             const Eigen::MatrixXd* normals);
  /// Completes the point cache and the animated glTF.
  void finish();

 private:
  void append_pc2(const Eigen::MatrixXd& dense);
  void append_gltf(int f, const Eigen::MatrixXd& dense, const Eigen::MatrixXd* normals);
  /// These return the paths written.
  std::vector<std::filesystem::path> write_mesh(int f, const Eigen::MatrixXd& dense, const Eigen::MatrixXd* normals);
  std::filesystem::path write_picture_2d(int f, const std::vector<const Eigen::MatrixXd*>& shown);
  const Scene& sc_;
  const SceneModels& m_;
  std::filesystem::path dir_;
  std::unique_ptr<io::Pc2Writer> pc2_;
  // mesh_format = "glb": the written frames, one file a dense model (mesh.glb, or mesh1.glb ...)
  std::vector<std::unique_ptr<io::GltfWriter>> gltf_;
  Eigen::MatrixXd flat_;  // a flat 2D model's positions with its z, for the point cache
};

}  // namespace mbi::scenes
