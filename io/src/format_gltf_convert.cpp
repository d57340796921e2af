// What an OBJ or PLY file holds besides positions, as a glTF asset (format_gltf.hpp): an OBJ's
// UVs (its vertices split where corners differ in texture coordinate, as glTF stores one UV a
// vertex), its groups and materials as primitives, its MTL materials as PBR materials where they
// map; a PLY's vertex colours as COLOR_0.
#include "format_gltf.hpp"
#include "surface.hpp"

#include <mbi/io/atomic_file.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cctype>
#include <cstdio>
#include <map>
#include <set>

namespace mbi::io::detail {
namespace {

using std::filesystem::path;
using nlohmann::json;
using Kind = ObjAttributes::Record::Kind;

// A file's path relative to a folder, links resolved; empty when the file lies outside it.
path relative_inside(const path& file, const path& folder) {
  std::error_code ec;
  const path base = std::filesystem::weakly_canonical(std::filesystem::absolute(folder, ec), ec);
  const path rel = std::filesystem::relative(std::filesystem::weakly_canonical(std::filesystem::absolute(file, ec), ec), base, ec);
  return ec || rel.empty() || *rel.begin() == ".." ? path() : rel;
}

// The MTL keys written into a glTF material; every other key is named in a note.
const std::set<std::string, std::less<>> kMapped = {"newmtl", "Kd", "map_Kd", "d", "Tr"};

struct MtlMaterial {
  std::array<double, 3> kd{1, 1, 1};
  double alpha = 1;
  path texture;  // map_Kd resolved against the MTL's folder, or empty
};

// The materials of one MTL file; keys that do not map are gathered into `unmapped`.
void read_mtl(const path& file, const path& model_folder, std::map<std::string, MtlMaterial>& out,
              std::set<std::string>& unmapped, std::vector<std::string>& notes) {
  std::error_code ec;
  if (relative_inside(file, model_folder).empty()) {  // read nothing the user did not name
    notes.push_back(file.string() + ": material library outside the model's folder: not read");
    return;
  }
  if (!std::filesystem::is_regular_file(file, ec)) {
    notes.push_back(file.string() + ": material library not found; materials are written by name only");
    return;
  }
  const std::string text = slurp(file);
  MtlMaterial* m = nullptr;
  for (const Line& l : tokenize(skip_bom(text))) {
    const std::string key(l.tok[0]);
    if (key == "newmtl" && l.tok.size() > 1) {
      m = &out[std::string(l.tok[1])];
      continue;
    }
    if (!kMapped.count(key)) {
      unmapped.insert(key);
      continue;
    }
    if (!m) continue;
    if (key == "Kd" && l.tok.size() >= 4) {
      for (int c = 0; c < 3; ++c) m->kd[static_cast<std::size_t>(c)] = std::clamp(to_double(l.tok[c + 1], file, l.number, "Kd"), 0.0, 1.0);
    } else if ((key == "d" || key == "Tr") && l.tok.size() >= 2) {
      const double x = std::clamp(to_double(l.tok.back(), file, l.number, key), 0.0, 1.0);
      m->alpha = key == "d" ? x : 1 - x;
    } else if (key == "map_Kd" && l.tok.size() >= 2) {
      if (l.tok.size() > 2) unmapped.insert("map_Kd options");
      m->texture = file.parent_path() / std::string(l.tok.back());
      if (relative_inside(m->texture, model_folder).empty()) {
        notes.push_back(m->texture.string() + ": texture (map_Kd) outside the model's folder: left out");
        m->texture.clear();
      }
    }
  }
}

// A file's path relative to the output's folder, as a URI reference (RFC 3986 escapes); empty
// when the file lies outside that folder (glTF readers, mbi's among them, refuse such URIs).
std::string relative_uri(const path& file, const path& output) {
  const path rel = relative_inside(file, output_name(output).parent_path());
  if (rel.empty()) return "";
  std::string uri;
  for (const unsigned char c : rel.generic_string()) {
    if (std::isalnum(c) || std::string_view("-._~/").find(static_cast<char>(c)) != std::string_view::npos) {
      uri += static_cast<char>(c);
    } else {
      char b[4];
      std::snprintf(b, sizeof b, "%%%02X", c);
      uri += b;
    }
  }
  return uri;
}

// The image of a texture file: named by a URI relative to the output when it lies in the output's
// folder or below (referenced, not copied), else its bytes stored in the file (PNG and JPEG, the
// formats glTF takes). False, with a note, when neither is possible.
bool add_image(const path& texture, const path& output, nlohmann::json& images, GltfAsset& asset) {
  std::error_code ec;
  const bool exists = std::filesystem::is_regular_file(texture, ec);
  if (const std::string uri = relative_uri(texture, output); !uri.empty()) {
    if (!exists) asset.notes.push_back(texture.string() + ": texture (map_Kd) not found; named all the same");
    images.push_back({{"uri", uri}});
    asset.image_bytes.emplace_back();
    asset.image_mime.emplace_back();
    return true;
  }
  const std::string bytes = exists ? slurp(texture) : std::string();
  const std::string mime = bytes.rfind("\x89PNG", 0) == 0 ? "image/png" : bytes.rfind("\xFF\xD8\xFF", 0) == 0 ? "image/jpeg" : "";
  if (mime.empty()) {
    asset.notes.push_back(texture.string() + ": texture (map_Kd) " + (exists ? "neither PNG nor JPEG" : "not found") +
                          ", and outside the output's folder: left out");
    return false;
  }
  images.push_back({{"mimeType", mime}});
  asset.image_bytes.emplace_back(bytes.begin(), bytes.end());
  asset.image_mime.push_back(mime);
  return true;
}

// The glTF materials, textures and images of the materials the parts use, by name.
void add_materials(const std::vector<std::string>& names, const std::vector<path>& libraries,
                   const path& model_folder, const path& output, GltfAsset& asset) {
  std::map<std::string, MtlMaterial> mtl;
  std::set<std::string> unmapped;
  for (const path& lib : libraries) read_mtl(lib, model_folder, mtl, unmapped, asset.notes);
  json materials = json::array(), textures = json::array(), images = json::array();
  std::map<path, int> texture_of;  // one texture an image file
  for (const std::string& name : names) {
    json m = {{"name", name}};
    const auto it = mtl.find(name);
    if (it == mtl.end()) {
      if (!libraries.empty()) asset.notes.push_back("material " + name + ": not in the material libraries");
      materials.push_back(std::move(m));
      continue;
    }
    const MtlMaterial& x = it->second;
    json pbr = {{"baseColorFactor", {x.kd[0], x.kd[1], x.kd[2], x.alpha}}, {"metallicFactor", 0.0}};
    if (!x.texture.empty()) {
      auto t = texture_of.find(x.texture);
      if (t == texture_of.end()) {
        int index = -1;
        if (add_image(x.texture, output, images, asset)) {
          textures.push_back({{"source", images.size() - 1}});
          index = static_cast<int>(textures.size()) - 1;
        }
        t = texture_of.emplace(x.texture, index).first;
      }
      if (t->second >= 0) pbr["baseColorTexture"] = {{"index", t->second}};
    }
    m["pbrMetallicRoughness"] = std::move(pbr);
    if (x.alpha < 1) m["alphaMode"] = "BLEND";
    materials.push_back(std::move(m));
  }
  asset.materials = materials.dump();
  asset.textures = textures.dump();
  asset.images = images.dump();
  if (!unmapped.empty()) {
    std::string list;
    for (const std::string& k : unmapped) list += (list.empty() ? "" : ", ") + k;
    asset.notes.push_back("MTL " + list + ": no glTF PBR counterpart, left out");
  }
}

// The OBJ records that place faces: their UVs, and each face's group and material.
struct ObjLayout {
  std::vector<std::array<double, 2>> vt;
  std::vector<std::pair<std::string, std::string>> face_part;  // per face: group, material
  std::vector<path> libraries;
};

ObjLayout obj_layout(const ObjAttributes& a) {
  ObjLayout o;
  std::string group, material;
  for (const auto& r : a.records) {
    if (r.kind == Kind::face) {
      o.face_part.emplace_back(group, material);
      continue;
    }
    if (r.kind != Kind::text) continue;
    const std::vector<std::string_view> w = words(r.text);
    if (w.empty()) continue;
    auto rest = [&] { return std::string(w[1].data(), static_cast<std::size_t>(w.back().data() + w.back().size() - w[1].data())); };
    if (w[0] == "vt") {
      std::array<double, 2> uv{0, 0};
      for (std::size_t c = 0; c < 2 && c + 1 < w.size(); ++c) uv[c] = to_double(w[c + 1], a.file, 0, "texture coordinate");
      o.vt.push_back(uv);
    } else if ((w[0] == "g" || w[0] == "o") && w.size() > 1) {
      group = rest();
    } else if (w[0] == "usemtl" && w.size() > 1) {
      material = rest();
    } else if (w[0] == "mtllib") {
      for (std::size_t k = 1; k < w.size(); ++k) o.libraries.push_back(a.file.parent_path() / std::string(w[k]));
    }
  }
  return o;
}

using Corner = std::pair<int, int>;  // (v, vt), vt -1: none
using Triangle = std::array<Corner, 3>;

// One part's triangles as written: a vertex for each (v, vt) the part uses, numbered in (v, vt)
// order (a part without seams keeps the mesh's vertex order), appended to `asset`; its UVs when
// any corner has one (`missing_uv` set for a corner without).
GltfPart split_part(const std::vector<Triangle>& triangles, const ObjLayout& lay, GltfAsset& asset, bool& missing_uv) {
  GltfPart part;
  part.first_vertex = static_cast<long long>(asset.source.size());
  part.first_face = static_cast<long long>(asset.triangles.size());
  std::map<Corner, int> split;
  bool any_uv = false;
  for (const Triangle& tri : triangles)
    for (const Corner& c : tri) {
      split.emplace(c, 0);
      any_uv |= c.second >= 0;
    }
  for (auto& [c, index] : split) {
    index = static_cast<int>(asset.source.size());
    asset.source.push_back(c.first);
    if (!any_uv) continue;
    const std::array<double, 2> uv = c.second >= 0 ? lay.vt[static_cast<std::size_t>(c.second)] : std::array<double, 2>{0, 0};
    missing_uv |= c.second < 0;
    part.uv0.push_back(static_cast<float>(uv[0]));
    part.uv0.push_back(static_cast<float>(1 - uv[1]));  // glTF's v runs down the image
  }
  for (const Triangle& tri : triangles) asset.triangles.push_back({split.at(tri[0]), split.at(tri[1]), split.at(tri[2])});
  part.vertices = static_cast<long long>(asset.source.size()) - part.first_vertex;
  part.faces = static_cast<long long>(asset.triangles.size()) - part.first_face;
  return part;
}

// Null when the OBJ has nothing glTF would keep (no vt, one group, no material): written plain.
std::shared_ptr<GltfAsset> obj_asset(const ObjAttributes& a, const Polygons& triangles, const path& output) {
  const ObjLayout lay = obj_layout(a);
  const bool any_vt = std::any_of(a.face_vt.begin(), a.face_vt.end(),
                                  [](const std::vector<int>& f) { return std::any_of(f.begin(), f.end(), [](int t) { return t >= 0; }); });
  const std::set<std::pair<std::string, std::string>> kinds(lay.face_part.begin(), lay.face_part.end());
  if (!any_vt && kinds.size() <= 1 && (kinds.empty() || kinds.begin()->second.empty())) return nullptr;
  // parts by (group, material) in order of first appearance, their faces fan-triangulated
  std::map<std::pair<std::string, std::string>, std::size_t> part_of;
  std::vector<std::pair<std::string, std::string>> keys;
  std::vector<std::vector<Triangle>> corners;
  std::size_t t = 0;
  for (std::size_t j = 0; j < a.face_vt.size(); ++j) {
    const auto [it, fresh] = part_of.emplace(lay.face_part[j], corners.size());
    if (fresh) corners.emplace_back(), keys.push_back(lay.face_part[j]);
    const std::vector<int>& vt = a.face_vt[j];
    for (std::size_t k = 1; k + 1 < vt.size(); ++k, ++t) {
      const std::vector<int>& tri = triangles[t];
      corners[it->second].push_back({{{tri[0], vt[0]}, {tri[1], vt[k]}, {tri[2], vt[k + 1]}}});
    }
  }
  auto asset = std::make_shared<GltfAsset>();
  std::vector<std::string> material_names;
  bool missing_uv = false;
  for (std::size_t p = 0; p < corners.size(); ++p) {
    GltfPart part = split_part(corners[p], lay, *asset, missing_uv);
    part.name = keys[p].first.empty() ? "default" : keys[p].first;
    if (const std::string& mat = keys[p].second; !mat.empty()) {
      const auto m = std::find(material_names.begin(), material_names.end(), mat);
      part.material = static_cast<int>(m - material_names.begin());
      if (m == material_names.end()) material_names.push_back(mat);
    }
    asset->parts.push_back(std::move(part));
  }
  if (missing_uv) asset->notes.push_back("faces without texture coordinates in a textured group get UV (0, 0)");
  const path folder = a.file.has_parent_path() ? a.file.parent_path() : path(".");
  add_materials(material_names, lay.libraries, folder, output, *asset);
  return asset;
}

// A PLY's red, green, blue (alpha) vertex properties as RGBA in [0, 1]; empty when it has none.
std::vector<float> ply_colors(const PlyAttributes& a, long long vertices) {
  for (std::size_t e = 0; e < a.elements.size(); ++e) {
    const PlyElement& el = a.elements[e];
    if (el.name != "vertex" || el.count != vertices) continue;
    int channel[4] = {-1, -1, -1, -1};
    double scale[4] = {1, 1, 1, 1};
    for (std::size_t k = 0; k < el.props.size(); ++k) {
      const PlyProp& p = el.props[k];
      if (p.list) return {};  // records of varying width
      const char* names[4] = {"red", "green", "blue", "alpha"};
      for (int c = 0; c < 4; ++c)
        if (p.name == names[c]) {
          channel[c] = static_cast<int>(k);
          scale[c] = p.type == PlyType::u8 ? 1 / 255.0 : p.type == PlyType::u16 ? 1 / 65535.0 : 1.0;
        }
    }
    if (channel[0] < 0 || channel[1] < 0 || channel[2] < 0) return {};
    const std::size_t width = el.props.size();
    std::vector<float> rgba;
    for (long long i = 0; i < vertices; ++i)
      for (int c = 0; c < 4; ++c) {
        const double x = channel[c] < 0 ? 1.0 : a.values[e][static_cast<std::size_t>(i) * width + static_cast<std::size_t>(channel[c])] * scale[c];
        rgba.push_back(static_cast<float>(std::clamp(x, 0.0, 1.0)));
      }
    return rgba;
  }
  return {};
}

}  // namespace

bool converts_to_gltf(const SurfaceAttributes& a, const Polygons& triangles) {
  if (a.format == ".ply") return true;
  if (a.format != ".obj") return false;
  std::size_t t = 0;
  for (const auto& vt : a.obj.face_vt) t += vt.size() - 2;
  return t == triangles.size();
}

std::shared_ptr<const GltfAsset> gltf_asset_of(const SurfaceAttributes& a, const Polygons& triangles, long long vertices,
                                               const path& output) {
  if (a.gltf) return a.gltf;
  if (!converts_to_gltf(a, triangles)) return nullptr;
  if (a.format == ".obj") return obj_asset(a.obj, triangles, output);
  auto asset = std::make_shared<GltfAsset>();
  GltfPart whole;
  whole.name = output_name(output).stem().string();
  whole.vertices = vertices;
  whole.faces = static_cast<long long>(triangles.size());
  whole.color = ply_colors(a.ply, vertices);
  asset->parts.push_back(std::move(whole));
  return asset;
}

}  // namespace mbi::io::detail
