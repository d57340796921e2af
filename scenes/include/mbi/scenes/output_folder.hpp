#pragma once
// The folder a run writes into, and the rules that keep a run from harming anything else: a
// scene's default folder is out/<its name> and nothing outside; an existing folder is
// overwritten only with --force, and then only the files a run writes are removed; an input of
// the run is never an output, not even with --force.
#include <mbi/scenes/scene.hpp>

#include <filesystem>
#include <vector>

namespace mbi::scenes {

/// The output folder of a run: `out_dir` when given, else "out/<scene name>". The name must be
/// one safe file name (no '/', '\\', control characters, leading '.'); otherwise SceneError
/// (a downloaded scene never writes outside out/).
std::filesystem::path output_folder(const Scene& scene, const std::filesystem::path& out_dir);

/// The files a run of `scene` reads (with `mesh_override` for its dense model): the scene file,
/// the dense model and its image, the control mesh with its TetGen companions (.node, .ele).
std::vector<std::filesystem::path> input_files(const Scene& scene,
                                               const std::filesystem::path& mesh_override);

class OutputFolder {
 public:
  /// The folder output_folder(scene, out_dir), checked before any work: the default folder is
  /// not reached through a symbolic link; an existing one is a folder, empty unless `force`, and
  /// holds none of `inputs` (by file identity) under a name the run writes; a new one has a
  /// folder (or nothing yet) as its nearest existing parent. Throws SceneError naming the path.
  OutputFolder(const Scene& scene, const std::filesystem::path& out_dir, bool force,
               const std::vector<std::filesystem::path>& inputs);

  const std::filesystem::path& path() const { return path_; }

  /// Makes the folder. With `force`, first removes what an earlier run wrote there (only the
  /// names a run writes, and the temporaries a killed run left), so that no extra frames of it
  /// stay beside the new ones.
  void make() const;

 private:
  std::filesystem::path path_;
  bool force_ = false;
};

}  // namespace mbi::scenes
