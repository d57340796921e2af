// Dense surfaces: OBJ, OFF, PLY (ASCII / binary), STL (ASCII / binary).
//
// These are read and written here rather than through OpenMesh's IO layer: OpenMesh 9 hands
// OBJ/OFF vertices to its importer as float (losing the %.17g round trip) and its importer
// interface has no way to receive PLY double coordinates; its importer also duplicates
// vertices of non-manifold faces. Keeping vertex order, count and double precision exactly is
// simplest with the small parsers below.
#include "io_common.hpp"

#include <Eigen/Dense>

#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>

namespace mbi::io {
namespace {

using detail::fail;
using detail::fmt;
using detail::put;
using std::filesystem::path;

constexpr long long kMaxCount = std::numeric_limits<int>::max();

void fan(SurfaceMesh& m) {
  long long t = 0;
  for (const auto& p : m.polygons) t += static_cast<long long>(p.size()) - 2;
  m.F.resize(static_cast<Eigen::Index>(t), 3);
  Eigen::Index r = 0;
  for (const auto& p : m.polygons)
    for (std::size_t k = 1; k + 1 < p.size(); ++k) {
      m.F(r, 0) = p[0];
      m.F(r, 1) = p[k];
      m.F(r, 2) = p[k + 1];
      ++r;
    }
}

void set_vertices(SurfaceMesh& m, const std::vector<std::array<double, 3>>& v) {
  m.V.resize(static_cast<Eigen::Index>(v.size()), 3);
  for (std::size_t i = 0; i < v.size(); ++i)
    for (int c = 0; c < 3; ++c) m.V(static_cast<Eigen::Index>(i), c) = v[i][c];
}

// ---------------------------------------------------------------------------------------- OBJ
SurfaceMesh read_obj(const path& file) {
  const std::string text = detail::slurp(file);
  const auto lines = detail::tokenize(text);
  std::vector<std::array<double, 3>> v;
  SurfaceMesh m;
  std::vector<std::pair<int, std::vector<long long>>> faces;  // line, raw resolved indices
  for (const auto& l : lines) {
    if (l.tok[0] == "v") {
      if (l.tok.size() < 4) fail(file, l.number, "vertex " + std::to_string(v.size()) +
                                                     ": expected 3 coordinates");
      std::array<double, 3> p{};
      for (int c = 0; c < 3; ++c)
        p[c] = detail::to_double(l.tok[c + 1], file, l.number,
                                 "vertex " + std::to_string(v.size()) + " coordinate " +
                                     std::to_string(c));
      v.push_back(p);
    } else if (l.tok[0] == "f") {
      const std::string field = "face " + std::to_string(faces.size());
      if (l.tok.size() < 4) fail(file, l.number, field + ": fewer than 3 vertices");
      std::vector<long long> idx;
      for (std::size_t k = 1; k < l.tok.size(); ++k) {
        std::string_view s = l.tok[k];
        s = s.substr(0, s.find('/'));
        long long i = detail::to_int(s, file, l.number, field + " index", -kMaxCount, kMaxCount);
        if (i == 0) fail(file, l.number, field + ": index 0 (OBJ indices start at 1)");
        if (i < 0) {
          i += static_cast<long long>(v.size());
          if (i < 0) fail(file, l.number, field + ": relative index points before vertex 1");
        } else {
          i -= 1;
        }
        idx.push_back(i);
      }
      faces.emplace_back(l.number, std::move(idx));
    }
  }
  const long long nv = static_cast<long long>(v.size());
  for (const auto& [line, idx] : faces) {
    std::vector<int> p;
    for (long long i : idx) {
      if (i >= nv)
        fail(file, line, "face " + std::to_string(m.polygons.size()) + ": index " +
                             std::to_string(i + 1) + " > number of vertices " +
                             std::to_string(nv));
      p.push_back(static_cast<int>(i));
    }
    m.polygons.push_back(std::move(p));
  }
  set_vertices(m, v);
  fan(m);
  return m;
}

// ---------------------------------------------------------------------------------------- OFF
SurfaceMesh read_off(const path& file) {
  const std::string text = detail::slurp(file);
  const auto lines = detail::tokenize(text);
  if (lines.empty()) fail(file, 0, "empty file (expected an OFF header)");
  const auto& h = lines[0];
  const std::string_view magic = h.tok[0];
  if (magic.size() < 3 || magic.substr(magic.size() - 3) != "OFF")
    fail(file, h.number, "header: expected 'OFF', found '" + std::string(magic) + "'");
  if (h.tok.size() > 1 && h.tok[1] == "BINARY")
    fail(file, h.number, "header: binary OFF is not supported (use ASCII OFF or PLY)");
  // Counts may be on the header line or on the next one.
  std::size_t li = 0;
  std::vector<std::string_view> counts(h.tok.begin() + 1, h.tok.end());
  int count_line = h.number;
  if (counts.empty()) {
    if (lines.size() < 2) fail(file, h.number, "header: missing vertex/face counts");
    li = 1;
    counts = lines[1].tok;
    count_line = lines[1].number;
  }
  if (counts.size() < 2) fail(file, count_line, "header: expected '<vertices> <faces> <edges>'");
  const long long nv = detail::to_int(counts[0], file, count_line, "vertex count", 0, kMaxCount);
  const long long nf = detail::to_int(counts[1], file, count_line, "face count", 0, kMaxCount);
  const long long remaining = static_cast<long long>(lines.size() - li - 1);
  if (nv + nf > remaining)
    fail(file, count_line,
         "header: " + std::to_string(nv) + " vertices and " + std::to_string(nf) +
             " faces but only " + std::to_string(remaining) + " data lines follow");
  SurfaceMesh m;
  std::vector<std::array<double, 3>> v(static_cast<std::size_t>(nv));
  std::size_t at = li + 1;
  for (long long i = 0; i < nv; ++i, ++at) {
    const auto& l = lines[at];
    const std::string field = "vertex " + std::to_string(i);
    if (l.tok.size() < 3) fail(file, l.number, field + ": expected 3 coordinates");
    for (int c = 0; c < 3; ++c)
      v[static_cast<std::size_t>(i)][c] =
          detail::to_double(l.tok[c], file, l.number, field + " coordinate " + std::to_string(c));
  }
  m.polygons.reserve(static_cast<std::size_t>(nf));
  for (long long f = 0; f < nf; ++f, ++at) {
    const auto& l = lines[at];
    const std::string field = "face " + std::to_string(f);
    const long long k = detail::to_int(l.tok[0], file, l.number, field + " vertex count", 3,
                                       static_cast<long long>(l.tok.size()) - 1);
    std::vector<int> p;
    for (long long j = 1; j <= k; ++j)
      p.push_back(static_cast<int>(detail::to_int(l.tok[static_cast<std::size_t>(j)], file,
                                                  l.number, field + " index", 0, nv - 1)));
    m.polygons.push_back(std::move(p));
  }
  set_vertices(m, v);
  fan(m);
  return m;
}

// ---------------------------------------------------------------------------------------- PLY
enum class PlyType { i8, u8, i16, u16, i32, u32, f32, f64 };

bool ply_type(std::string_view s, PlyType& t) {
  static const std::pair<const char*, PlyType> names[] = {
      {"char", PlyType::i8},     {"int8", PlyType::i8},     {"uchar", PlyType::u8},
      {"uint8", PlyType::u8},    {"short", PlyType::i16},   {"int16", PlyType::i16},
      {"ushort", PlyType::u16},  {"uint16", PlyType::u16},  {"int", PlyType::i32},
      {"int32", PlyType::i32},   {"uint", PlyType::u32},    {"uint32", PlyType::u32},
      {"float", PlyType::f32},   {"float32", PlyType::f32}, {"double", PlyType::f64},
      {"float64", PlyType::f64}};
  for (const auto& [n, ty] : names)
    if (s == n) {
      t = ty;
      return true;
    }
  return false;
}

std::size_t ply_size(PlyType t) {
  switch (t) {
    case PlyType::i8:
    case PlyType::u8: return 1;
    case PlyType::i16:
    case PlyType::u16: return 2;
    case PlyType::i32:
    case PlyType::u32:
    case PlyType::f32: return 4;
    case PlyType::f64: return 8;
  }
  return 8;
}

struct PlyProp {
  std::string name;
  PlyType type = PlyType::f32;
  bool list = false;
  PlyType count_type = PlyType::u8;
};
struct PlyElement {
  std::string name;
  long long count = 0;
  std::vector<PlyProp> props;
  int line = 0;
};

struct BinaryCursor {
  const std::string& data;
  std::size_t pos;
  bool swap;
  const path& file;
  double read(PlyType t, const std::string& field) {
    const std::size_t n = ply_size(t);
    if (data.size() - pos < n) fail(file, 0, field + ": file truncated");
    unsigned char b[8];
    std::memcpy(b, data.data() + pos, n);
    pos += n;
    if (swap)
      for (std::size_t i = 0; i < n / 2; ++i) std::swap(b[i], b[n - 1 - i]);
    switch (t) {
      case PlyType::i8: { std::int8_t x; std::memcpy(&x, b, 1); return x; }
      case PlyType::u8: { std::uint8_t x; std::memcpy(&x, b, 1); return x; }
      case PlyType::i16: { std::int16_t x; std::memcpy(&x, b, 2); return x; }
      case PlyType::u16: { std::uint16_t x; std::memcpy(&x, b, 2); return x; }
      case PlyType::i32: { std::int32_t x; std::memcpy(&x, b, 4); return x; }
      case PlyType::u32: { std::uint32_t x; std::memcpy(&x, b, 4); return x; }
      case PlyType::f32: { float x; std::memcpy(&x, b, 4); return x; }
      case PlyType::f64: { double x; std::memcpy(&x, b, 8); return x; }
    }
    return 0.0;
  }
};

SurfaceMesh read_ply(const path& file) {
  const std::string data = detail::slurp(file);
  // Header: text lines up to "end_header".
  std::size_t body = std::string::npos;
  {
    std::size_t p = 0;
    while (p < data.size()) {
      std::size_t e = data.find('\n', p);
      if (e == std::string::npos) break;
      std::string_view l(data.data() + p, e - p);
      while (!l.empty() && (l.back() == '\r' || l.back() == ' ')) l.remove_suffix(1);
      if (l == "end_header") {
        body = e + 1;
        break;
      }
      p = e + 1;
    }
  }
  if (data.compare(0, 3, "ply") != 0) fail(file, 1, "not a PLY file (missing 'ply' magic)");
  if (body == std::string::npos) fail(file, 0, "header: missing 'end_header'");
  const auto header = detail::tokenize(std::string_view(data.data(), body), 0);
  enum class Format { none, ascii, le, be } format = Format::none;
  std::vector<PlyElement> elements;
  for (std::size_t i = 1; i < header.size(); ++i) {
    const auto& l = header[i];
    const auto& t = l.tok;
    if (t[0] == "format") {
      if (t.size() < 2) fail(file, l.number, "format: missing");
      if (t[1] == "ascii") format = Format::ascii;
      else if (t[1] == "binary_little_endian") format = Format::le;
      else if (t[1] == "binary_big_endian") format = Format::be;
      else fail(file, l.number, "format: unknown '" + std::string(t[1]) + "'");
    } else if (t[0] == "element") {
      if (t.size() != 3) fail(file, l.number, "element: expected 'element <name> <count>'");
      PlyElement e;
      e.name = std::string(t[1]);
      e.count = detail::to_int(t[2], file, l.number, "element " + e.name + " count", 0, kMaxCount);
      e.line = l.number;
      elements.push_back(std::move(e));
    } else if (t[0] == "property") {
      if (elements.empty()) fail(file, l.number, "property before any element");
      PlyProp p;
      if (t.size() == 3) {
        if (!ply_type(t[1], p.type)) fail(file, l.number, "property: unknown type '" + std::string(t[1]) + "'");
        p.name = std::string(t[2]);
      } else if (t.size() == 5 && t[1] == "list") {
        p.list = true;
        if (!ply_type(t[2], p.count_type) || !ply_type(t[3], p.type))
          fail(file, l.number, "property list: unknown type");
        if (p.count_type == PlyType::f32 || p.count_type == PlyType::f64)
          fail(file, l.number, "property list: count type must be an integer type");
        p.name = std::string(t[4]);
      } else {
        fail(file, l.number, "property: malformed");
      }
      elements.back().props.push_back(std::move(p));
    } else if (t[0] == "comment" || t[0] == "obj_info" || t[0] == "end_header") {
    } else {
      fail(file, l.number, "header: unknown keyword '" + std::string(t[0]) + "'");
    }
  }
  if (format == Format::none) fail(file, 0, "header: missing 'format' line");
  const PlyElement* ve = nullptr;
  const PlyElement* fe = nullptr;
  for (const auto& e : elements) {
    if (e.name == "vertex") ve = &e;
    if (e.name == "face") fe = &e;
  }
  if (!ve) fail(file, 0, "header: no 'vertex' element");
  int px = -1, py = -1, pz = -1, pf = -1;
  for (std::size_t k = 0; k < ve->props.size(); ++k) {
    const auto& p = ve->props[k];
    if (p.list) continue;
    if (p.name == "x") px = static_cast<int>(k);
    if (p.name == "y") py = static_cast<int>(k);
    if (p.name == "z") pz = static_cast<int>(k);
  }
  if (px < 0 || py < 0 || pz < 0) fail(file, ve->line, "element vertex: needs properties x, y, z");
  if (fe) {
    for (std::size_t k = 0; k < fe->props.size(); ++k)
      if (fe->props[k].list &&
          (fe->props[k].name == "vertex_indices" || fe->props[k].name == "vertex_index"))
        pf = static_cast<int>(k);
    if (pf < 0) fail(file, fe->line, "element face: needs a list property 'vertex_indices'");
  }
  const long long nv = ve->count;

  // Counts against the size of the body, before allocating anything for them.
  const std::size_t remaining = data.size() - body;
  std::vector<detail::Line> lines;
  if (format == Format::ascii) {
    lines = detail::tokenize(std::string_view(data).substr(body), 0);
    long long total = 0;
    for (const auto& e : elements) total += e.count;
    if (total > static_cast<long long>(lines.size()))
      fail(file, 0, "header: " + std::to_string(total) + " elements but only " +
                        std::to_string(lines.size()) + " data lines follow");
  } else {
    long double need = 0;
    for (const auto& e : elements) {
      std::size_t min = 0;
      for (const auto& p : e.props) min += p.list ? ply_size(p.count_type) : ply_size(p.type);
      need += static_cast<long double>(e.count) * static_cast<long double>(min);
    }
    if (need > static_cast<long double>(remaining))
      fail(file, 0, "header: element counts need at least " +
                        std::to_string(static_cast<long long>(need)) + " bytes but only " +
                        std::to_string(remaining) + " follow the header");
  }
  const int header_lines = header.empty() ? 0 : header.back().number;

  std::vector<std::array<double, 3>> v(static_cast<std::size_t>(nv));
  SurfaceMesh m;
  BinaryCursor cur{data, body, format == Format::be ? std::endian::native == std::endian::little
                                                   : std::endian::native == std::endian::big,
                   file};
  std::size_t line_at = 0;
  for (const auto& e : elements) {
    const bool is_v = &e == ve, is_f = &e == fe;
    for (long long i = 0; i < e.count; ++i) {
      const std::string field = e.name + " " + std::to_string(i);
      std::vector<double> scalars(e.props.size(), 0.0);
      std::vector<long long> list;
      if (format == Format::ascii) {
        const auto& l = lines[line_at++];
        const int ln = header_lines + l.number;
        std::size_t t = 0;
        for (std::size_t k = 0; k < e.props.size(); ++k) {
          const auto& p = e.props[k];
          if (t >= l.tok.size()) fail(file, ln, field + ": too few values");
          if (!p.list) {
            scalars[k] = detail::to_double(l.tok[t++], file, ln, field + " " + p.name);
          } else {
            const std::string_view count_tok = l.tok[t++];
            const long long n = detail::to_int(count_tok, file, ln, field + " " + p.name +
                                               " count", 0,
                                               static_cast<long long>(l.tok.size() - t));
            for (long long j = 0; j < n; ++j) {
              if (static_cast<int>(k) == pf && is_f)
                list.push_back(detail::to_int(l.tok[t], file, ln, field + " index", 0, nv - 1));
              ++t;
            }
          }
        }
        if (is_f && list.size() < 3) fail(file, ln, field + ": fewer than 3 vertices");
      } else {
        for (std::size_t k = 0; k < e.props.size(); ++k) {
          const auto& p = e.props[k];
          if (!p.list) {
            scalars[k] = cur.read(p.type, field + " " + p.name);
            continue;
          }
          const double nd = cur.read(p.count_type, field + " " + p.name + " count");
          if (nd < 0) fail(file, 0, field + ": negative list count");
          const auto n = static_cast<std::size_t>(nd);
          if (n > (data.size() - cur.pos) / ply_size(p.type))
            fail(file, 0, field + ": list of " + std::to_string(n) + " exceeds the file size");
          for (std::size_t j = 0; j < n; ++j) {
            const double x = cur.read(p.type, field + " index");
            if (static_cast<int>(k) == pf && is_f) {
              if (!(x >= 0 && x < static_cast<double>(nv)) || x != std::floor(x))
                fail(file, 0, field + ": index " + fmt(x) + " out of range [0, " +
                                  std::to_string(nv) + ")");
              list.push_back(static_cast<long long>(x));
            }
          }
        }
        if (is_f && list.size() < 3) fail(file, 0, field + ": fewer than 3 vertices");
      }
      if (is_v) {
        auto& p = v[static_cast<std::size_t>(i)];
        p = {scalars[static_cast<std::size_t>(px)], scalars[static_cast<std::size_t>(py)],
             scalars[static_cast<std::size_t>(pz)]};
        for (double c : p)
          if (!std::isfinite(c)) fail(file, 0, field + ": non-finite coordinate");
      }
      if (is_f) m.polygons.emplace_back(list.begin(), list.end());
    }
  }
  set_vertices(m, v);
  fan(m);
  return m;
}

// ---------------------------------------------------------------------------------------- STL
struct Merger {
  std::map<std::array<double, 3>, int> index;
  std::vector<std::array<double, 3>> v;
  int add(const std::array<double, 3>& p) {
    auto [it, fresh] = index.emplace(p, static_cast<int>(v.size()));
    if (fresh) v.push_back(p);
    return it->second;
  }
};

SurfaceMesh read_stl(const path& file) {
  const std::string data = detail::slurp(file);
  Merger merge;
  SurfaceMesh m;
  bool binary = false;
  if (data.size() >= 84) {
    std::uint32_t n = 0;
    std::memcpy(&n, data.data() + 80, 4);
    if constexpr (std::endian::native == std::endian::big) n = __builtin_bswap32(n);
    if (84 + 50ull * n == data.size()) binary = true;
    else if (data.compare(0, 5, "solid") != 0)
      fail(file, 0, "binary STL: header says " + std::to_string(n) + " triangles (" +
                        std::to_string(84 + 50ull * n) + " bytes) but the file has " +
                        std::to_string(data.size()) + " bytes");
  } else if (data.compare(0, 5, "solid") != 0) {
    fail(file, 0, "not an STL file (too short for binary, no 'solid' keyword)");
  }
  if (binary) {
    std::uint32_t n = 0;
    std::memcpy(&n, data.data() + 80, 4);
    if constexpr (std::endian::native == std::endian::big) n = __builtin_bswap32(n);
    for (std::uint32_t t = 0; t < n; ++t) {
      std::vector<int> tri;
      for (int k = 0; k < 3; ++k) {
        std::array<double, 3> p{};
        for (int c = 0; c < 3; ++c) {
          std::uint32_t bits = 0;
          std::memcpy(&bits, data.data() + 84 + 50ull * t + 12 + 12 * k + 4 * c, 4);
          if constexpr (std::endian::native == std::endian::big) bits = __builtin_bswap32(bits);
          p[c] = static_cast<double>(std::bit_cast<float>(bits));
          if (!std::isfinite(p[c]))
            fail(file, 0, "triangle " + std::to_string(t) + ": non-finite coordinate");
        }
        tri.push_back(merge.add(p));
      }
      m.polygons.push_back(std::move(tri));
    }
  } else {
    const auto lines = detail::tokenize(data, 0);
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
        for (int c = 0; c < 3; ++c) p[c] = detail::to_double(l.tok[c + 1], file, l.number, field);
        tri.push_back(merge.add(p));
      } else if (l.tok[0] == "endfacet") {
        if (tri.size() != 3) fail(file, l.number, field + ": expected 3 vertices, found " +
                                                      std::to_string(tri.size()));
        m.polygons.push_back(tri);
        facet_line = 0;
      }
    }
    if (facet_line != 0) fail(file, facet_line, "facet not closed (file truncated?)");
  }
  set_vertices(m, merge.v);
  fan(m);
  return m;
}

// -------------------------------------------------------------------------------------- write
std::vector<std::vector<int>> faces_of(const SurfaceMesh& m,
                                       const Eigen::Ref<const Eigen::MatrixXd>& V,
                                       const path& file, bool triangles) {
  if (V.cols() != 3) fail(file, 0, "V must be n x 3, got n x " + std::to_string(V.cols()));
  detail::check_finite(V, file, "vertex");
  std::vector<std::vector<int>> faces;
  if (!m.polygons.empty() && !triangles) {
    faces = m.polygons;
  } else {
    if (m.F.cols() != 3 && m.F.rows() > 0) fail(file, 0, "F must be t x 3");
    for (Eigen::Index i = 0; i < m.F.rows(); ++i) faces.push_back({m.F(i, 0), m.F(i, 1), m.F(i, 2)});
  }
  for (std::size_t i = 0; i < faces.size(); ++i) {
    if (faces[i].size() < 3) fail(file, 0, "face " + std::to_string(i) + ": fewer than 3 vertices");
    for (int x : faces[i])
      if (x < 0 || x >= V.rows())
        fail(file, 0, "face " + std::to_string(i) + ": index " + std::to_string(x) +
                          " out of range [0, " + std::to_string(V.rows()) + ")");
  }
  return faces;
}

template <typename T>
void put_le(std::FILE* f, T x, const path& file) {
  if constexpr (std::endian::native == std::endian::big) {
    unsigned char b[sizeof(T)];
    std::memcpy(b, &x, sizeof(T));
    for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
    put(f, b, sizeof(T), file);
  } else {
    put(f, &x, sizeof(T), file);
  }
}

}  // namespace

SurfaceMesh read_surface(const path& file) {
  const std::string ext = detail::extension(file);
  if (ext == ".obj") return read_obj(file);
  if (ext == ".off") return read_off(file);
  if (ext == ".ply") return read_ply(file);
  if (ext == ".stl") return read_stl(file);
  fail(file, 0, "unknown surface format '" + ext + "' (expected .obj, .off, .ply or .stl)");
}

void write_surface(const path& file, const SurfaceMesh& mesh, Encoding encoding) {
  detail::write_surface_positions(file, mesh, mesh.V, encoding);
}

void detail::write_surface_positions(const path& file, const SurfaceMesh& mesh,
                                     const Eigen::Ref<const Eigen::MatrixXd>& V,
                                     Encoding encoding) {
  const std::string ext = detail::extension(file);
  if (ext != ".obj" && ext != ".off" && ext != ".ply" && ext != ".stl")
    fail(file, 0, "unknown surface format '" + ext + "' (expected .obj, .off, .ply or .stl)");
  if (V.cols() != 3) fail(file, 0, "positions must have 3 columns");
  const auto faces = faces_of(mesh, V, file, ext == ".stl");
  detail::write_atomic(file, [&](std::FILE* f) {
    // OFF and ASCII PLY share these lines: "x y z" per vertex, "k i0 .. ik-1" per face (0-based).
    auto put_ascii_vertices = [&] {
      for (Eigen::Index i = 0; i < V.rows(); ++i)
        put(f, fmt(V(i, 0)) + " " + fmt(V(i, 1)) + " " + fmt(V(i, 2)) + "\n", file);
    };
    auto put_counted_faces = [&] {
      for (const auto& p : faces) {
        std::string s = std::to_string(p.size());
        for (int x : p) s += " " + std::to_string(x);
        put(f, s + "\n", file);
      }
    };
    if (ext == ".obj") {
      for (Eigen::Index i = 0; i < V.rows(); ++i)
        put(f, "v " + fmt(V(i, 0)) + " " + fmt(V(i, 1)) + " " + fmt(V(i, 2)) + "\n", file);
      for (const auto& p : faces) {
        std::string s = "f";
        for (int x : p) s += " " + std::to_string(x + 1);
        put(f, s + "\n", file);
      }
    } else if (ext == ".off") {
      put(f, "OFF\n" + std::to_string(V.rows()) + " " + std::to_string(faces.size()) + " 0\n",
          file);
      put_ascii_vertices();
      put_counted_faces();
    } else if (ext == ".ply") {
      std::size_t max_k = 0;
      for (const auto& p : faces) max_k = std::max(max_k, p.size());
      const bool wide = max_k > 255;
      put(f,
          std::string("ply\nformat ") +
              (encoding == Encoding::binary ? "binary_little_endian" : "ascii") +
              " 1.0\ncomment written by mbi\nelement vertex " + std::to_string(V.rows()) +
              "\nproperty double x\nproperty double y\nproperty double z\nelement face " +
              std::to_string(faces.size()) + "\nproperty list " + (wide ? "int" : "uchar") +
              " int vertex_indices\nend_header\n",
          file);
      if (encoding == Encoding::binary) {
        for (Eigen::Index i = 0; i < V.rows(); ++i)
          for (int c = 0; c < 3; ++c) put_le<double>(f, V(i, c), file);
        for (const auto& p : faces) {
          if (wide) put_le<std::int32_t>(f, static_cast<std::int32_t>(p.size()), file);
          else put_le<std::uint8_t>(f, static_cast<std::uint8_t>(p.size()), file);
          for (int x : p) put_le<std::int32_t>(f, x, file);
        }
      } else {
        put_ascii_vertices();
        put_counted_faces();
      }
    } else {  // .stl
      auto normal = [&](const std::vector<int>& p) {
        const Eigen::Vector3d a = V.row(p[0]).transpose();
        const Eigen::Vector3d e1 = V.row(p[1]).transpose() - a;
        const Eigen::Vector3d e2 = V.row(p[2]).transpose() - a;
        Eigen::Vector3d n = e1.cross(e2);
        const double len = n.norm();
        if (len > 0) n /= len;
        return n;
      };
      if (encoding == Encoding::binary) {
        char header[80] = {};
        std::snprintf(header, sizeof header, "binary STL written by mbi");
        put(f, header, 80, file);
        put_le<std::uint32_t>(f, static_cast<std::uint32_t>(faces.size()), file);
        for (const auto& p : faces) {
          const Eigen::Vector3d n = normal(p);
          for (int c = 0; c < 3; ++c) put_le<float>(f, static_cast<float>(n(c)), file);
          for (int k = 0; k < 3; ++k)
            for (int c = 0; c < 3; ++c) put_le<float>(f, static_cast<float>(V(p[k], c)), file);
          put_le<std::uint16_t>(f, 0, file);
        }
      } else {
        put(f, "solid mbi\n", file);
        for (const auto& p : faces) {
          const Eigen::Vector3d n = normal(p);
          std::string s = " facet normal " + fmt(n(0)) + " " + fmt(n(1)) + " " + fmt(n(2)) +
                          "\n  outer loop\n";
          for (int k = 0; k < 3; ++k)
            s += "   vertex " + fmt(V(p[k], 0)) + " " + fmt(V(p[k], 1)) + " " +
                 fmt(V(p[k], 2)) + "\n";
          put(f, s + "  endloop\n endfacet\n", file);
        }
        put(f, "endsolid mbi\n", file);
      }
    }
  });
}

void write_surface(const path& file, const Eigen::Ref<const Eigen::MatrixXd>& V,
                   const Eigen::Ref<const Eigen::MatrixXi>& F, Encoding encoding) {
  SurfaceMesh m;
  m.V = V;
  m.F = F;
  write_surface(file, m, encoding);
}

}  // namespace mbi::io
