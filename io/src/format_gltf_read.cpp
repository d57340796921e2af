// glTF 2.0 in: every triangle primitive of the default scene, placed by its nodes' transforms,
// becomes one part of a single SurfaceMesh (world coordinates); materials, UVs and colours are
// kept for the writer (format_gltf.hpp). tinygltf parses and checks the file; the accessors are
// read here with their bounds checked, so that a hostile file names what is wrong.
#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <tiny_gltf.h>

#include "format_gltf.hpp"
#include "format_gltf_check.hpp"
#include "surface.hpp"

#include <Eigen/Geometry>

#include <array>
#include <cmath>
#include <set>

namespace mbi::io::detail {
namespace {

using std::filesystem::path;

// Images are not decoded: they are passed through as bytes or as their uri.
bool keep_image(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int, void*) {
  return true;
}

// Buffers in files beside the asset: only in the asset's folder or below (`folder`, the user
// data; format_gltf_check.cpp refuses other uris first, by name), read as every input of mbi is
// (regular files only, the size capped: /dev/zero or a FIFO is refused), names taken as written
// (tinygltf's own expansion runs wordexp).
const path& folder_of(void* user) { return *static_cast<const path*>(user); }
bool regular_file(const std::string& name, void* user) {
  const path p = confined(folder_of(user), name, true);
  std::error_code ec;
  return !p.empty() && std::filesystem::is_regular_file(p, ec);
}
std::string as_written(const std::string& name, void*) { return name; }
bool read_buffer(std::vector<unsigned char>* out, std::string* err, const std::string& name, void* user) {
  try {
    const path p = confined(folder_of(user), name, true);
    if (p.empty()) fail(name, 0, "outside the asset's folder");
    const std::string bytes = slurp(p);
    out->assign(bytes.begin(), bytes.end());
    return true;
  } catch (const std::exception& e) {
    if (err) *err += e.what();
    return false;
  }
}
bool never_write(std::string*, const std::string&, const std::vector<unsigned char>&, void*) { return false; }

tinygltf::Model load_model(std::string_view data, const path& file, bool binary) {
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(keep_image, nullptr);
  std::error_code ec;
  const path folder = std::filesystem::absolute(file, ec).parent_path();
  const std::string dir = folder.string();
  loader.SetFsCallbacks({regular_file, as_written, read_buffer, never_write, const_cast<path*>(&folder)});
  tinygltf::Model model;
  std::string err, warn;
  const bool ok = binary ? loader.LoadBinaryFromMemory(&model, &err, &warn,
                                                       reinterpret_cast<const unsigned char*>(data.data()),
                                                       static_cast<unsigned>(data.size()), dir)
                         : loader.LoadASCIIFromString(&model, &err, &warn, data.data(),
                                                      static_cast<unsigned>(data.size()), dir);
  if (!ok) {
    while (!err.empty() && err.back() == '\n') err.pop_back();
    fail(file, 0, "not a readable glTF 2.0 file: " + (err.empty() ? std::string("parse error") : err));
  }
  return model;
}

std::string node_name(const tinygltf::Model& m, int n) {
  const std::string& s = m.nodes[static_cast<std::size_t>(n)].name;
  return s.empty() ? "node " + std::to_string(n) : "node " + std::to_string(n) + " '" + s + "'";
}

// What an accessor is read for: each use allows the component types of glTF 2.0 section
// 3.7.2.1 (KHR_mesh_quantization allows more for positions, normals and texture coordinates).
enum class Use { kPosition, kNormal, kTexcoord, kColor, kIndices };

struct Kind {
  int type;
  bool normalized;
};

std::vector<Kind> allowed_kinds(Use use, bool quantized) {
  constexpr int b = TINYGLTF_COMPONENT_TYPE_BYTE, ub = TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE,
                s = TINYGLTF_COMPONENT_TYPE_SHORT, us = TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
                ui = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, f = TINYGLTF_COMPONENT_TYPE_FLOAT;
  switch (use) {
    case Use::kPosition:
      if (quantized) return {{f, false}, {b, false}, {b, true}, {ub, false}, {ub, true}, {s, false}, {s, true}, {us, false}, {us, true}};
      return {{f, false}};
    case Use::kNormal:
      if (quantized) return {{f, false}, {b, true}, {s, true}};
      return {{f, false}};
    case Use::kTexcoord:
      if (quantized) return {{f, false}, {b, false}, {b, true}, {ub, false}, {ub, true}, {s, false}, {s, true}, {us, false}, {us, true}};
      return {{f, false}, {ub, true}, {us, true}};
    case Use::kColor: return {{f, false}, {ub, true}, {us, true}};
    case Use::kIndices: return {{ub, false}, {us, false}, {ui, false}};
  }
  return {};
}

// "unsigned short normalized"; "" for a type glTF 2.0 does not have.
std::string kind_name(int type, bool normalized) {
  std::string s;
  switch (type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE: s = "byte"; break;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: s = "unsigned byte"; break;
    case TINYGLTF_COMPONENT_TYPE_SHORT: s = "short"; break;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: s = "unsigned short"; break;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: s = "unsigned int"; break;
    case TINYGLTF_COMPONENT_TYPE_FLOAT: s = "float"; break;
    default: return "";
  }
  return normalized ? s + " normalized" : s;
}

// Throws unless accessor `a`'s component type is one the spec allows for `use`.
void check_kind(const tinygltf::Model& m, const tinygltf::Accessor& a, Use use, const path& file, const std::string& at) {
  const bool quantized = std::find(m.extensionsUsed.begin(), m.extensionsUsed.end(), "KHR_mesh_quantization") !=
                         m.extensionsUsed.end();
  const std::vector<Kind> kinds = allowed_kinds(use, quantized);
  if (std::any_of(kinds.begin(), kinds.end(), [&](Kind k) { return k.type == a.componentType && k.normalized == a.normalized; }))
    return;
  std::string names;
  for (const Kind& k : kinds) names += (names.empty() ? "" : ", ") + kind_name(k.type, k.normalized);
  const bool more = !quantized && use != Use::kColor && use != Use::kIndices;
  const std::string name = kind_name(a.componentType, a.normalized);
  fail(file, 0, at + ": component type " + std::to_string(a.componentType) + (name.empty() ? "" : " (" + name + ")") +
                    " is not allowed for this use by glTF 2.0 (allowed: " + names +
                    (more ? "; more with KHR_mesh_quantization in extensionsUsed)" : ")"));
}

// The values of accessor `index`, count x components, normalized integers mapped to [0, 1] or
// [-1, 1] as the format says. `where` names the node, mesh and attribute in messages.
std::vector<double> read_accessor(const tinygltf::Model& m, int index, Use use, std::initializer_list<int> components,
                                  const path& file, const std::string& where) {
  if (index < 0 || index >= static_cast<int>(m.accessors.size()))
    fail(file, 0, where + ": accessor " + std::to_string(index) + " does not exist");
  const tinygltf::Accessor& a = m.accessors[static_cast<std::size_t>(index)];
  const std::string at = where + ": accessor " + std::to_string(index);
  if (a.sparse.isSparse) fail(file, 0, at + ": sparse accessors are not read");
  const int comps = tinygltf::GetNumComponentsInType(static_cast<std::uint32_t>(a.type));
  if (std::find(components.begin(), components.end(), comps) == components.end())
    fail(file, 0, at + ": " + std::to_string(comps) + " components is not a type this attribute takes");
  check_kind(m, a, use, file, at);
  const int size = tinygltf::GetComponentSizeInBytes(static_cast<std::uint32_t>(a.componentType));
  if (a.bufferView < 0 || a.bufferView >= static_cast<int>(m.bufferViews.size()))
    fail(file, 0, at + ": no bufferView");
  const tinygltf::BufferView& bv = m.bufferViews[static_cast<std::size_t>(a.bufferView)];
  if (bv.buffer < 0 || bv.buffer >= static_cast<int>(m.buffers.size())) fail(file, 0, at + ": no buffer");
  const std::vector<unsigned char>& buf = m.buffers[static_cast<std::size_t>(bv.buffer)].data;
  const unsigned long long elem = static_cast<unsigned long long>(comps) * static_cast<unsigned>(size);
  const unsigned long long stride = bv.byteStride ? bv.byteStride : elem;
  const unsigned long long count = a.count, start = a.byteOffset;
  // every element inside the bufferView, and the view inside its buffer
  if (stride < elem || bv.byteOffset > buf.size() || bv.byteLength > buf.size() - bv.byteOffset ||
      (count > 0 && (start > bv.byteLength || (count - 1) > (bv.byteLength - start) / stride ||
                     (count - 1) * stride + elem > bv.byteLength - start)))
    fail(file, 0, at + ": " + std::to_string(count) + " elements do not fit in bufferView " +
                      std::to_string(a.bufferView));
  std::vector<double> out(count * static_cast<unsigned>(comps));
  const char* base = reinterpret_cast<const char*>(buf.data()) + bv.byteOffset + start;
  for (unsigned long long i = 0; i < count; ++i)
    for (int c = 0; c < comps; ++c) {
      const char* p = base + i * stride + static_cast<unsigned>(c * size);
      double x = 0;
      switch (a.componentType) {
        case TINYGLTF_COMPONENT_TYPE_FLOAT: x = load_le<float>(p); break;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: x = static_cast<unsigned char>(*p); break;
        case TINYGLTF_COMPONENT_TYPE_BYTE: x = static_cast<signed char>(*p); break;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: x = load_le<std::uint16_t>(p); break;
        case TINYGLTF_COMPONENT_TYPE_SHORT: x = load_le<std::int16_t>(p); break;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: x = load_le<std::uint32_t>(p); break;
        default: fail(file, 0, at + ": component type " + std::to_string(a.componentType) + " is not read");
      }
      if (a.normalized && a.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT) {
        const double top = static_cast<double>((1ull << (8 * size - (a.componentType % 2 == 0 ? 1 : 0))) - 1);
        x = std::max(x / top, -1.0);
      }
      if (!std::isfinite(x)) fail(file, 0, at + ": element " + std::to_string(i) + ": non-finite value");
      out[i * static_cast<unsigned>(comps) + static_cast<unsigned>(c)] = x;
    }
  return out;
}

int attribute(const tinygltf::Primitive& p, const char* name) {
  const auto it = p.attributes.find(name);
  return it == p.attributes.end() ? -1 : it->second;
}

Eigen::Matrix4d local_matrix(const tinygltf::Node& n) {
  Eigen::Matrix4d M = Eigen::Matrix4d::Identity();
  if (n.matrix.size() == 16) {
    for (int k = 0; k < 16; ++k) M(k % 4, k / 4) = n.matrix[static_cast<std::size_t>(k)];  // column-major
    return M;
  }
  Eigen::Affine3d A = Eigen::Affine3d::Identity();
  if (n.translation.size() == 3) A.translate(Eigen::Vector3d(n.translation[0], n.translation[1], n.translation[2]));
  if (n.rotation.size() == 4)
    A.rotate(Eigen::Quaterniond(n.rotation[3], n.rotation[0], n.rotation[1], n.rotation[2]).normalized());
  if (n.scale.size() == 3) A.scale(Eigen::Vector3d(n.scale[0], n.scale[1], n.scale[2]));
  return A.matrix();
}

// Deepest node hierarchy read (the walk is recursive; real assets nest a few dozen levels).
constexpr int kMaxDepth = 1000;

// Builds the SurfaceMesh from the scene's nodes, one part per (node, primitive).
class Gatherer {
 public:
  Gatherer(const tinygltf::Model& m, const path& file, GltfAsset& asset, std::size_t bytes)
      : m_(m), file_(file), asset_(asset), bytes_(static_cast<long long>(bytes)) {}

  void node(int n, const Eigen::Matrix4d& parent, int depth) {
    if (n < 0 || n >= static_cast<int>(m_.nodes.size())) fail(file_, 0, "node " + std::to_string(n) + " does not exist");
    // nodes form trees: a node reached twice (two parents, a cycle) would repeat its subtree
    if (seen_.empty()) seen_.resize(m_.nodes.size(), 0);
    if (seen_[static_cast<std::size_t>(n)]++)
      fail(file_, 0, node_name(m_, n) + ": reached twice in the scene (two parents or a cycle; glTF nodes form trees)");
    if (depth > kMaxDepth) fail(file_, 0, node_name(m_, n) + ": the node hierarchy is deeper than " + std::to_string(kMaxDepth));
    const tinygltf::Node& node = m_.nodes[static_cast<std::size_t>(n)];
    const Eigen::Matrix4d M = parent * local_matrix(node);
    // a node scaled to nothing is hidden, with its children (an animation of mbi shows one frame
    // node at a time: read back, it gives its first frame)
    if (M.topLeftCorner<3, 3>().determinant() == 0) return;
    if (node.mesh >= 0) {
      if (node.skin >= 0)
        fail(file_, 0, node_name(m_, n) + ": a skinned mesh (skin " + std::to_string(node.skin) +
                           ") is not read: apply the skin first (e.g. Blender: apply the Armature modifier) and "
                           "export the posed mesh");
      if (node.mesh >= static_cast<int>(m_.meshes.size()))
        fail(file_, 0, node_name(m_, n) + ": mesh " + std::to_string(node.mesh) + " does not exist");
      const tinygltf::Mesh& mesh = m_.meshes[static_cast<std::size_t>(node.mesh)];
      for (std::size_t k = 0; k < mesh.primitives.size(); ++k)
        primitive(mesh.primitives[k], M, node_name(m_, n) + ": mesh " + std::to_string(node.mesh) + " primitive " +
                                             std::to_string(k), node.name.empty() ? "node " + std::to_string(n) : node.name);
    }
    for (int c : node.children) this->node(c, M, depth + 1);
  }

  void finish(SurfaceMesh& s) {
    if (v_.empty()) fail(file_, 0, "the scene has no triangle mesh");
    set_vertices(s, v_);
    s.F.resize(static_cast<Eigen::Index>(f_.size()), 3);
    for (std::size_t i = 0; i < f_.size(); ++i) s.F.row(static_cast<Eigen::Index>(i)) << f_[i][0], f_[i][1], f_[i][2];
    if (std::find(have_n_.begin(), have_n_.end(), 1) == have_n_.end()) return;  // no normals in the file
    s.N.resize(s.V.rows(), 3);
    for (std::size_t i = 0; i < n_.size(); ++i) s.N.row(static_cast<Eigen::Index>(i)) << n_[i][0], n_[i][1], n_[i][2];
    complete_normals(s, have_n_);
  }

 private:
  void primitive(const tinygltf::Primitive& p, const Eigen::Matrix4d& M, const std::string& where, const std::string& name) {
    if (p.mode != -1 && p.mode != TINYGLTF_MODE_TRIANGLES)
      fail(file_, 0, where + ": mode " + std::to_string(p.mode) + " is not read (only triangles, mode 4)");
    if (!p.targets.empty())
      fail(file_, 0, where + ": morph targets are not read: apply the shape keys first and export the mesh alone");
    const int pos = attribute(p, "POSITION");
    if (pos < 0) fail(file_, 0, where + ": no POSITION attribute");
    const std::vector<double> P = read_accessor(m_, pos, Use::kPosition, {3}, file_, where + ": POSITION");
    const long long nv = static_cast<long long>(P.size() / 3), first = static_cast<long long>(v_.size());
    if (nv == 0) return;
    // instances place a mesh many times: bounded by the file's size, and by int indices
    if (first + nv > std::min<long long>(kMaxCount, 64 * bytes_ + (1 << 20)))
      fail(file_, 0, where + ": more than " + std::to_string(first) + " vertices placed; too many for a file of " +
                         std::to_string(bytes_) + " bytes");
    GltfPart part;
    part.name = name;
    part.first_vertex = first;
    part.vertices = nv;
    part.first_face = static_cast<long long>(f_.size());
    part.material = p.material;
    const Eigen::Matrix3d L = M.topLeftCorner<3, 3>();
    const Eigen::Matrix3d normal_map = L.inverse().transpose();
    for (long long i = 0; i < nv; ++i) {
      const Eigen::Vector3d x = L * Eigen::Vector3d(P[3 * i], P[3 * i + 1], P[3 * i + 2]) + M.topRightCorner<3, 1>();
      for (int c = 0; c < 3; ++c) check_coordinate(x[c], file_, 0, where + ": POSITION " + std::to_string(i));
      v_.push_back({x[0], x[1], x[2]});
    }
    normals(p, normal_map, nv, where);
    faces(p, nv, first, L.determinant() < 0, where);
    part.faces = static_cast<long long>(f_.size()) - part.first_face;
    if (const int t = attribute(p, "TEXCOORD_0"); t >= 0) part.uv0 = uvs(t, nv, where + ": TEXCOORD_0");
    if (const int t = attribute(p, "TEXCOORD_1"); t >= 0) part.uv1 = uvs(t, nv, where + ": TEXCOORD_1");
    if (const int c = attribute(p, "COLOR_0"); c >= 0) part.color = colors(c, nv, where + ": COLOR_0");
    asset_.parts.push_back(std::move(part));
  }

  void normals(const tinygltf::Primitive& p, const Eigen::Matrix3d& map, long long nv, const std::string& where) {
    const int a = attribute(p, "NORMAL");
    const std::vector<double> N = a >= 0 ? read_accessor(m_, a, Use::kNormal, {3}, file_, where + ": NORMAL") : std::vector<double>();
    if (a >= 0 && static_cast<long long>(N.size()) != 3 * nv)
      fail(file_, 0, where + ": NORMAL has " + std::to_string(N.size() / 3) + " elements, POSITION " + std::to_string(nv));
    for (long long i = 0; i < nv; ++i) {
      const Eigen::Vector3d n = a >= 0 ? (map * Eigen::Vector3d(N[3 * i], N[3 * i + 1], N[3 * i + 2])).eval()
                                       : Eigen::Vector3d::Zero();
      n_.push_back({n[0], n[1], n[2]});
      have_n_.push_back(a >= 0 && n.norm() > 0 ? 1 : 0);  // complete_normals makes them unit
    }
  }

  void faces(const tinygltf::Primitive& p, long long nv, long long first, bool flip, const std::string& where) {
    std::vector<double> I;
    if (p.indices >= 0) {
      I = read_accessor(m_, p.indices, Use::kIndices, {1}, file_, where + ": indices");
    } else {
      I.resize(static_cast<std::size_t>(nv));
      for (long long i = 0; i < nv; ++i) I[static_cast<std::size_t>(i)] = static_cast<double>(i);
    }
    if (I.size() % 3 != 0)
      fail(file_, 0, where + ": indices: " + std::to_string(I.size()) + " indices is not a whole number of triangles");
    for (std::size_t k = 0; k < I.size(); k += 3) {
      std::array<int, 3> t{};
      for (int c = 0; c < 3; ++c) {
        if (!(I[k + c] >= 0) || I[k + c] != std::floor(I[k + c]) || I[k + c] >= static_cast<double>(nv))
          fail(file_, 0, where + ": index " + std::to_string(k + c) + " is " + std::to_string(static_cast<long long>(I[k + c])) +
                             ", past the primitive's " + std::to_string(nv) + " vertices");
        t[static_cast<std::size_t>(c)] = static_cast<int>(first + static_cast<long long>(I[k + c]));
      }
      if (flip) std::swap(t[1], t[2]);  // a mirroring transform turns the faces inside out
      f_.push_back(t);
    }
  }

  std::vector<float> uvs(int accessor, long long nv, const std::string& where) {
    const std::vector<double> x = read_accessor(m_, accessor, Use::kTexcoord, {2}, file_, where);
    if (static_cast<long long>(x.size()) != nv * 2)
      fail(file_, 0, where + ": " + std::to_string(x.size() / 2) + " elements, POSITION has " + std::to_string(nv));
    return {x.begin(), x.end()};
  }

  std::vector<float> colors(int accessor, long long nv, const std::string& where) {
    const std::vector<double> x = read_accessor(m_, accessor, Use::kColor, {3, 4}, file_, where);
    const long long comps = nv > 0 ? static_cast<long long>(x.size()) / nv : 4;
    if (static_cast<long long>(x.size()) != nv * comps) fail(file_, 0, where + ": count differs from POSITION's");
    std::vector<float> rgba;
    for (long long i = 0; i < nv; ++i)
      for (long long c = 0; c < 4; ++c) rgba.push_back(c < comps ? static_cast<float>(x[static_cast<std::size_t>(i * comps + c)]) : 1.0f);
    return rgba;
  }

  const tinygltf::Model& m_;
  const path& file_;
  GltfAsset& asset_;
  std::vector<std::array<double, 3>> v_, n_;
  std::vector<char> have_n_;
  std::vector<std::array<int, 3>> f_;
  std::vector<int> seen_;  // per node: times reached
  long long bytes_;        // the file's size
};

// Materials, textures, samplers and images as in the file; images inside a buffer as bytes.
void keep_materials(const tinygltf::Model& m, const nlohmann::json& j, GltfAsset& a) {
  for (auto [key, kept] : {std::pair{"materials", &a.materials}, {"textures", &a.textures},
                           {"samplers", &a.samplers}, {"images", &a.images}})
    if (j.contains(key) && j[key].is_array()) *kept = j[key].dump();
  for (const tinygltf::Image& im : m.images) {
    std::vector<unsigned char> bytes;
    if (im.bufferView >= 0 && im.bufferView < static_cast<int>(m.bufferViews.size())) {
      const tinygltf::BufferView& bv = m.bufferViews[static_cast<std::size_t>(im.bufferView)];
      const std::vector<unsigned char>& buf = m.buffers.at(static_cast<std::size_t>(bv.buffer)).data;
      if (bv.byteOffset <= buf.size() && bv.byteLength <= buf.size() - bv.byteOffset)
        bytes.assign(buf.begin() + static_cast<long>(bv.byteOffset), buf.begin() + static_cast<long>(bv.byteOffset + bv.byteLength));
    }
    a.image_bytes.push_back(std::move(bytes));
    a.image_mime.push_back(im.mimeType);
  }
  std::set<std::string> used;
  for (const char* key : {"materials", "textures", "samplers", "images"})
    if (j.contains(key)) extension_names(j[key], used);
  a.extensions_used.assign(used.begin(), used.end());
  for (const std::string& e : m.extensionsRequired)
    if (used.count(e)) a.extensions_required.push_back(e);
}

}  // namespace

SurfaceMesh parse_gltf(std::string_view data, const path& file) {
  const bool binary = data.size() >= 4 && data.substr(0, 4) == "glTF";
  const nlohmann::json json = gltf_json(data, binary, file);
  check_gltf_uris(json, file);
  check_gltf_extensions(json, file);
  const tinygltf::Model model = load_model(data, file, binary);
  if (model.scenes.empty()) fail(file, 0, "no scene (a glTF file of parts alone is not read)");
  const int scene = model.defaultScene >= 0 ? model.defaultScene : 0;
  if (scene >= static_cast<int>(model.scenes.size())) fail(file, 0, "scene " + std::to_string(scene) + " does not exist");
  auto asset = std::make_shared<GltfAsset>();
  Gatherer g(model, file, *asset, data.size());
  for (int n : model.scenes[static_cast<std::size_t>(scene)].nodes) g.node(n, Eigen::Matrix4d::Identity(), 0);
  SurfaceMesh s;
  g.finish(s);
  keep_materials(model, json, *asset);
  auto attributes = std::make_shared<SurfaceAttributes>();
  attributes->format = ".glb";  // either extension writes them back (formats.cpp)
  attributes->binary = binary;
  attributes->vertices = s.V.rows();
  attributes->gltf = std::move(asset);
  s.attributes = std::move(attributes);
  return s;
}

}  // namespace mbi::io::detail
