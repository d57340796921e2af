// The checks made on a glTF asset's JSON before tinygltf reads it: files named by uris stay in
// the asset's folder, and the required extensions are ones mbi implements.
#include "format_gltf_check.hpp"

#include "io_common.hpp"

#include <tiny_gltf.h>

#include <algorithm>
#include <cctype>
#include <set>

namespace mbi::io::detail {
namespace {

namespace fs = std::filesystem;

// A uri as it may appear in a message: a long one (a data URI) cut short.
std::string shown(const std::string& uri) {
  return "'" + (uri.size() > 80 ? uri.substr(0, 77) + "..." : uri) + "'";
}

int hex(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

// RFC 3986 percent-decoding; false on a '%' not followed by two hex digits, or a decoded NUL.
bool percent_decode(const std::string& uri, std::string& out) {
  out.clear();
  for (std::size_t i = 0; i < uri.size(); ++i) {
    if (uri[i] != '%') {
      out += uri[i];
      continue;
    }
    if (i + 2 >= uri.size() || hex(uri[i + 1]) < 0 || hex(uri[i + 2]) < 0) return false;
    out += static_cast<char>(hex(uri[i + 1]) * 16 + hex(uri[i + 2]));
    i += 2;
  }
  return out.find('\0') == std::string::npos;
}

// Whether the uri starts with a scheme ("http:", "file:", "data:"): letters, digits, + - .
// before a ':' that comes before any '/'.
bool has_scheme(const std::string& uri) {
  const std::size_t colon = uri.find(':');
  if (colon == std::string::npos || colon == 0 || uri.find('/') < colon) return false;
  return std::isalpha(static_cast<unsigned char>(uri[0])) &&
         std::all_of(uri.begin(), uri.begin() + static_cast<long>(colon), [](char c) {
           return std::isalnum(static_cast<unsigned char>(c)) || c == '+' || c == '-' || c == '.';
         });
}

// Why `uri` of the asset in `folder` is refused, or "" when it is read.
std::string refusal(const fs::path& folder, const std::string& uri) {
  if (tinygltf::IsDataURI(uri)) return "";
  if (has_scheme(uri))
    return "only relative paths and base64 data: URIs (application/octet-stream, application/gltf-buffer, "
           "image/png, image/jpeg) are read";
  std::string path;
  if (!percent_decode(uri, path)) return "a '%' not followed by two hex digits, or an encoded NUL";
  if (path.empty()) return "an empty path";
  if (path.front() == '/') return "an absolute path (a file must lie in the asset's folder or below)";
  if (confined(folder, folder / path, false).empty()) return "it names a file outside the asset's folder";
  return "";
}

// What the reader reads or writes back as it is: materials and what they name.
bool kept_as_written(const std::string& key) {
  return key == "materials" || key == "textures" || key == "samplers" || key == "images";
}

}  // namespace

nlohmann::json gltf_json(std::string_view data, bool binary, const fs::path& file) {
  if (binary) {  // the header as tinygltf reads it: magic, version, length, JSON chunk length
    if (data.size() < 20) return nullptr;
    const auto length = load_le<std::uint32_t>(data.data() + 12);
    if (length > data.size() - 20) return nullptr;
    data = data.substr(20, length);
  }
  // nlohmann's parser does not recurse, tinygltf's conversion of extras does
  int depth = 0;
  const auto deepest = [&depth](int d, nlohmann::json::parse_event_t, nlohmann::json&) {
    depth = std::max(depth, d);
    return true;
  };
  nlohmann::json j = nlohmann::json::parse(data.begin(), data.end(), deepest, false);
  if (depth > kMaxGltfNesting)
    fail(file, 0, "the JSON nests arrays and objects deeper than " + std::to_string(kMaxGltfNesting) + " levels");
  return j;
}

void extension_names(const nlohmann::json& j, std::set<std::string>& names) {
  if (j.is_object()) {
    for (const auto& [key, value] : j.items()) {
      if (key == "extensions" && value.is_object())
        for (const auto& e : value.items()) names.insert(e.key());
      extension_names(value, names);
    }
  } else if (j.is_array()) {
    for (const auto& value : j) extension_names(value, names);
  }
}

fs::path confined(const fs::path& folder, const fs::path& target, bool exists) {
  if (target.native().find('\0') != std::string::npos) return {};
  std::error_code ec;
  const fs::path root = fs::canonical(folder, ec);
  if (ec) return {};
  const fs::path real = exists ? fs::canonical(target, ec) : fs::weakly_canonical(target, ec);
  if (ec) return {};
  const auto [in_root, in_real] = std::mismatch(root.begin(), root.end(), real.begin(), real.end());
  return in_root == root.end() ? real : fs::path();
}

void check_gltf_uris(const nlohmann::json& j, const fs::path& file) {
  if (!j.is_object()) return;
  std::error_code ec;
  const fs::path folder = fs::absolute(file, ec).parent_path();
  for (const char* key : {"buffers", "images"}) {
    if (!j.contains(key) || !j[key].is_array()) continue;
    const std::string what = key == std::string("buffers") ? "buffer " : "image ";
    for (std::size_t i = 0; i < j[key].size(); ++i) {
      const nlohmann::json& item = j[key][i];
      if (!item.is_object() || !item.contains("uri") || !item["uri"].is_string()) continue;
      const std::string uri = item["uri"].get<std::string>();
      if (const std::string why = refusal(folder, uri); !why.empty())
        fail(file, 0, what + std::to_string(i) + ": uri " + shown(uri) + " is not read: " + why);
    }
  }
}

void check_gltf_extensions(const nlohmann::json& j, const fs::path& file) {
  if (!j.is_object() || !j.contains("extensionsRequired") || !j["extensionsRequired"].is_array()) return;
  std::set<std::string> kept, elsewhere;
  for (const auto& [key, value] : j.items()) {
    std::set<std::string>& names = kept_as_written(key) ? kept : elsewhere;
    if (key == "extensions" && value.is_object())
      for (const auto& e : value.items()) names.insert(e.key());
    extension_names(value, names);
  }
  for (const nlohmann::json& e : j["extensionsRequired"]) {
    if (!e.is_string()) continue;  // tinygltf refuses it
    const std::string name = e.get<std::string>();
    if (name == "KHR_mesh_quantization" || (kept.count(name) && !elsewhere.count(name))) continue;
    fail(file, 0, "extension '" + name + "' is required and mbi does not implement it (it reads "
                  "KHR_mesh_quantization, and keeps the extensions of materials and textures as written)");
  }
}

}  // namespace mbi::io::detail
