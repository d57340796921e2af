// The page module's native twin: the same C API (api.cpp) in a native build, for the browser
// test and the bench report.
//   mbi-web-twin replay <journal> <out.bin> [<folder>]   replays the page's calls (one a line:
//       the function's name without mbi_, then its numbers; `load_scene_text NAME` reads the
//       scene file NAME given to the page from <folder>), then writes both views' positions
//       (float32, BI then modified-BI) and prints the discontinuity table's means and the
//       touching points
//   mbi-web-twin frames <scene> <n>           n frames of a scene file (its name, e.g. twist-bar):
//                                             mean ms per phase
//   mbi-web-twin solve <n>                    ms per modified-BI solve at 448 control vertices
#include "api.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

namespace {

// load_scene_text NAME: the scene file the page was given, read from `folder`.
bool load_text(const std::string& name, const std::filesystem::path& folder) {
  std::ifstream in(folder / name, std::ios::binary);
  if (!in) return std::fprintf(stderr, "mbi-web-twin: cannot read %s\n", (folder / name).string().c_str()), false;
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return mbi_load_scene_text(text.data(), static_cast<int>(text.size()), name.c_str()) == 1;
}

// Replays one journal line; false (with a message) when the call failed.
bool call(const std::string& line, const std::filesystem::path& folder) {
  std::istringstream in(line);
  std::string f;
  in >> f;
  if (f == "load_scene_text") {
    std::string name;
    std::getline(in >> std::ws, name);  // the rest of the line: a file name may hold spaces
    const bool ok = load_text(name, folder);
    if (!ok) std::fprintf(stderr, "mbi-web-twin: %s: %s\n", line.c_str(), mbi_error());
    return ok;
  }
  std::vector<double> a;
  for (double x; in >> x;) a.push_back(x);
  a.resize(7, 0.0);
  const auto i = [&](int k) { return static_cast<int>(a[static_cast<std::size_t>(k)]); };
  bool ok = true;
  if (f == "load_scene") ok = mbi_load_scene(i(0)) == 1;
  else if (f == "step") ok = mbi_step() >= 0;
  else if (f == "reset") ok = mbi_reset() == 1;
  else if (f == "set_method") ok = mbi_set_method(i(0)) == 1;
  else if (f == "set_alpha") ok = mbi_set_alpha(a[0]) == 1;
  else if (f == "grab") mbi_grab(i(0), a[1], a[2], a[3], a[4], a[5], a[6]);
  else if (f == "move") mbi_move(a[0], a[1], a[2], a[3], a[4], a[5]);
  else if (f == "release") mbi_release();
  else if (f == "set_cpu_evaluation") ok = mbi_set_cpu_evaluation(i(0)) == 1;
  else if (!f.empty()) {
    std::fprintf(stderr, "mbi-web-twin: unknown call '%s'\n", f.c_str());
    return false;
  }
  if (!ok) std::fprintf(stderr, "mbi-web-twin: %s: %s\n", line.c_str(), mbi_error());
  return ok;
}

int replay(const char* journal, const char* out, const std::filesystem::path& folder) {
  std::ifstream in(journal);
  if (!in) return std::fprintf(stderr, "mbi-web-twin: cannot read %s\n", journal), 1;
  int calls = 0;
  for (std::string line; std::getline(in, line); ++calls)
    if (!call(line, folder)) return 1;
  std::FILE* f = std::fopen(out, "wb");
  if (!f) return std::fprintf(stderr, "mbi-web-twin: cannot write %s\n", out), 1;
  const std::size_t n = 3 * static_cast<std::size_t>(mbi_vertex_count());
  const bool ok = std::fwrite(mbi_positions(0), sizeof(float), n, f) == n &&
                  std::fwrite(mbi_positions(1), sizeof(float), n, f) == n;
  if (std::fclose(f) != 0 || !ok) return std::fprintf(stderr, "mbi-web-twin: cannot write %s\n", out), 1;
  std::printf("replayed %d calls: %s\n", calls, mbi_description());
  const double* table = mbi_discontinuity();
  if (!table) return std::fprintf(stderr, "mbi-web-twin: %s\n", mbi_error()), 1;
  std::printf("table: BI mean %.17g modified-BI mean %.17g\n", table[0], table[2]);
  std::printf("touching: %d\n", mbi_touching_points());
  return 0;
}

int frames(const std::string& name, int n) {
  int scene = 0;
  while (scene < mbi_scene_count() && name != mbi_scene_name(scene)) ++scene;
  if (mbi_load_scene(scene) != 1) return std::fprintf(stderr, "mbi-web-twin: %s: %s\n", name.c_str(), mbi_error()), 1;
  double sum[5] = {0, 0, 0, 0, 0};
  for (int k = 0; k < n; ++k) {
    if (mbi_step() < 0) return std::fprintf(stderr, "mbi-web-twin: %s\n", mbi_error()), 1;
    for (int p = 0; p < 5; ++p) sum[p] += mbi_times()[p];
  }
  std::printf("%s, %d frames: ms per frame: drive %.3f solve %.3f bezier %.3f evaluate %.3f "
              "(pipeline %.3f), other view %.3f\n",
              mbi_description(), n, sum[0] / n, sum[1] / n, sum[2] / n, sum[3] / n,
              (sum[0] + sum[1] + sum[2] + sum[3]) / n, sum[4] / n);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string what = argc > 1 ? argv[1] : "";
  if (what == "replay" && (argc == 4 || argc == 5)) return replay(argv[2], argv[3], argc == 5 ? argv[4] : ".");
  if (what == "frames" && argc == 4) return frames(argv[2], std::stoi(argv[3]));
  if (what == "solve" && argc == 3) {
    std::printf("modified-BI solve at 448 control vertices: %.4f ms\n", mbi_bench_solve(std::stoi(argv[2])));
    return 0;
  }
  std::fprintf(stderr, "usage: mbi-web-twin replay <journal> <out.bin> [<folder>] | frames <scene> <n> | solve <n>\n");
  return 2;
}
