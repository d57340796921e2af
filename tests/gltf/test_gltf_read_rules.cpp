// What a glTF asset may ask of the reader: buffers and images only from the asset's folder or
// below (percent-encodings decoded, symbolic links followed; a property test draws uris and
// watches with inotify that no file outside is opened), required extensions that mbi
// implements, and the component types the spec allows for each accessor's use.
#include <mbi/io/io.hpp>

#include "common/files.hpp"
#include "common/run_mbi.hpp"
#include "common/temp_dir.hpp"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <sys/inotify.h>
#include <unistd.h>

#include <climits>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <random>
#include <string>

namespace fs = std::filesystem;
using mbi::test::TempDir;
using nlohmann::json;

namespace {

// One triangle: 3 float positions then 3 uint16 indices (and 2 bytes of padding), 44 bytes.
std::string triangle_bytes(float shift = 0) {
  const float p[9] = {shift, 0, 0, shift + 1, 0, 0, shift, 1, 0};
  const std::uint16_t idx[4] = {0, 1, 2, 0};
  std::string bytes(44, '\0');
  std::memcpy(bytes.data(), p, 36);
  std::memcpy(bytes.data() + 36, idx, 8);
  return bytes;
}

// The asset of one triangle whose buffer is the file `uri`.
json triangle_asset(const std::string& uri) {
  json j = json::parse(R"({
    "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
    "nodes": [{"name": "tri", "mesh": 0}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
    "accessors": [
      {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
      {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}],
    "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 6}]})");
  j["buffers"] = json::array({{{"byteLength", 44}, {"uri", uri}}});
  return j;
}

fs::path write_json(const fs::path& p, const json& j) {
  std::ofstream(p) << j.dump();
  return p;
}

std::string error_of(const fs::path& p) {
  try {
    mbi::io::read_surface(p);
  } catch (const mbi::io::Error& e) {
    return e.what();
  }
  return "no error";
}

// root/in.bin and root/secret.bin lie outside the asset's folder root/asset, which holds
// in.bin, sub/in.bin, link_up -> .. (out), link_sub -> sub, link_in -> sub/in.bin and
// sub/link_out -> ../../in.bin (out).
struct Folders {
  TempDir root{"gltf_confine"};
  fs::path asset = root / "asset";
  Folders() {
    fs::create_directories(asset / "sub");
    for (const fs::path& p : {root / "in.bin", root / "secret.bin", asset / "in.bin", asset / "sub" / "in.bin"})
      std::ofstream(p, std::ios::binary) << triangle_bytes(p.parent_path() == root.path() ? 1000 : 0);
    fs::create_directory_symlink("..", asset / "link_up");
    fs::create_directory_symlink("sub", asset / "link_sub");
    fs::create_symlink("sub/in.bin", asset / "link_in");
    fs::create_symlink("../../in.bin", asset / "sub" / "link_out");
  }
};

// Reports whether any of the watched files was opened since the last call.
class OpenWatch {
 public:
  explicit OpenWatch(std::initializer_list<fs::path> files) : fd_(inotify_init1(IN_NONBLOCK)) {
    REQUIRE(fd_ >= 0);
    for (const fs::path& f : files) REQUIRE(inotify_add_watch(fd_, f.c_str(), IN_OPEN) >= 0);
  }
  ~OpenWatch() { close(fd_); }
  bool opened() {
    alignas(inotify_event) char buf[4096];
    bool any = false;
    while (read(fd_, buf, sizeof buf) > 0) any = true;
    return any;
  }

 private:
  int fd_;
};

}  // namespace

TEST_CASE("glTF in: buffers and images only from the asset's folder or below", "[io][gltf]") {
  Folders f;
  const fs::path t = f.asset / "t.gltf";
  OpenWatch watch({f.root / "in.bin", f.root / "secret.bin"});
  // inside: read, whatever the spelling
  for (const char* uri : {"in.bin", "sub/in.bin", "sub/../in.bin", "./in.bin", "sub%2Fin.bin", "%69n.bin", "link_in",
                          "link_sub/in.bin"}) {
    INFO(uri);
    CHECK(mbi::io::read_surface(write_json(t, triangle_asset(uri))).V.rows() == 3);
  }
  CHECK_FALSE(watch.opened());
  // outside: refused by name before anything is read
  const std::string absolute_inside = (f.asset / "in.bin").string();
  for (const std::string& uri : std::vector<std::string>{"../in.bin", "../secret.bin", "../../../../../../../../../../../../etc/passwd",
                                "%2e%2e/in.bin", "%2E%2E%2Fin.bin", "..%2fsecret.bin", "sub/../../in.bin",
                                "link_up/in.bin", "link_sub/link_out", "sub/link_out", "/etc/passwd",
                                absolute_inside, "file:///etc/passwd", "in%2.bin", "in%00.bin"}) {
    INFO(uri);
    CHECK_THAT(error_of(write_json(t, triangle_asset(uri))),
               Catch::Contains("t.gltf: buffer 0: uri '" + uri + "' is not read"));
  }
  CHECK_FALSE(watch.opened());
  // the issue's case: a second buffer outside, copied into the output through an image
  json copied = triangle_asset("in.bin");
  copied["buffers"].push_back({{"byteLength", 44}, {"uri", "../secret.bin"}});
  copied["bufferViews"].push_back({{"buffer", 1}, {"byteOffset", 0}, {"byteLength", 44}});
  copied["images"] = json::array({{{"bufferView", 2}, {"mimeType", "image/png"}}});
  copied["textures"] = json::array({{{"source", 0}}});
  copied["materials"] = json::array({{{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}}});
  copied["meshes"][0]["primitives"][0]["material"] = 0;
  CHECK_THAT(error_of(write_json(t, copied)), Catch::Contains("t.gltf: buffer 1: uri '../secret.bin' is not read"));
  // images given by uri are written back as they are: confined too
  json image = triangle_asset("in.bin");
  image["images"] = json::array({{{"uri", "tex.png"}}, {{"uri", "../../secret.png"}}});
  CHECK_THAT(error_of(write_json(t, image)), Catch::Contains("t.gltf: image 1: uri '../../secret.png' is not read"));
  image["images"][1]["uri"] = "sub/tex%20one.png";  // need not exist: it is not read
  CHECK(mbi::io::read_surface(write_json(t, image)).V.rows() == 3);
  // a .glb's external buffer follows the same rule
  const std::string text = triangle_asset("../secret.bin").dump();
  std::string glb = "glTF";
  const auto le32 = [&](std::uint32_t v) { glb.append(reinterpret_cast<const char*>(&v), 4); };
  const std::string padded = text + std::string((4 - text.size() % 4) % 4, ' ');
  le32(2);
  le32(static_cast<std::uint32_t>(20 + padded.size()));
  le32(static_cast<std::uint32_t>(padded.size()));
  le32(0x4E4F534A);
  glb += padded;
  std::ofstream(f.asset / "t.glb", std::ios::binary) << glb;
  CHECK_THAT(error_of(f.asset / "t.glb"), Catch::Contains("t.glb: buffer 0: uri '../secret.bin' is not read"));
  CHECK_FALSE(watch.opened());
}

TEST_CASE("mbi deform: a glTF whose image buffer lies outside its folder is refused, nothing written", "[io][gltf]") {
  Folders f;
  // one tetrahedron around the triangle, at rest
  std::ofstream(f.root / "cage.node") << "4 3 0 0\n1 -1 -1 -1\n2 3 -1 -1\n3 -1 3 -1\n4 -1 -1 3\n";
  std::ofstream(f.root / "cage.ele") << "1 4 0\n1 1 2 3 4\n";
  json asset = triangle_asset("in.bin");
  asset["buffers"].push_back({{"byteLength", 44}, {"uri", "in.bin"}});
  asset["bufferViews"].push_back({{"buffer", 1}, {"byteOffset", 0}, {"byteLength", 44}});
  asset["images"] = json::array({{{"bufferView", 2}, {"mimeType", "image/png"}}});
  asset["textures"] = json::array({{{"source", 0}}});
  asset["materials"] = json::array({{{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}}});
  asset["meshes"][0]["primitives"][0]["material"] = 0;
  write_json(f.asset / "t.gltf", asset);
  const std::string deform = "deform --method bi --control cage --deformed cage.node --mesh asset/t.gltf --out out.glb";
  auto r = mbi::test::run_mbi(deform, f.root, "", f.root.path());
  INFO(r.err);
  REQUIRE(r.code == 0);  // the image's bytes travel into the output
  CHECK(mbi::test::slurp(f.root / "out.glb").find(triangle_bytes()) != std::string::npos);
  fs::remove(f.root / "out.glb");
  asset["buffers"][1]["uri"] = "../secret.bin";  // the same bytes, outside the asset's folder
  write_json(f.asset / "t.gltf", asset);
  r = mbi::test::run_mbi(deform, f.root, "", f.root.path());
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("t.gltf: buffer 1: uri '../secret.bin' is not read"));
  CHECK_FALSE(fs::exists(f.root / "out.glb"));
}

TEST_CASE("glTF in: drawn buffer uris are read exactly when they name a file in the asset's folder", "[io][gltf]") {
  Folders f;
  const fs::path t = f.asset / "t.gltf";
  OpenWatch watch({f.root / "in.bin", f.root / "secret.bin"});
  char real_asset[PATH_MAX];
  REQUIRE(realpath(f.asset.c_str(), real_asset));
  const std::string inside = std::string(real_asset) + "/";
  const std::vector<std::string> dirs = {"..", ".", "sub", "link_up", "link_sub", "asset"};
  const std::vector<std::string> names = {"in.bin", "secret.bin", "link_in", "link_out"};
  std::mt19937 rng(41);
  int read = 0, refused = 0;
  for (int draw = 0; draw < 400; ++draw) {
    // a path of 0 to 4 folders and a file name: the oracle is the kernel's realpath
    std::string plain;
    for (int k = static_cast<int>(rng() % 5); k > 0; --k) plain += dirs[rng() % dirs.size()] + "/";
    plain += names[rng() % names.size()];
    if (rng() % 8 == 0) plain = f.root.path().string() + "/" + plain;  // absolute: always refused
    // the uri: each character percent-encoded at random, in either case
    std::string uri;
    for (char c : plain) {
      if (rng() % 3 == 0) {
        char hex[4];
        std::snprintf(hex, sizeof hex, rng() % 2 ? "%%%02X" : "%%%02x", static_cast<unsigned char>(c));
        uri += hex;
      } else {
        uri += c;
      }
    }
    char real[PATH_MAX];
    const bool exists = plain[0] != '/' && realpath((f.asset / plain).c_str(), real) && fs::is_regular_file(real);
    const bool expect_read = exists && std::string(real).rfind(inside, 0) == 0;
    INFO("uri " << uri << " (" << plain << ")");
    const std::string e = error_of(write_json(t, triangle_asset(uri)));
    CHECK((e == "no error") == expect_read);
    // refused by the rule, or (a folder missing on the way) not found
    if (!expect_read)
      CHECK_THAT(e, Catch::Contains("t.gltf: buffer 0: uri '" + uri.substr(0, 60)) || Catch::Contains("File not found"));
    CHECK_FALSE(watch.opened());
    (expect_read ? read : refused) += 1;
  }
  CHECK(read > 20);  // both outcomes drawn often
  CHECK(refused > 20);
}

TEST_CASE("glTF in: required extensions that mbi does not implement are refused by name", "[io][gltf]") {
  Folders f;
  const fs::path t = f.asset / "t.gltf";
  // instancing: three boxes in the file, one read if it were ignored
  json instanced = triangle_asset("in.bin");
  instanced["extensionsUsed"] = instanced["extensionsRequired"] = {"EXT_mesh_gpu_instancing"};
  instanced["nodes"][0]["extensions"] = {{"EXT_mesh_gpu_instancing", {{"attributes", {{"TRANSLATION", 0}}}}}};
  CHECK_THAT(error_of(write_json(t, instanced)),
             Catch::Contains("t.gltf: extension 'EXT_mesh_gpu_instancing' is required and mbi does not implement it"));
  // Draco: the accessors have no bufferView, the data is in the extension
  json draco = triangle_asset("in.bin");
  draco["extensionsUsed"] = draco["extensionsRequired"] = {"KHR_draco_mesh_compression"};
  draco["accessors"][1].erase("bufferView");
  draco["meshes"][0]["primitives"][0]["extensions"] = {
      {"KHR_draco_mesh_compression", {{"bufferView", 0}, {"attributes", {{"POSITION", 0}}}}}};
  CHECK_THAT(error_of(write_json(t, draco)), Catch::Contains("t.gltf: extension 'KHR_draco_mesh_compression' is required"));
  json meshopt = triangle_asset("in.bin");
  meshopt["extensionsUsed"] = meshopt["extensionsRequired"] = {"EXT_meshopt_compression"};
  meshopt["bufferViews"][0]["extensions"] = {{"EXT_meshopt_compression", {{"buffer", 0}, {"byteLength", 36}}}};
  CHECK_THAT(error_of(write_json(t, meshopt)), Catch::Contains("t.gltf: extension 'EXT_meshopt_compression' is required"));
  json unused = triangle_asset("in.bin");  // required but nowhere used: not one mbi knows
  unused["extensionsUsed"] = unused["extensionsRequired"] = {"EXT_unknown"};
  CHECK_THAT(error_of(write_json(t, unused)), Catch::Contains("extension 'EXT_unknown' is required"));
  // kept: a material's extension is written back as it is
  json transform = triangle_asset("in.bin");
  transform["extensionsUsed"] = transform["extensionsRequired"] = {"KHR_texture_transform"};
  transform["images"] = json::array({{{"uri", "tex.png"}}});
  transform["textures"] = json::array({{{"source", 0}}});
  transform["materials"] = json::array({{{"pbrMetallicRoughness",
                                          {{"baseColorTexture",
                                            {{"index", 0}, {"extensions", {{"KHR_texture_transform", {{"scale", {2, 2}}}}}}}}}}}});
  transform["meshes"][0]["primitives"][0]["material"] = 0;
  const mbi::io::SurfaceMesh m = mbi::io::read_surface(write_json(t, transform));
  CHECK(m.V.rows() == 3);
  mbi::io::write_surface(f.asset / "out.gltf", m);
  std::ifstream in(f.asset / "out.gltf");
  const json out = json::parse(in);
  CHECK(out["extensionsRequired"] == json({"KHR_texture_transform"}));
}

TEST_CASE("glTF in: each accessor's component type is one the spec allows for its use", "[io][gltf]") {
  Folders f;
  const fs::path t = f.asset / "t.gltf";
  // signed int (5124) is no glTF type: read as unsigned it tore the model 4e8 away
  json int_positions = triangle_asset("in.bin");
  int_positions["accessors"][0]["componentType"] = 5124;
  CHECK_THAT(error_of(write_json(t, int_positions)),
             Catch::Contains("POSITION: accessor 0: component type 5124 is not allowed for this use by glTF 2.0 (allowed: float;"));
  json int_indices = triangle_asset("in.bin");
  int_indices["accessors"][1]["componentType"] = 5124;
  int_indices["bufferViews"][1]["byteLength"] = 8;
  CHECK_THAT(error_of(write_json(t, int_indices)), Catch::Contains("indices: accessor 1: component type 5124"));
  json normalized_float = triangle_asset("in.bin");
  normalized_float["accessors"][0]["normalized"] = true;
  CHECK_THAT(error_of(write_json(t, normalized_float)), Catch::Contains("component type 5126 (float normalized) is not allowed"));
  // quantized positions: only with KHR_mesh_quantization
  // (0,0,0) (7,0,0) (0,9,0) as unsigned shorts, each padded to 8 bytes, then the indices
  const std::uint16_t q[12] = {0, 0, 0, 0, 7, 0, 0, 0, 0, 9, 0, 0};
  std::string bytes(24, '\0');
  std::memcpy(bytes.data(), q, 24);
  std::ofstream(f.asset / "q.bin", std::ios::binary) << bytes << triangle_bytes().substr(36);
  json quantized = triangle_asset("q.bin");
  quantized["buffers"][0]["byteLength"] = 32;
  quantized["accessors"][0] = {{"bufferView", 0}, {"componentType", 5123}, {"count", 3}, {"type", "VEC3"}};
  quantized["bufferViews"][0] = {{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 24}, {"byteStride", 8}};
  quantized["bufferViews"][1]["byteOffset"] = 24;
  CHECK_THAT(error_of(write_json(t, quantized)), Catch::Contains("more with KHR_mesh_quantization in extensionsUsed"));
  quantized["extensionsUsed"] = quantized["extensionsRequired"] = {"KHR_mesh_quantization"};
  const mbi::io::SurfaceMesh m = mbi::io::read_surface(write_json(t, quantized));
  REQUIRE(m.V.rows() == 3);
  CHECK(m.V.row(1) == Eigen::RowVector3d(7, 0, 0));
  CHECK(m.V.row(2) == Eigen::RowVector3d(0, 9, 0));
  // texture coordinates: float or normalized unsigned; colours likewise
  json uv = triangle_asset("in.bin");
  uv["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = 2;
  uv["accessors"].push_back({{"bufferView", 0}, {"componentType", 5121}, {"count", 3}, {"type", "VEC2"}});
  CHECK_THAT(error_of(write_json(t, uv)), Catch::Contains("TEXCOORD_0: accessor 2: component type 5121 (unsigned byte) is not allowed"));
  uv["accessors"][2]["normalized"] = true;
  CHECK(mbi::io::read_surface(write_json(t, uv)).V.rows() == 3);
  json color = triangle_asset("in.bin");
  color["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"] = 2;
  color["accessors"].push_back({{"bufferView", 0}, {"componentType", 5122}, {"normalized", true}, {"count", 3}, {"type", "VEC4"}});
  CHECK_THAT(error_of(write_json(t, color)), Catch::Contains("COLOR_0: accessor 2: component type 5122 (short normalized) is not allowed"));
}

TEST_CASE("glTF in: JSON nested deeper than 64 levels is refused before tinygltf recurses into it", "[io][gltf]") {
  Folders f;
  const fs::path t = f.asset / "t.gltf";
  const auto nested = [&](int depth) {
    std::string text = triangle_asset("in.bin").dump();
    text.pop_back();
    return text + ", \"extras\": " + std::string(static_cast<std::size_t>(depth), '[') +
           std::string(static_cast<std::size_t>(depth), ']') + "}";
  };
  std::ofstream(t) << nested(60);  // within the limit with the asset's own levels
  CHECK(mbi::io::read_surface(t).V.rows() == 3);
  std::ofstream(t) << nested(200000);  // overflowed the stack in tinygltf's conversion of extras
  CHECK_THAT(error_of(t), Catch::Contains("t.gltf: the JSON nests arrays and objects deeper than 64 levels"));
}
