// STL: binary (80-byte header, uint32 triangle count, 50 bytes a triangle, little endian) or
// ASCII ("solid", then "facet" / "vertex x y z" / "endfacet"). STL has no shared vertices and
// stores float32 (binary).
#include "surface.hpp"

#include <Eigen/Geometry>

#include <array>
#include <map>

namespace mbi::io::detail {
namespace {

using std::filesystem::path;

// Vertices from corners: a corner bitwise equal to an earlier one is that vertex.
struct Merger {
  std::map<std::array<double, 3>, int> index;
  std::vector<std::array<double, 3>> v;
  int add(const std::array<double, 3>& p) {
    auto [it, fresh] = index.emplace(p, static_cast<int>(v.size()));
    if (fresh) v.push_back(p);
    return it->second;
  }
};

// The triangle count of a binary STL (data has >= 84 bytes).
std::uint32_t stl_count(std::string_view data) { return load_le<std::uint32_t>(data.data() + 80); }

void read_binary(std::string_view data, const path& file, Merger& merge, SurfaceMesh& m,
                 StlAttributes& a) {
  const std::uint32_t n = stl_count(data);
  a.header = std::string(data.substr(0, 80));
  bool any_word = false;
  for (std::uint32_t t = 0; t < n; ++t) {
    const char* rec = data.data() + 84 + 50ull * t;
    const auto word = load_le<std::uint16_t>(rec + 48);
    any_word = any_word || word != 0;
    a.words.push_back(word);
    std::vector<int> tri;
    for (int k = 0; k < 3; ++k) {
      std::array<double, 3> p{};
      for (int c = 0; c < 3; ++c) {
        p[c] = static_cast<double>(load_le<float>(rec + 12 + 12 * k + 4 * c));
        check_coordinate(p[c], file, 0, "triangle " + std::to_string(t));
      }
      tri.push_back(merge.add(p));
    }
    m.polygons.push_back(std::move(tri));
  }
  if (!any_word) a.words.clear();
}

void read_ascii(std::string_view data, const path& file, Merger& merge, SurfaceMesh& m,
                StlAttributes& a) {
  const auto lines = tokenize(data, 0);
  if (!lines.empty() && lines[0].tok[0] == "solid" && lines[0].tok.size() > 1) {
    const auto& t = lines[0].tok;
    a.header.assign(t[1].data(), static_cast<std::size_t>(t.back().data() + t.back().size() - t[1].data()));
  }
  std::vector<int> tri;
  int facet_line = 0;
  for (const auto& l : lines) {
    const std::string field = "facet " + std::to_string(m.polygons.size());
    if (l.tok[0] == "facet") {
      tri.clear();
      facet_line = l.number;
    } else if (l.tok[0] == "vertex") {
      if (l.tok.size() != 4) fail(file, l.number, field + ": expected 'vertex x y z'");
      if (facet_line == 0) fail(file, l.number, "vertex outside a facet");
      std::array<double, 3> p{};
      for (int c = 0; c < 3; ++c) p[c] = to_coordinate(l.tok[c + 1], file, l.number, field);
      tri.push_back(merge.add(p));
    } else if (l.tok[0] == "endfacet") {
      if (tri.size() != 3)
        fail(file, l.number, field + ": expected 3 vertices, found " + std::to_string(tri.size()));
      m.polygons.push_back(tri);
      facet_line = 0;
    }
  }
  if (facet_line != 0) fail(file, facet_line, "facet not closed (file truncated?)");
}

// The unit normal of triangle p, from the positions (0 when degenerate; -0 written as 0).
Eigen::Vector3d facet_normal(const Eigen::Ref<const Eigen::MatrixXd>& V, const std::vector<int>& p) {
  const Eigen::Vector3d a = V.row(p[0]).transpose();
  const Eigen::Vector3d e1 = V.row(p[1]).transpose() - a;
  const Eigen::Vector3d e2 = V.row(p[2]).transpose() - a;
  Eigen::Vector3d n = e1.cross(e2);
  const double len = n.norm();
  if (len > 0) n /= len;
  return Eigen::Vector3d(n.array() + 0.0);
}

void write_binary(std::FILE* f, const SurfaceOutput& out) {
  const SurfaceAttributes* attr = out.attributes;
  std::string buf;
  if (attr && attr->binary) {
    buf = attr->stl.header;
  } else {
    char header[80] = {};
    std::snprintf(header, sizeof header, "binary STL written by mbi");
    buf.assign(header, 80);
  }
  append_bytes<std::uint32_t>(buf, static_cast<std::uint32_t>(out.faces.size()), false);
  for (std::size_t t = 0; t < out.faces.size(); ++t) {
    const auto& p = out.faces[t];
    const Eigen::Vector3d n = facet_normal(out.V, p);
    for (int c = 0; c < 3; ++c) append_bytes<float>(buf, static_cast<float>(n(c)), false);
    for (int k = 0; k < 3; ++k)
      for (int c = 0; c < 3; ++c) append_bytes<float>(buf, static_cast<float>(out.V(p[k], c)), false);
    const std::uint16_t word = attr && !attr->stl.words.empty() ? attr->stl.words[t] : 0;
    append_bytes<std::uint16_t>(buf, word, false);
    put_buffered(buf, f, out.file);
  }
  put(f, buf.data(), buf.size(), out.file);
}

void write_ascii(std::FILE* f, const SurfaceOutput& out) {
  const SurfaceAttributes* attr = out.attributes;
  const auto& V = out.V;
  const std::string name =
      attr && !attr->binary && !attr->stl.header.empty() ? attr->stl.header : std::string("mbi");
  put(f, "solid " + name + "\n", out.file);
  for (const auto& p : out.faces) {
    const Eigen::Vector3d n = facet_normal(V, p);
    std::string s = " facet normal " + fmt(n(0)) + " " + fmt(n(1)) + " " + fmt(n(2)) +
                    "\n  outer loop\n";
    for (int k = 0; k < 3; ++k)
      s += "   vertex " + fmt(V(p[k], 0)) + " " + fmt(V(p[k], 1)) + " " + fmt(V(p[k], 2)) + "\n";
    put(f, s + "  endloop\n endfacet\n", out.file);
  }
  put(f, "endsolid " + name + "\n", out.file);
}

}  // namespace

SurfaceMesh parse_stl(std::string_view bytes, const path& file) {
  // A binary STL is recognised by its size (84 + 50 per triangle); its 80-byte header may hold
  // anything, so a byte-order mark is skipped only for ASCII.
  std::string_view data = bytes;
  if (data.size() < 84 || 84 + 50ull * stl_count(data) != data.size()) data = skip_bom(data);
  bool binary = false;
  if (data.size() >= 84) {
    const std::uint32_t n = stl_count(data);
    if (84 + 50ull * n == data.size()) binary = true;
    else if (data.compare(0, 5, "solid") != 0)
      fail(file, 0, "binary STL: header says " + std::to_string(n) + " triangles (" +
                        std::to_string(84 + 50ull * n) + " bytes) but the file has " +
                        std::to_string(data.size()) + " bytes");
  } else if (data.compare(0, 5, "solid") != 0) {
    fail(file, 0, "not an STL file (too short for binary, no 'solid' keyword)");
  }
  auto attr = std::make_shared<SurfaceAttributes>();
  attr->format = ".stl";
  attr->binary = binary;
  Merger merge;
  SurfaceMesh m;
  if (binary) read_binary(data, file, merge, m, attr->stl);
  else read_ascii(data, file, merge, m, attr->stl);
  set_vertices(m, merge.v);
  fan(m);
  attr->vertices = m.V.rows();
  attr->stl.triangles = m.F.rows();
  m.attributes = std::move(attr);
  return m;
}

bool stl_attributes_fit(const SurfaceAttributes& a, const std::vector<std::vector<int>>& faces) {
  return a.stl.triangles == static_cast<long long>(faces.size());
}

void write_stl(std::FILE* f, const SurfaceOutput& out) {
  if (out.binary) write_binary(f, out);
  else write_ascii(f, out);
}

}  // namespace mbi::io::detail
