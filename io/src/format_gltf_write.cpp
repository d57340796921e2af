// glTF 2.0 out: one static frame (write_surface) or an animation (GltfWriter), written as our own
// JSON and GLB layout. An animation is one node per frame, each with a mesh of every part, shown
// in turn by step-keyed scale (1 while its frame lasts, 0 otherwise): Blender's and three.js's
// importers play node scale animations, and the file grows linearly with the frames (morph
// targets with step-keyed weights would need frames^2 weights). Indices, UVs and colours are
// stored once and shared by every frame; positions and normals are float32.
#include "format_gltf.hpp"
#include "surface.hpp"

#include <mbi/io/atomic_file.hpp>

#include <nlohmann/json.hpp>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>

namespace mbi::io {
namespace detail {
namespace {

using std::filesystem::path;
using nlohmann::json;

constexpr int kFloat = 5126, kUint = 5125;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;
// A .glb stores its length as uint32; the JSON chunk gets a margin below that.
constexpr unsigned long long kMaxBinary = 0xFFFFFFFFull - (64ull << 20);

std::string base64(const std::vector<unsigned char>& b) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string s;
  s.reserve((b.size() + 2) / 3 * 4);
  for (std::size_t i = 0; i < b.size(); i += 3) {
    const unsigned v = (b[i] << 16u) | (i + 1 < b.size() ? b[i + 1] << 8u : 0u) | (i + 2 < b.size() ? b[i + 2] : 0u);
    s += k[(v >> 18) & 63];
    s += k[(v >> 12) & 63];
    s += i + 1 < b.size() ? k[(v >> 6) & 63] : '=';
    s += i + 2 < b.size() ? k[v & 63] : '=';
  }
  return s;
}

// A time as written in messages (6 significant digits).
std::string short_number(double x) {
  char b[32];
  std::snprintf(b, sizeof b, "%.6g", x);
  return b;
}

}  // namespace

/// The document being built: JSON objects and the one binary buffer they point into.
class GltfDocument {
 public:
  // `name`: the root node's (and a plain mesh's part's) name
  GltfDocument(const path& file, const std::string& name, const Polygons& faces, long long vertices, const GltfAsset* asset)
      : file_(file), name_(name), vertices_(vertices) {
    const Polygons* written = &faces;  // in the vertices written
    if (asset) {
      parts_ = asset->parts;
      asset_ = asset;
      if (!asset->source.empty()) written = &asset->triangles;
    } else {
      GltfPart whole;
      whole.name = name;
      whole.vertices = vertices;
      whole.faces = static_cast<long long>(faces.size());
      parts_.push_back(std::move(whole));
    }
    if (faces.empty()) fail(file, 0, "a mesh without faces is not written as glTF");
    for (GltfPart& p : parts_) shared_.push_back(shared_accessors(p, *written));
    if (asset) keep_images(*asset);
  }

  // One frame: V n x 3, N n x 3 or empty; `time` (s) after the previous frame's.
  void add_frame(double time, const Eigen::Ref<const Eigen::MatrixXd>& V, const Eigen::Ref<const Eigen::MatrixXd>& N) {
    if (V.rows() != vertices_ || V.cols() != 3 || (N.size() > 0 && (N.rows() != vertices_ || N.cols() != 3)))
      fail(file_, 0, "frame " + std::to_string(times_.size()) + ": positions or normals do not match the mesh");
    if (asset_ && !asset_->source.empty()) {  // the split vertices copy their mesh vertex's rows
      split(V, V_split_);
      split(N, N_split_);
      return add_written(time, V_split_, N_split_);
    }
    add_written(time, V, N);
  }

  std::size_t frames() const { return times_.size(); }

 private:
  // One frame of the vertices written (the mesh's, or its split copies).
  void add_written(double time, const Eigen::Ref<const Eigen::MatrixXd>& V, const Eigen::Ref<const Eigen::MatrixXd>& N) {
    // the file stores float32 times: those must be finite and strictly increasing
    const float t32 = static_cast<float>(time);
    if (!std::isfinite(time) || !std::isfinite(t32))
      fail(file_, 0, "frame " + std::to_string(times_.size()) + ": time " + short_number(time) + " s is not finite as float32");
    if (!times_.empty() && !(t32 > static_cast<float>(times_.back())))
      fail(file_, 0, "frame " + std::to_string(times_.size()) + ": time " + short_number(time) +
                         " s is not after the previous frame's (" + short_number(times_.back()) + " s) as float32");
    const unsigned long long frame_bytes = static_cast<unsigned long long>(V.rows()) * (N.size() > 0 ? 24 : 12);
    if (bin_.size() + frame_bytes > kMaxBinary)
      fail(file_, 0, "frame " + std::to_string(times_.size()) + ": the glTF would pass 4 GB, the format's limit " +
                         "(write fewer frames, or a point cache)");
    const int pos_view = view(floats(V, false), kArrayBuffer, 12);
    std::vector<int> positions;  // min and max from the floats just converted
    for (const GltfPart& p : parts_) positions.push_back(position_accessor(pos_view, p));
    const int nor_view = N.size() > 0 ? view(floats(N, true), kArrayBuffer, 12) : -1;
    json primitives = json::array();
    for (std::size_t k = 0; k < parts_.size(); ++k) {
      const GltfPart& p = parts_[k];
      json prim = {{"attributes", shared_[k]}, {"mode", 4}};
      prim["attributes"]["POSITION"] = positions[k];
      if (nor_view >= 0) prim["attributes"]["NORMAL"] = accessor(nor_view, p.first_vertex * 12, kFloat, p.vertices, "VEC3");
      prim["indices"] = indices_[k];
      if (p.material >= 0) prim["material"] = p.material;
      primitives.push_back(std::move(prim));
    }
    const std::size_t k = times_.size();
    char name[32];
    std::snprintf(name, sizeof name, "frame_%04zu", k);
    meshes_.push_back({{"name", name}, {"primitives", std::move(primitives)}});
    json node = {{"name", name}, {"mesh", k}};
    if (k > 0) node["scale"] = {0, 0, 0};  // a reader without animation shows the first frame
    nodes_.push_back(std::move(node));
    times_.push_back(time);
  }

  void split(const Eigen::Ref<const Eigen::MatrixXd>& M, Eigen::MatrixXd& out) const {
    if (M.size() == 0) return out.resize(0, 0);
    out.resize(static_cast<Eigen::Index>(asset_->source.size()), 3);
    for (std::size_t i = 0; i < asset_->source.size(); ++i) out.row(static_cast<Eigen::Index>(i)) = M.row(asset_->source[i]);
  }


 public:
  void write(std::FILE* f) {
    if (times_.empty()) fail(file_, 0, "no frame to write");
    if (times_.size() > 1) add_animation();
    const bool binary = lower_extension(file_) == ".glb";
    json buffer = {{"byteLength", bin_.size()}};
    if (!binary) buffer["uri"] = "data:application/octet-stream;base64," + base64(bin_);
    json j = document();
    j["buffers"] = json::array({buffer});
    std::string text = j.dump();
    if (!binary) return put(f, text + "\n", file_);
    while (text.size() % 4) text += ' ';
    while (bin_.size() % 4) bin_.push_back(0);
    const unsigned long long total = 12 + 8 + text.size() + 8 + bin_.size();
    if (total > 0xFFFFFFFFull) fail(file_, 0, "the .glb would pass 4 GB, the format's limit");
    std::string head;
    head += "glTF";
    append_bytes<std::uint32_t>(head, 2, false);
    append_bytes<std::uint32_t>(head, static_cast<std::uint32_t>(total), false);
    append_bytes<std::uint32_t>(head, static_cast<std::uint32_t>(text.size()), false);
    append_bytes<std::uint32_t>(head, 0x4E4F534Au, false);  // "JSON"
    put(f, head + text, file_);
    std::string bin_head;
    append_bytes<std::uint32_t>(bin_head, static_cast<std::uint32_t>(bin_.size()), false);
    append_bytes<std::uint32_t>(bin_head, 0x004E4942u, false);  // "BIN"
    put(f, bin_head, file_);
    put(f, bin_.data(), bin_.size(), file_);
  }

 private:
  // A bufferView of `bytes`, 4-byte aligned in the buffer. A view that several accessors share
  // states its stride (the format requires it for vertex attributes).
  int view(const std::vector<unsigned char>& bytes, int target, int stride = 0) {
    while (bin_.size() % 4) bin_.push_back(0);
    json v = {{"buffer", 0}, {"byteOffset", bin_.size()}, {"byteLength", bytes.size()}};
    if (target) v["target"] = target;
    if (stride) v["byteStride"] = stride;
    bin_.insert(bin_.end(), bytes.begin(), bytes.end());
    views_.push_back(std::move(v));
    return static_cast<int>(views_.size()) - 1;
  }

  int accessor(int view, long long offset, int type, long long count, const char* shape) {
    accessors_.push_back({{"bufferView", view}, {"byteOffset", offset}, {"componentType", type},
                          {"count", count}, {"type", shape}});
    return static_cast<int>(accessors_.size()) - 1;
  }

  template <typename T>
  static std::vector<unsigned char> bytes_of(const std::vector<T>& x) {
    std::vector<unsigned char> b(x.size() * sizeof(T));
    for (std::size_t i = 0; i < x.size(); ++i) {
      std::string s;
      append_bytes<T>(s, x[i], false);
      std::memcpy(b.data() + i * sizeof(T), s.data(), sizeof(T));
    }
    return b;
  }

  // Rows of M as float32 (unit length when `unit`: a zero normal becomes +z).
  std::vector<unsigned char> floats(const Eigen::Ref<const Eigen::MatrixXd>& M, bool unit) {
    frame_.resize(static_cast<std::size_t>(M.rows()) * 3);
    for (Eigen::Index i = 0; i < M.rows(); ++i) {
      Eigen::Vector3d r = M.row(i).transpose();
      if (!r.allFinite()) fail(file_, 0, std::string(unit ? "normal " : "vertex ") + std::to_string(i) + ": non-finite value");
      if (unit) r = r.norm() > 0 ? (r / r.norm()).eval() : Eigen::Vector3d(0, 0, 1);
      for (int c = 0; c < 3; ++c) frame_[static_cast<std::size_t>(3 * i + c)] = static_cast<float>(r[c]);
    }
    return bytes_of(frame_);
  }

  // POSITION needs min and max, taken from the float32 values stored.
  int position_accessor(int view, const GltfPart& p) {
    std::array<float, 3> lo, hi;
    lo.fill(std::numeric_limits<float>::max());
    hi.fill(std::numeric_limits<float>::lowest());
    for (long long i = p.first_vertex; i < p.first_vertex + p.vertices; ++i)
      for (int c = 0; c < 3; ++c) {
        const float x = frame_[static_cast<std::size_t>(3 * i + c)];
        lo[static_cast<std::size_t>(c)] = std::min(lo[static_cast<std::size_t>(c)], x);
        hi[static_cast<std::size_t>(c)] = std::max(hi[static_cast<std::size_t>(c)], x);
      }
    const int a = accessor(view, p.first_vertex * 12, kFloat, p.vertices, "VEC3");
    accessors_[static_cast<std::size_t>(a)]["min"] = lo;
    accessors_[static_cast<std::size_t>(a)]["max"] = hi;
    return a;
  }

  // What every frame's primitive of part p shares: its indices (part-local), UVs and colours.
  json shared_accessors(const GltfPart& p, const Polygons& faces) {
    std::vector<std::uint32_t> idx;
    for (long long f = p.first_face; f < p.first_face + p.faces; ++f)
      for (int v : faces[static_cast<std::size_t>(f)]) idx.push_back(static_cast<std::uint32_t>(v - p.first_vertex));
    indices_.push_back(accessor(view(bytes_of(idx), kElementArrayBuffer), 0, kUint, static_cast<long long>(idx.size()), "SCALAR"));
    json a = json::object();
    if (!p.uv0.empty()) a["TEXCOORD_0"] = accessor(view(bytes_of(p.uv0), kArrayBuffer), 0, kFloat, p.vertices, "VEC2");
    if (!p.uv1.empty()) a["TEXCOORD_1"] = accessor(view(bytes_of(p.uv1), kArrayBuffer), 0, kFloat, p.vertices, "VEC2");
    if (!p.color.empty()) a["COLOR_0"] = accessor(view(bytes_of(p.color), kArrayBuffer), 0, kFloat, p.vertices, "VEC4");
    return a;
  }

  // Images stored in the input's buffer go into ours; those named by a uri keep it.
  void keep_images(const GltfAsset& a) {
    images_ = json::parse(a.images);
    for (std::size_t i = 0; i < images_.size() && i < a.image_bytes.size(); ++i) {
      if (a.image_bytes[i].empty()) continue;
      images_[i]["bufferView"] = view(a.image_bytes[i], 0);
      images_[i].erase("uri");
    }
  }

  // Node k is shown (scale 1) from its frame's time to the next frame's: keys at the times of
  // frames k-1, k, k+1 (a window of the one list of times), step interpolated. The last frame
  // lasts as long as the one before it (one more time), so that a looping player shows it.
  void add_animation() {
    std::vector<float> t(times_.begin(), times_.end());
    const std::size_t F = t.size();
    t.push_back(static_cast<float>(times_[F - 1] + (times_[F - 1] - times_[F - 2])));
    const int times_view = view(bytes_of(t), 0);
    const std::vector<float> show_first{1, 1, 1, 0, 0, 0}, show_middle{0, 0, 0, 1, 1, 1, 0, 0, 0};
    const std::vector<float> show_last{0, 0, 0, 1, 1, 1, 1, 1, 1};
    const int out_first = accessor(view(bytes_of(show_first), 0), 0, kFloat, 2, "VEC3");
    const int out_middle = accessor(view(bytes_of(show_middle), 0), 0, kFloat, 3, "VEC3");
    const int out_last = accessor(view(bytes_of(show_last), 0), 0, kFloat, 3, "VEC3");
    json samplers = json::array(), channels = json::array();
    for (std::size_t k = 0; k < F; ++k) {
      const std::size_t from = k == 0 ? 0 : k - 1, to = k + 1 == F ? F : k + 1;
      const int in = accessor(times_view, static_cast<long long>(from * 4), kFloat, static_cast<long long>(to - from + 1), "SCALAR");
      accessors_[static_cast<std::size_t>(in)]["min"] = {t[from]};
      accessors_[static_cast<std::size_t>(in)]["max"] = {t[to]};
      const int out = k == 0 ? out_first : k + 1 == F ? out_last : out_middle;
      samplers.push_back({{"input", in}, {"output", out}, {"interpolation", "STEP"}});
      channels.push_back({{"sampler", k}, {"target", {{"node", k + 1}, {"path", "scale"}}}});
    }
    animations_.push_back({{"name", "deformation"}, {"samplers", samplers}, {"channels", channels}});
  }

  json document() const {
    json children = json::array();
    for (std::size_t k = 0; k < nodes_.size(); ++k) children.push_back(k + 1);
    json nodes = json::array({{{"name", name_}, {"children", children}}});
    for (const json& n : nodes_) nodes.push_back(n);
    json j = {{"asset", {{"version", "2.0"}, {"generator", "mbi"}}}, {"scene", 0},
              {"scenes", json::array({{{"nodes", {0}}}})}, {"nodes", nodes}, {"meshes", meshes_},
              {"accessors", accessors_}, {"bufferViews", views_}};
    if (!animations_.empty()) j["animations"] = animations_;
    if (asset_) {
      for (auto [key, value] : {std::pair{"materials", &asset_->materials}, {"textures", &asset_->textures},
                                {"samplers", &asset_->samplers}})
        if (json array = json::parse(*value); !array.empty()) j[key] = std::move(array);
      if (!images_.empty()) j["images"] = images_;
      if (!asset_->extensions_used.empty()) j["extensionsUsed"] = asset_->extensions_used;
      if (!asset_->extensions_required.empty()) j["extensionsRequired"] = asset_->extensions_required;
    }
    return j;
  }

  path file_;
  std::string name_;
  long long vertices_;
  const GltfAsset* asset_ = nullptr;
  std::vector<GltfPart> parts_;
  std::vector<json> shared_;   // per part: its TEXCOORD/COLOR attributes
  std::vector<int> indices_;   // per part: its indices accessor
  std::vector<float> frame_;   // the last rows converted (positions: for min and max)
  Eigen::MatrixXd V_split_, N_split_;
  std::vector<unsigned char> bin_;
  json views_ = json::array(), accessors_ = json::array(), meshes_ = json::array(), nodes_ = json::array(),
       animations_ = json::array(), images_ = json::array();
  std::vector<double> times_;
};

void write_gltf(std::FILE* f, const SurfaceOutput& out) {
  const auto asset = out.attributes ? gltf_asset_of(*out.attributes, out.faces, out.V.rows(), out.file) : nullptr;
  GltfDocument doc(out.file, output_name(out.file).stem().string(), out.faces, out.V.rows(), asset.get());
  doc.add_frame(0.0, out.V, out.N);
  doc.write(f);
}

bool gltf_attributes_fit(const SurfaceAttributes& a, const Polygons& faces) {
  if (!a.gltf) return converts_to_gltf(a, faces);
  long long total = 0;
  for (const GltfPart& p : a.gltf->parts) {
    if (p.first_face != total || p.first_face + p.faces > static_cast<long long>(faces.size())) return false;
    for (long long f = p.first_face; f < p.first_face + p.faces; ++f)
      for (int v : faces[static_cast<std::size_t>(f)])
        if (v < p.first_vertex || v >= p.first_vertex + p.vertices) return false;
    total += p.faces;
  }
  return total == static_cast<long long>(faces.size());
}

}  // namespace detail

struct GltfWriter::State {
  detail::Polygons faces;
  std::shared_ptr<const detail::GltfAsset> asset;
  std::unique_ptr<detail::GltfDocument> doc;
};

GltfWriter::GltfWriter(const std::filesystem::path& file, const SurfaceMesh& topology) : file_(file), state_(std::make_unique<State>()) {
  const std::string ext = lower_extension(file);
  if (ext != ".glb" && ext != ".gltf") detail::fail(file, 0, "a glTF animation is written to .glb or .gltf");
  state_->faces = detail::faces_of(topology, topology.V, file, true);
  const SurfaceAttributes* a = topology.attributes.get();
  if (a && a->vertices == topology.V.rows() && detail::gltf_attributes_fit(*a, state_->faces))
    state_->asset = detail::gltf_asset_of(*a, state_->faces, topology.V.rows(), file);
  state_->doc = std::make_unique<detail::GltfDocument>(file, output_name(file).stem().string(), state_->faces,
                                                       topology.V.rows(), state_->asset.get());
}

GltfWriter::~GltfWriter() = default;

void GltfWriter::append(double time, const Eigen::Ref<const Eigen::MatrixXd>& V, const Eigen::Ref<const Eigen::MatrixXd>& N) {
  state_->doc->add_frame(time, V, N);
}

const std::vector<std::string>& GltfWriter::notes() const {
  static const std::vector<std::string> none;
  return state_->asset ? state_->asset->notes : none;
}

int GltfWriter::samples() const { return static_cast<int>(state_->doc->frames()); }

void GltfWriter::finish() {
  detail::write_atomic(file_, [&](std::FILE* f) { state_->doc->write(f); });
}

}  // namespace mbi::io
