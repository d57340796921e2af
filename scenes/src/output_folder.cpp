#include <mbi/io/atomic_file.hpp>
#include <mbi/scenes/output_folder.hpp>

#include <algorithm>
#include <regex>

namespace fs = std::filesystem;

namespace mbi::scenes {
namespace {

// The names of the files run_scene writes into its output folder.
const std::regex& output_names() {
  static const std::regex ours(R"((mesh[0-9]*_[0-9]+\.(obj|ply)|mesh[0-9]*\.glb|control_[0-9]+\.vtk|frame_[0-9]+\.png|dense\.pc2|metrics\.json))");
  return ours;
}

// Removes the files of an earlier run (only names that run_scene writes) from `dir`, and the
// temporaries a killed run left there (".mbi-tmp.<pid>.*" of a process that is gone). A
// symbolic link under one of these names is removed itself, never followed.
void clear_outputs(const fs::path& dir) {
  std::vector<fs::path> old;
  for (const auto& e : fs::directory_iterator(dir))
    if ((e.is_symlink() || e.is_regular_file()) && std::regex_match(e.path().filename().string(), output_names()))
      old.push_back(e.path());
  for (const auto& p : old) fs::remove(p);
  io::remove_stale_temporaries(dir);
}

// An input in the output folder under one of the run's output names would be replaced (or, with
// --force, removed): refused, whatever its spelling (file identity).
void check_inputs_outside(const std::vector<fs::path>& inputs, const fs::path& dir) {
  const auto dir_id = io::file_id(dir);
  if (!dir_id) return;
  for (const fs::path& in : inputs) {
    const auto id = io::file_id(in);
    if (!id) continue;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(dir, ec)) {
      if (!std::regex_match(e.path().filename().string(), output_names())) continue;
      if (io::file_id(e.path()) == id)
        throw Error(in.string() + ": is an input and also " + e.path().string() +
                         ", a file this run writes; an input is never overwritten, not even with --force");
    }
  }
}

// A folder still to be made: its nearest existing parent must be a folder.
void check_parent(const fs::path& dir) {
  std::error_code ec;
  for (fs::path p = dir.parent_path(); !p.empty(); p = p.parent_path()) {
    const auto ps = fs::status(p, ec);
    if (fs::exists(ps)) {
      if (!fs::is_directory(ps))
        throw Error(dir.string() + ": cannot make this folder: " + p.string() + " is not a folder");
      break;
    }
    if (p == p.parent_path()) break;
  }
}

}  // namespace

fs::path output_folder(const Scene& sc, const fs::path& out_dir) {
  if (!out_dir.empty()) return out_dir;
  // The scene's name, verbatim, as one path component under out/: a downloaded scene never
  // writes outside it.
  const std::string& n = sc.name;
  const bool bad = n.empty() || n == "." || n == ".." || n.front() == '.' ||
                   n.find_first_of("/\\") != std::string::npos ||
                   std::any_of(n.begin(), n.end(), [](char c) {
                     return static_cast<unsigned char>(c) < 0x20 || c == 0x7f;
                   }) ||
                   n.size() > 200;
  if (bad) {
    std::string shown;
    for (char c : n) shown += static_cast<unsigned char>(c) < 0x20 || c == 0x7f ? '?' : c;
    throw Error(sc.file.string() + ": name = \"" + shown +
                     "\" cannot name an output folder: it must be one file name (no '/', '\\', "
                     "control characters, leading '.', at most 200 bytes); give --out DIR to "
                     "choose the folder");
  }
  return fs::path("out") / n;
}

std::vector<fs::path> input_files(const Scene& sc, const fs::path& mesh_override) {
  std::vector<fs::path> in{sc.file};
  if (!mesh_override.empty()) in.push_back(mesh_override);
  if (!sc.dense.path.empty()) in.push_back(resolve_path(sc, sc.dense.path));
  for (const DenseSpec& d : sc.more_dense) in.push_back(resolve_path(sc, d.path));
  if (!sc.dense.image.empty()) in.push_back(resolve_path(sc, sc.dense.image));
  if (!sc.control.path.empty()) {
    fs::path c = resolve_path(sc, sc.control.path);
    in.push_back(c);
    fs::path base = c;
    base.replace_extension();
    for (const char* e : {".node", ".ele"}) {
      fs::path p = base;
      p += e;
      in.push_back(p);
    }
  }
  return in;
}

namespace {
// Makes `dir` and the parents it lacks; returns those made, outermost first.
std::vector<fs::path> make_folders(const fs::path& dir) {
  std::vector<fs::path> missing;
  std::error_code ec;
  for (fs::path p = dir; !p.empty() && !fs::exists(fs::symlink_status(p, ec)); p = p.parent_path()) {
    missing.push_back(p);
    if (p == p.parent_path()) break;
  }
  std::vector<fs::path> made;
  for (auto it = missing.rbegin(); it != missing.rend(); ++it) {
    if (fs::create_directory(*it, ec)) made.push_back(*it);
    else if (ec) throw Error(dir.string() + ": cannot make this folder (" + ec.message() + ")");
  }
  return made;
}
}  // namespace

OutputFolder::OutputFolder(const Scene& sc, const fs::path& out_dir, bool force,
                           const std::vector<fs::path>& inputs)
    : path_(output_folder(sc, out_dir)), force_(force) {
  std::error_code ec;
  const auto st = fs::symlink_status(path_, ec);
  if (out_dir.empty() && fs::is_symlink(st))
    throw Error(path_.string() +
                     ": is a symbolic link; a scene's default output folder is never reached "
                     "through one (give --out to choose a folder)");
  const bool exists = fs::exists(st) || fs::is_symlink(st);
  if (exists && !fs::is_directory(path_, ec)) throw Error(path_.string() + ": exists and is not a folder");
  if (!exists) check_parent(path_);
  made_ = make_folders(path_);
  // a folder made here by a run that then loses the lock belongs to the winner: left alone
  lock_.emplace(path_);
  try {
    if (exists) check_existing(force, inputs);
  } catch (...) {
    remove_made();
    throw;
  }
}

OutputFolder::~OutputFolder() {
  if (!used_) remove_made();
}

void OutputFolder::check_existing(bool force, const std::vector<fs::path>& inputs) const {
  std::error_code ec;
  if (!fs::is_empty(path_, ec) && !force)
    throw Error(path_.string() + ": exists and is not empty (use --force to overwrite)");
  check_inputs_outside(inputs, path_);
}

void OutputFolder::remove_made() noexcept {
  std::error_code ec;  // only empty folders go (remove() does not empty one)
  for (auto it = made_.rbegin(); it != made_.rend(); ++it) fs::remove(*it, ec);
  made_.clear();
}

void OutputFolder::make() {
  used_ = true;
  if (force_) clear_outputs(path_);
}

}  // namespace mbi::scenes
