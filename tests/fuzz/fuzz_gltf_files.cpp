// libFuzzer target: the glTF reader with buffers in files (mbi::io::parse_surface) (docs/hardening.md; seeds in tests/fuzz/gltf_files/).
// The input is the asset (.gltf text or .glb), read as asset/fuzz.gltf of a temporary tree:
// asset/ holds in.bin, sub/in.bin, link_in -> sub/in.bin, link_sub -> sub; outside it lie
// in.bin and secret.bin, reached by link_up -> .. and sub/link_out -> ../../in.bin. An open of
// an outside file (watched with inotify) breaks the rule that files stay in the asset's folder.
#include "fuzz_common.hpp"

#include <sys/inotify.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

namespace {

namespace fs = std::filesystem;

// A valid triangle: 3 float positions, 3 uint16 indices and 2 bytes of padding (44 bytes).
std::string triangle() {
  const float p[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const std::uint16_t idx[4] = {0, 1, 2, 0};
  std::string bytes(44, '\0');
  std::memcpy(bytes.data(), p, 36);
  std::memcpy(bytes.data() + 36, idx, 8);
  return bytes;
}

struct Tree {
  fs::path root, asset;
  int watch = -1;  // inotify: opens of the files outside asset/
  Tree() {
    char name[] = "/tmp/mbi-fuzz-gltf-XXXXXX";
    mbi::fuzz::invariant(mkdtemp(name) != nullptr, "mkdtemp");
    root = name;
    asset = root / "asset";
    fs::create_directories(asset / "sub");
    for (const fs::path& p : {root / "in.bin", root / "secret.bin", asset / "in.bin", asset / "sub" / "in.bin"})
      std::ofstream(p, std::ios::binary) << triangle();
    fs::create_directory_symlink("..", asset / "link_up");
    fs::create_directory_symlink("sub", asset / "link_sub");
    fs::create_symlink("sub/in.bin", asset / "link_in");
    fs::create_symlink("../../in.bin", asset / "sub" / "link_out");
    watch = inotify_init1(IN_NONBLOCK);
    mbi::fuzz::invariant(watch >= 0, "inotify_init1");
    for (const fs::path& p : {root / "in.bin", root / "secret.bin"})
      mbi::fuzz::invariant(inotify_add_watch(watch, p.c_str(), IN_OPEN) >= 0, "inotify_add_watch");
  }
  ~Tree() {
    close(watch);
    std::error_code ec;
    fs::remove_all(root, ec);
  }
  bool outside_opened() const {
    alignas(inotify_event) char buf[4096];
    bool any = false;
    while (read(watch, buf, sizeof buf) > 0) any = true;
    return any;
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const Tree tree;
  const std::string_view in = mbi::fuzz::bytes(data, size);
  try {
    mbi::fuzz::check_surface(mbi::io::parse_surface(in, tree.asset / "fuzz.gltf"));
  } catch (const mbi::io::Error&) {
  }
  mbi::fuzz::invariant(!tree.outside_opened(), "a file outside the asset's folder was opened");
  return 0;
}
