#pragma once
// What a glTF asset is checked for before tinygltf reads it (format_gltf_check.cpp): the files
// its buffers and images name stay in the asset's folder, and every extension it requires is
// one mbi implements. The rules are stated in docs/cli.md "glTF 2.0".
#include <nlohmann/json.hpp>

#include <filesystem>
#include <set>
#include <string>
#include <string_view>

namespace mbi::io::detail {

/// Deepest nesting of arrays and objects read (tinygltf converts extras recursively; real
/// assets nest about ten levels).
constexpr int kMaxGltfNesting = 64;

/// The asset's JSON: a .glb's first chunk, or the whole text; discarded when it cannot be parsed
/// (tinygltf then reports why). Throws Error naming `file` when it nests deeper than
/// kMaxGltfNesting.
nlohmann::json gltf_json(std::string_view data, bool binary, const std::filesystem::path& file);

/// Throws Error naming `file`, the buffer or image, and its uri, unless every uri of `j` is
/// a data: URI or a relative path that, percent-decoded and with its symbolic links followed,
/// lies in `file`'s folder or below.
void check_gltf_uris(const nlohmann::json& j, const std::filesystem::path& file);

/// Throws Error naming the extension unless every one in `extensionsRequired` is read by mbi
/// (KHR_mesh_quantization) or used only by materials, textures, samplers and images (written
/// back as they are).
void check_gltf_extensions(const nlohmann::json& j, const std::filesystem::path& file);

/// The names of the extensions used inside `j` (in objects named "extensions", at any depth).
void extension_names(const nlohmann::json& j, std::set<std::string>& names);

/// `target` with its symbolic links followed, when that lies in `folder` or below (compared by
/// path components); empty otherwise, when `target` holds a NUL, or, with `exists`, when a
/// component of it does not exist (as the kernel resolves it; else what exists is resolved and
/// the rest taken lexically).
std::filesystem::path confined(const std::filesystem::path& folder, const std::filesystem::path& target, bool exists);

}  // namespace mbi::io::detail
