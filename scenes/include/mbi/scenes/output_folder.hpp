#pragma once
// The folder a run writes into, and the rules that keep a run from harming anything else: a
// scene's default folder is out/<its name> and nothing outside; an existing folder is
// overwritten only with --force, and then only the files a run writes are removed; an input of
// the run is never an output, not even with --force; one run at a time writes into a folder.
#include <mbi/io/folder_lock.hpp>
#include <mbi/scenes/scene.hpp>

#include <filesystem>
#include <optional>
#include <vector>

namespace mbi::scenes {

/// The output folder of a run: `out_dir` when given, else "out/<scene name>". The name must be
/// one safe file name (no '/', '\\', control characters, leading '.'); otherwise Error
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
  /// folder (or nothing yet) as its nearest existing parent, and is made now. Then the folder is
  /// locked (io::FolderLock) until this object goes: a folder another run (or mbi command)
  /// writes into is refused at once, naming that process. Throws Error / io::Error naming
  /// the path.
  OutputFolder(const Scene& scene, const std::filesystem::path& out_dir, bool force,
               const std::vector<std::filesystem::path>& inputs);
  /// A folder made here into which nothing was written (make() never called: the run failed or
  /// was interrupted while loading) is removed again, with the parents made for it.
  ~OutputFolder();
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;

  const std::filesystem::path& path() const { return path_; }

  /// Readies the folder for the first frame. With `force`, first removes what an earlier run
  /// wrote there (only the names a run writes, and the temporaries a killed run left), so that
  /// no extra frames of it stay beside the new ones.
  void make();

 private:
  void check_existing(bool force, const std::vector<std::filesystem::path>& inputs) const;
  void remove_made() noexcept;

  std::filesystem::path path_;
  bool force_ = false;
  bool used_ = false;
  std::vector<std::filesystem::path> made_;  // folders made here, outermost first
  std::optional<io::FolderLock> lock_;
};

}  // namespace mbi::scenes
