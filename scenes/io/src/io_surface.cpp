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
#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>

namespace mbi::io {
namespace detail {
enum class PlyType { i8, u8, i16, u16, i32, u32, f32, f64 };

struct PlyProp {
  std::string name;
  std::string type_name, count_type_name;  // as written in the header
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

}  // namespace detail

struct SurfaceAttributes {
  std::string format;       // ".obj", ".ply" or ".stl"
  bool binary = false;      // PLY, STL
  bool big_endian = false;  // binary PLY
  long long vertices = 0;   // vertex count of the file (attributes fit a mesh with as many)

  // OBJ: the file's records in order (comments and blank lines dropped): verbatim text, or the
  // vertex / face of that index (written from the mesh). `vn` lines are not kept (N replaces
  // them).
  struct ObjRecord {
    enum class Kind { text, vertex, face } kind;
    int index;
    std::string text;
  };
  std::vector<ObjRecord> obj_records;
  std::vector<std::string> obj_vertex_tail;    // per vertex: numbers after x y z, or empty
  std::vector<std::vector<int>> obj_face_vt;   // per face and corner: 0-based vt, -1 = none

  // PLY: header comment/obj_info lines, elements as declared, and every value of every
  // element (per element, record after record; a list is its count, then its items).
  std::vector<std::string> ply_comments;
  std::vector<detail::PlyElement> ply_elements;
  std::vector<std::vector<double>> ply_values;
  std::vector<int> ply_face_sizes;  // sizes of the face element's vertex lists

  // STL: binary 80-byte header and per-triangle attribute words, or the ASCII solid's name.
  std::string stl_header;
  std::vector<std::uint16_t> stl_attributes;
  long long stl_triangles = 0;
};

namespace {

using detail::fail;
using detail::fmt;
using detail::put;
using detail::PlyElement;
using detail::PlyProp;
using detail::PlyType;
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

// v / |v| computed without overflow (v scaled by its largest component first); false when v
// is zero or not finite.
bool unit_vector(Eigen::RowVector3d& v) {
  if (!v.allFinite()) return false;  // maxCoeff is undefined with a NaN
  const double s = v.cwiseAbs().maxCoeff();
  if (!(s > 0)) return false;
  v /= s;
  v /= v.norm();
  return v.allFinite();
}

// Area-weighted vertex normals of the triangles F, written into the rows of N where `have` is
// false; every row of N is then made unit length ((0, 0, 1) for a vertex without area). Far-out
// coordinates (up to the readers' 1e300) overflow the area weights: such a vertex gets the sum
// of its faces' unit normals instead, so the normals are always finite.
void complete_normals(SurfaceMesh& m, std::vector<char> have) {
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(m.V.rows(), 3), U = A;
  for (Eigen::Index f = 0; f < m.F.rows(); ++f) {
    // edges from halves: no overflow for coordinates below the largest double / 2
    const Eigen::RowVector3d a = 0.5 * m.V.row(m.F(f, 0)), e1 = 0.5 * m.V.row(m.F(f, 1)) - a,
                             e2 = 0.5 * m.V.row(m.F(f, 2)) - a;
    const Eigen::RowVector3d n = 4.0 * e1.cross(e2);
    const double s = std::max(e1.cwiseAbs().maxCoeff(), e2.cwiseAbs().maxCoeff());
    Eigen::RowVector3d u = s > 0 ? Eigen::RowVector3d((e1 / s).cross(e2 / s)) : Eigen::RowVector3d::Zero();
    if (!unit_vector(u)) u.setZero();
    for (int k = 0; k < 3; ++k) {
      A.row(m.F(f, k)) += n;
      U.row(m.F(f, k)) += u;
    }
  }
  for (Eigen::Index i = 0; i < m.N.rows(); ++i) {
    Eigen::RowVector3d n = m.N.row(i);
    if (have[static_cast<std::size_t>(i)] && unit_vector(n)) {
      m.N.row(i) = n;
      continue;
    }
    n = A.row(i);
    if (!unit_vector(n)) {
      n = U.row(i);
      if (!unit_vector(n)) n << 0, 0, 1;
    }
    m.N.row(i) = n;
  }
}

// ---------------------------------------------------------------------------------------- OBJ
// One OBJ face corner "v", "v/t", "v//n" or "v/t/n": the three numbers as written (0 = none).
struct ObjCorner {
  long long v = 0, vt = 0, vn = 0;
};

// Resolves a 1-based or negative (relative) OBJ index against `count` items read so far;
// returns it 0-based.
long long obj_index(long long i, long long count, const path& file, int line,
                    const std::string& what) {
  if (i == 0) fail(file, line, what + ": index 0 (OBJ indices start at 1)");
  if (i < 0) {
    i += count;
    if (i < 0) fail(file, line, what + ": relative index points before the first one");
    return i;
  }
  return i - 1;
}

SurfaceMesh read_obj(std::string_view data, const path& file) {
  const std::string_view text = detail::skip_bom(data);
  auto attr = std::make_shared<SurfaceAttributes>();
  attr->format = ".obj";
  std::vector<std::array<double, 3>> v, vn;
  long long nvt = 0;
  bool any_tail = false;
  struct RawFace {
    int line;
    std::vector<long long> v, vt, vn;  // 0-based, -1 = none
  };
  std::vector<RawFace> faces;
  int number = 0;
  std::size_t pos = 0;
  while (pos < text.size()) {
    // A line ends at LF, CR LF or a lone CR.
    std::size_t end = text.find_first_of("\r\n", pos);
    if (end == std::string_view::npos) end = text.size();
    if (number < std::numeric_limits<int>::max()) ++number;  // saturates (files of > 2^31 lines)
    std::string_view raw(text.data() + pos, end - pos);
    pos = end + (end + 1 < text.size() && text[end] == '\r' && text[end + 1] == '\n' ? 2 : 1);
    const auto tl = detail::tokenize(raw);
    if (tl.empty()) continue;  // blank line or comment
    const auto& tok = tl[0].tok;
    if (tok[0] == "v") {
      if (tok.size() < 4) fail(file, number, "vertex " + std::to_string(v.size()) +
                                                  ": expected 3 coordinates");
      std::array<double, 3> p{};
      for (int c = 0; c < 3; ++c)
        p[c] = detail::to_coordinate(tok[c + 1], file, number,
                                     "vertex " + std::to_string(v.size()) + " coordinate " +
                                         std::to_string(c));
      std::string tail;
      if (tok.size() > 4) {  // w or vertex colours: kept as written
        tail.assign(tok[4].data(),
                    static_cast<std::size_t>(tok.back().data() + tok.back().size() - tok[4].data()));
        any_tail = true;
      }
      attr->obj_vertex_tail.push_back(std::move(tail));
      attr->obj_records.push_back({SurfaceAttributes::ObjRecord::Kind::vertex,
                                   static_cast<int>(v.size()), {}});
      v.push_back(p);
    } else if (tok[0] == "vn") {
      if (tok.size() < 4) fail(file, number, "normal " + std::to_string(vn.size()) +
                                                  ": expected 3 numbers");
      std::array<double, 3> n{};
      for (int c = 0; c < 3; ++c)
        n[c] = detail::to_double(tok[c + 1], file, number, "normal " + std::to_string(vn.size()));
      vn.push_back(n);
    } else if (tok[0] == "f") {
      const std::string field = "face " + std::to_string(faces.size());
      if (tok.size() < 4) fail(file, number, field + ": fewer than 3 vertices");
      RawFace f{number, {}, {}, {}};
      for (std::size_t k = 1; k < tok.size(); ++k) {
        const std::string_view s = tok[k];
        std::string_view parts[3];
        const std::size_t a = s.find('/');
        parts[0] = s.substr(0, a);
        if (a != std::string_view::npos) {
          const std::string_view rest = s.substr(a + 1);
          const std::size_t b = rest.find('/');
          parts[1] = rest.substr(0, b);
          if (b != std::string_view::npos) parts[2] = rest.substr(b + 1);
          if (parts[2].find('/') != std::string_view::npos)
            fail(file, number, field + ": corner '" + std::string(s) + "' has more than 3 numbers");
        }
        const long long iv = detail::to_int(parts[0], file, number, field + " index", -kMaxCount, kMaxCount);
        f.v.push_back(obj_index(iv, static_cast<long long>(v.size()), file, number, field));
        long long it = -1, in = -1;
        if (!parts[1].empty())
          it = obj_index(detail::to_int(parts[1], file, number, field + " texture index",
                                        -kMaxCount, kMaxCount),
                         nvt, file, number, field + " texture");
        if (!parts[2].empty())
          in = obj_index(detail::to_int(parts[2], file, number, field + " normal index",
                                        -kMaxCount, kMaxCount),
                         static_cast<long long>(vn.size()), file, number, field + " normal");
        f.vt.push_back(it);
        f.vn.push_back(in);
      }
      attr->obj_records.push_back({SurfaceAttributes::ObjRecord::Kind::face,
                                   static_cast<int>(faces.size()), {}});
      faces.push_back(std::move(f));
    } else {  // vt, g, o, usemtl, mtllib, s, l, ...: kept as written
      if (tok[0] == "vt") ++nvt;
      attr->obj_records.push_back({SurfaceAttributes::ObjRecord::Kind::text, 0, std::string(raw)});
    }
  }
  if (!any_tail) attr->obj_vertex_tail.clear();
  SurfaceMesh m;
  const long long nv = static_cast<long long>(v.size());
  const long long nn = static_cast<long long>(vn.size());
  set_vertices(m, v);
  std::vector<char> have(v.size(), 0);
  bool any_normal = false;
  if (nn > 0) m.N = Eigen::MatrixXd::Zero(nv, 3);
  for (std::size_t j = 0; j < faces.size(); ++j) {
    const RawFace& f = faces[j];
    const std::string field = "face " + std::to_string(j);
    std::vector<int> p;
    for (std::size_t k = 0; k < f.v.size(); ++k) {
      const long long i = f.v[k];
      if (i >= nv)
        fail(file, f.line, field + ": index " + std::to_string(i + 1) +
                               " > number of vertices " + std::to_string(nv));
      if (f.vt[k] >= nvt)
        fail(file, f.line, field + ": texture index " + std::to_string(f.vt[k] + 1) +
                               " > number of texture coordinates " + std::to_string(nvt));
      if (f.vn[k] >= nn)
        fail(file, f.line, field + ": normal index " + std::to_string(f.vn[k] + 1) +
                               " > number of normals " + std::to_string(nn));
      if (f.vn[k] >= 0 && !have[static_cast<std::size_t>(i)]) {
        const auto& n = vn[static_cast<std::size_t>(f.vn[k])];
        m.N.row(i) << n[0], n[1], n[2];
        have[static_cast<std::size_t>(i)] = 1;
        any_normal = true;
      }
      p.push_back(static_cast<int>(i));
    }
    m.polygons.push_back(std::move(p));
    std::vector<int> t(f.vt.begin(), f.vt.end());
    attr->obj_face_vt.push_back(std::move(t));
  }
  attr->vertices = nv;
  fan(m);
  if (any_normal) complete_normals(m, std::move(have));
  else m.N.resize(0, 0);
  m.attributes = std::move(attr);
  return m;
}

// ---------------------------------------------------------------------------------------- OFF
SurfaceMesh read_off(std::string_view data, const path& file) {
  const auto lines = detail::tokenize(detail::skip_bom(data));
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
      v[static_cast<std::size_t>(i)][c] = detail::to_coordinate(
          l.tok[c], file, l.number, field + " coordinate " + std::to_string(c));
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

struct BinaryCursor {
  std::string_view data;
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

SurfaceMesh read_ply(std::string_view bytes, const path& file) {
  const std::string_view data = detail::skip_bom(bytes);
  // Header: text lines up to "end_header".
  std::size_t body = std::string::npos;
  {
    std::size_t p = 0;
    while (p < data.size()) {
      std::size_t e = data.find('\n', p);
      if (e == std::string_view::npos) break;
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
  if (body == std::string_view::npos) fail(file, 0, "header: missing 'end_header'");
  const auto header = detail::tokenize(std::string_view(data.data(), body), 0);
  enum class Format { none, ascii, le, be } format = Format::none;
  auto attr = std::make_shared<SurfaceAttributes>();
  attr->format = ".ply";
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
        p.type_name = std::string(t[1]);
        p.name = std::string(t[2]);
      } else if (t.size() == 5 && t[1] == "list") {
        p.list = true;
        if (!ply_type(t[2], p.count_type) || !ply_type(t[3], p.type))
          fail(file, l.number, "property list: unknown type");
        if (p.count_type == PlyType::f32 || p.count_type == PlyType::f64)
          fail(file, l.number, "property list: count type must be an integer type");
        p.count_type_name = std::string(t[2]);
        p.type_name = std::string(t[3]);
        p.name = std::string(t[4]);
      } else {
        fail(file, l.number, "property: malformed");
      }
      elements.back().props.push_back(std::move(p));
    } else if (t[0] == "comment" || t[0] == "obj_info") {
      const char* b = t[0].data();
      const char* e = b;
      while (e < data.data() + body && *e != '\n' && *e != '\r') ++e;
      attr->ply_comments.emplace_back(b, static_cast<std::size_t>(e - b));
    } else if (t[0] == "end_header") {
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
  int px = -1, py = -1, pz = -1, pf = -1, pnx = -1, pny = -1, pnz = -1;
  for (std::size_t k = 0; k < ve->props.size(); ++k) {
    const auto& p = ve->props[k];
    if (p.list) continue;
    if (p.name == "x") px = static_cast<int>(k);
    if (p.name == "y") py = static_cast<int>(k);
    if (p.name == "z") pz = static_cast<int>(k);
    if (p.name == "nx") pnx = static_cast<int>(k);
    if (p.name == "ny") pny = static_cast<int>(k);
    if (p.name == "nz") pnz = static_cast<int>(k);
  }
  const bool normals = pnx >= 0 && pny >= 0 && pnz >= 0;
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
    lines = detail::tokenize(data.substr(body), 0);
    long long total = 0;
    for (const auto& e : elements) total += e.count;
    if (total > static_cast<long long>(lines.size()))
      fail(file, 0, "header: " + std::to_string(total) + " elements but only " +
                        std::to_string(lines.size()) + " data lines follow");
  } else {
    long double need = 0;
    for (const auto& e : elements) {
      // An element without properties takes no bytes, but its records are still looped over:
      // count it as one byte each, so that a short file cannot declare 2^31 of them.
      std::size_t min = 0;
      for (const auto& p : e.props) min += p.list ? ply_size(p.count_type) : ply_size(p.type);
      need += static_cast<long double>(e.count) * static_cast<long double>(std::max<std::size_t>(min, 1));
    }
    if (need > static_cast<long double>(remaining))
      fail(file, 0, "header: element counts need at least " +
                        std::to_string(static_cast<long long>(need)) + " bytes but only " +
                        std::to_string(remaining) + " follow the header");
  }
  const int header_lines = header.empty() ? 0 : header.back().number;

  std::vector<std::array<double, 3>> v(static_cast<std::size_t>(nv));
  std::vector<std::array<double, 3>> vnorm(normals ? static_cast<std::size_t>(nv) : 0);
  SurfaceMesh m;
  attr->ply_values.resize(elements.size());
  BinaryCursor cur{data, body, format == Format::be ? std::endian::native == std::endian::little
                                                   : std::endian::native == std::endian::big,
                   file};
  std::size_t line_at = 0;
  for (std::size_t ei = 0; ei < elements.size(); ++ei) {
    const auto& e = elements[ei];
    std::vector<double>& values = attr->ply_values[ei];
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
            values.push_back(scalars[k]);
          } else {
            const std::string_view count_tok = l.tok[t++];
            const long long n = detail::to_int(count_tok, file, ln, field + " " + p.name +
                                               " count", 0,
                                               static_cast<long long>(l.tok.size() - t));
            values.push_back(static_cast<double>(n));
            for (long long j = 0; j < n; ++j) {
              if (static_cast<int>(k) == pf && is_f) {
                list.push_back(detail::to_int(l.tok[t], file, ln, field + " index", 0, nv - 1));
                values.push_back(static_cast<double>(list.back()));
              } else {
                values.push_back(detail::to_double(l.tok[t], file, ln, field + " " + p.name));
              }
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
            values.push_back(scalars[k]);
            continue;
          }
          const double nd = cur.read(p.count_type, field + " " + p.name + " count");
          values.push_back(nd);
          if (nd < 0) fail(file, 0, field + ": negative list count");
          const auto n = static_cast<std::size_t>(nd);
          if (n > (data.size() - cur.pos) / ply_size(p.type))
            fail(file, 0, field + ": list of " + std::to_string(n) + " exceeds the file size");
          for (std::size_t j = 0; j < n; ++j) {
            const double x = cur.read(p.type, field + " index");
            values.push_back(x);
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
          detail::check_coordinate(c, file, format == Format::ascii ? header_lines + lines[line_at - 1].number : 0, field);
        if (normals)
          vnorm[static_cast<std::size_t>(i)] = {scalars[static_cast<std::size_t>(pnx)],
                                                scalars[static_cast<std::size_t>(pny)],
                                                scalars[static_cast<std::size_t>(pnz)]};
      }
      if (is_f) {
        m.polygons.emplace_back(list.begin(), list.end());
        attr->ply_face_sizes.push_back(static_cast<int>(list.size()));
      }
    }
  }
  set_vertices(m, v);
  fan(m);
  if (normals) {
    m.N.resize(nv, 3);
    std::vector<char> have(static_cast<std::size_t>(nv), 1);
    for (Eigen::Index i = 0; i < nv; ++i) {
      const auto& n = vnorm[static_cast<std::size_t>(i)];
      m.N.row(i) << n[0], n[1], n[2];
      if (!m.N.row(i).allFinite()) have[static_cast<std::size_t>(i)] = 0, m.N.row(i).setZero();
    }
    complete_normals(m, std::move(have));
  }
  attr->binary = format != Format::ascii;
  attr->big_endian = format == Format::be;
  attr->vertices = nv;
  attr->ply_elements = elements;
  m.attributes = std::move(attr);
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

// The triangle count of a binary STL (little-endian uint32 at byte 80; data has >= 84 bytes).
std::uint32_t stl_count(std::string_view data) {
  std::uint32_t n = 0;
  std::memcpy(&n, data.data() + 80, 4);
  if constexpr (std::endian::native == std::endian::big) n = __builtin_bswap32(n);
  return n;
}

SurfaceMesh read_stl(std::string_view bytes, const path& file) {
  // A binary STL is recognised by its size (84 + 50 per triangle); its 80-byte header may hold
  // anything, so a byte-order mark is skipped only for ASCII.
  std::string_view data = bytes;
  if (data.size() < 84 || 84 + 50ull * stl_count(data) != data.size()) data = detail::skip_bom(data);
  Merger merge;
  SurfaceMesh m;
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
  if (binary) {
    const std::uint32_t n = stl_count(data);
    attr->stl_header = std::string(data.substr(0, 80));
    bool any_attribute = false;
    for (std::uint32_t t = 0; t < n; ++t) {
      std::uint16_t word = 0;
      std::memcpy(&word, data.data() + 84 + 50ull * t + 48, 2);
      if constexpr (std::endian::native == std::endian::big) word = __builtin_bswap16(word);
      any_attribute = any_attribute || word != 0;
      attr->stl_attributes.push_back(word);
      std::vector<int> tri;
      for (int k = 0; k < 3; ++k) {
        std::array<double, 3> p{};
        for (int c = 0; c < 3; ++c) {
          std::uint32_t bits = 0;
          std::memcpy(&bits, data.data() + 84 + 50ull * t + 12 + 12 * k + 4 * c, 4);
          if constexpr (std::endian::native == std::endian::big) bits = __builtin_bswap32(bits);
          p[c] = static_cast<double>(std::bit_cast<float>(bits));
          detail::check_coordinate(p[c], file, 0, "triangle " + std::to_string(t));
        }
        tri.push_back(merge.add(p));
      }
      m.polygons.push_back(std::move(tri));
    }
    if (!any_attribute) attr->stl_attributes.clear();
  } else {
    const auto lines = detail::tokenize(data, 0);
    if (!lines.empty() && lines[0].tok[0] == "solid" && lines[0].tok.size() > 1) {
      const auto& t = lines[0].tok;
      attr->stl_header.assign(t[1].data(), static_cast<std::size_t>(t.back().data() +
                                                                      t.back().size() - t[1].data()));
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
        for (int c = 0; c < 3; ++c) p[c] = detail::to_coordinate(l.tok[c + 1], file, l.number, field);
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
  attr->vertices = m.V.rows();
  attr->stl_triangles = m.F.rows();
  m.attributes = std::move(attr);
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
void append_bytes(std::string& out, T x, bool big) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, &x, sizeof(T));
  if (big != (std::endian::native == std::endian::big))
    for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
  out.append(reinterpret_cast<const char*>(b), sizeof(T));
}

template <typename T>
T to_integer(double x) {
  const double lo = static_cast<double>(std::numeric_limits<T>::min());
  const double hi = static_cast<double>(std::numeric_limits<T>::max());
  return static_cast<T>(std::clamp(std::round(x), lo, hi));
}

// x as the PLY type t, binary (`big` endian).
void append_ply_binary(std::string& out, double x, PlyType t, bool big) {
  switch (t) {
    case PlyType::i8: append_bytes(out, to_integer<std::int8_t>(x), big); break;
    case PlyType::u8: append_bytes(out, to_integer<std::uint8_t>(x), big); break;
    case PlyType::i16: append_bytes(out, to_integer<std::int16_t>(x), big); break;
    case PlyType::u16: append_bytes(out, to_integer<std::uint16_t>(x), big); break;
    case PlyType::i32: append_bytes(out, to_integer<std::int32_t>(x), big); break;
    case PlyType::u32: append_bytes(out, to_integer<std::uint32_t>(x), big); break;
    case PlyType::f32: append_bytes(out, static_cast<float>(x), big); break;
    case PlyType::f64: append_bytes(out, x, big); break;
  }
}

// x as the PLY type t in ASCII: integers as integers, reals in the shortest form that reads
// back to the same float32 / float64 (so values read from a file are written as they were).
void append_ply_ascii(std::string& out, double x, PlyType t) {
  char buf[64];
  std::to_chars_result r{};
  if (t == PlyType::f32) r = std::to_chars(buf, buf + sizeof buf, static_cast<float>(x));
  else if (t == PlyType::f64) r = std::to_chars(buf, buf + sizeof buf, x);
  else r = std::to_chars(buf, buf + sizeof buf, static_cast<long long>(std::round(x)));
  out.append(buf, r.ptr);
}

void put_le_buffered(std::string& out, std::FILE* f, const path& file) {
  if (out.size() >= (1u << 20)) {
    put(f, out.data(), out.size(), file);
    out.clear();
  }
}

int find_prop(const PlyElement& e, const char* name, bool list) {
  for (std::size_t k = 0; k < e.props.size(); ++k)
    if (e.props[k].name == name && e.props[k].list == list) return static_cast<int>(k);
  return -1;
}

// Writes a PLY file from the elements and values read (attributes), with the positions V,
// normals N and faces in place of the file's.
void write_ply_attributes(std::FILE* f, const path& file, const SurfaceAttributes& a,
                          const Eigen::Ref<const Eigen::MatrixXd>& V,
                          const Eigen::Ref<const Eigen::MatrixXd>& N,
                          const std::vector<std::vector<int>>& faces, bool binary, bool big) {
  const bool has_n = N.rows() > 0;
  std::string h = std::string("ply\nformat ") +
                  (binary ? (big ? "binary_big_endian" : "binary_little_endian") : "ascii") +
                  " 1.0\n";
  for (const auto& c : a.ply_comments) h += c + "\n";
  int ve = -1, fe = -1;
  for (std::size_t i = 0; i < a.ply_elements.size(); ++i) {
    if (a.ply_elements[i].name == "vertex" && ve < 0) ve = static_cast<int>(i);
    if (a.ply_elements[i].name == "face" && fe < 0) fe = static_cast<int>(i);
  }
  int pos[3] = {-1, -1, -1}, nrm[3] = {-1, -1, -1}, pf = -1;
  bool add_normals = false;
  if (ve >= 0) {
    const auto& e = a.ply_elements[static_cast<std::size_t>(ve)];
    const char* pn[3] = {"x", "y", "z"};
    const char* nn[3] = {"nx", "ny", "nz"};
    for (int c = 0; c < 3; ++c) {
      pos[c] = find_prop(e, pn[c], false);
      nrm[c] = find_prop(e, nn[c], false);
    }
    add_normals = has_n && (nrm[0] < 0 || nrm[1] < 0 || nrm[2] < 0);
    if (add_normals) nrm[0] = nrm[1] = nrm[2] = -1;
  }
  if (fe >= 0) {
    pf = find_prop(a.ply_elements[static_cast<std::size_t>(fe)], "vertex_indices", true);
    if (pf < 0) pf = find_prop(a.ply_elements[static_cast<std::size_t>(fe)], "vertex_index", true);
  }
  for (std::size_t i = 0; i < a.ply_elements.size(); ++i) {
    const auto& e = a.ply_elements[i];
    h += "element " + e.name + " " + std::to_string(e.count) + "\n";
    for (const auto& p : e.props)
      h += p.list ? "property list " + p.count_type_name + " " + p.type_name + " " + p.name + "\n"
                  : "property " + p.type_name + " " + p.name + "\n";
    if (static_cast<int>(i) == ve && add_normals)
      h += "property double nx\nproperty double ny\nproperty double nz\n";
  }
  h += "end_header\n";
  put(f, h, file);
  std::string out;
  for (std::size_t ei = 0; ei < a.ply_elements.size(); ++ei) {
    const auto& e = a.ply_elements[ei];
    const auto& vals = a.ply_values[ei];
    const bool is_v = static_cast<int>(ei) == ve, is_f = static_cast<int>(ei) == fe;
    std::size_t at = 0;
    for (long long r = 0; r < e.count; ++r) {
      bool first = true;
      auto emit = [&](double x, PlyType t, bool exact) {
        if (binary) {
          append_ply_binary(out, x, t, big);
          return;
        }
        if (!first) out += ' ';
        first = false;
        if (exact) out += fmt(x);
        else append_ply_ascii(out, x, t);
      };
      for (std::size_t k = 0; k < e.props.size(); ++k) {
        const auto& p = e.props[k];
        const int ki = static_cast<int>(k);
        if (!p.list) {
          double x = vals[at++];
          bool exact = false;
          if (is_v)
            for (int c = 0; c < 3; ++c) {
              if (ki == pos[c]) x = V(r, c), exact = true;
              if (ki == nrm[c] && has_n) x = N(r, c), exact = true;
            }
          emit(x, p.type, exact);
          continue;
        }
        const auto n = static_cast<std::size_t>(vals[at++]);
        emit(static_cast<double>(n), p.count_type, false);
        for (std::size_t j = 0; j < n; ++j) {
          double x = vals[at++];
          if (is_f && ki == pf) x = faces[static_cast<std::size_t>(r)][j];
          emit(x, p.type, false);
        }
      }
      if (is_v && add_normals)
        for (int c = 0; c < 3; ++c) emit(N(r, c), PlyType::f64, true);
      if (!binary) out += '\n';
      put_le_buffered(out, f, file);
    }
  }
  put(f, out.data(), out.size(), file);
}

// Whether the attributes read from a file can be written back with these vertices and faces.
bool attributes_fit(const SurfaceAttributes* a, const std::string& ext, Eigen::Index vertices,
                    const std::vector<std::vector<int>>& faces) {
  if (!a || a->format != ext || a->vertices != vertices) return false;
  auto sizes_match = [&](const auto& per_face, auto size_of) {
    if (per_face.size() != faces.size()) return false;
    for (std::size_t i = 0; i < faces.size(); ++i)
      if (static_cast<std::size_t>(size_of(per_face[i])) != faces[i].size()) return false;
    return true;
  };
  if (ext == ".obj")
    return sizes_match(a->obj_face_vt, [](const std::vector<int>& c) { return c.size(); });
  if (ext == ".ply") return sizes_match(a->ply_face_sizes, [](int k) { return k; });
  if (ext == ".stl") return a->stl_triangles == static_cast<long long>(faces.size());
  return false;
}

}  // namespace

bool is_surface_file(const path& file) {
  const std::string ext = detail::extension(file);
  return ext == ".obj" || ext == ".off" || ext == ".ply" || ext == ".stl";
}

SurfaceMesh parse_surface(std::string_view data, const path& file) {
  const std::string ext = detail::extension(file);
  if (ext == ".obj") return read_obj(data, file);
  if (ext == ".off") return read_off(data, file);
  if (ext == ".ply") return read_ply(data, file);
  if (ext == ".stl") return read_stl(data, file);
  fail(file, 0, "unknown surface format '" + ext + "' (expected .obj, .off, .ply or .stl)");
}

SurfaceMesh read_surface(const path& file) {
  const std::string ext = detail::extension(file);
  std::error_code ec;  // what was given (a FIFO, a directory) is named before its extension
  if (std::filesystem::exists(file, ec)) detail::require_regular_file(file);
  if (!is_surface_file(file))
    fail(file, 0, "unknown surface format '" + ext + "' (expected .obj, .off, .ply or .stl)");
  return parse_surface(detail::slurp(file), file);
}

void write_surface(const path& file, const SurfaceMesh& mesh, Encoding encoding) {
  detail::write_surface_positions(file, mesh, mesh.V, mesh.N, encoding);
}

void detail::write_surface_positions(const path& file, const SurfaceMesh& mesh,
                                     const Eigen::Ref<const Eigen::MatrixXd>& V,
                                     const Eigen::Ref<const Eigen::MatrixXd>& N,
                                     Encoding encoding) {
  const std::string ext = detail::extension(file);
  if (!is_surface_file(file))
    fail(file, 0, "unknown surface format '" + ext + "' (expected .obj, .off, .ply or .stl)");
  if (V.cols() != 3) fail(file, 0, "positions must have 3 columns");
  const bool has_n = N.size() > 0;
  if (has_n && (N.rows() != V.rows() || N.cols() != 3))
    fail(file, 0, "normals must be " + std::to_string(V.rows()) + " x 3, got " +
                      std::to_string(N.rows()) + " x " + std::to_string(N.cols()));
  if (has_n) detail::check_finite(N, file, "normal");
  const auto faces = faces_of(mesh, V, file, ext == ".stl");
  const SurfaceAttributes* attr =
      attributes_fit(mesh.attributes.get(), ext, V.rows(), faces) ? mesh.attributes.get() : nullptr;
  const bool binary =
      encoding == Encoding::binary || (encoding == Encoding::as_read && attr && attr->binary);
  const bool big = binary && attr && attr->big_endian;
  detail::write_atomic(file, [&](std::FILE* f) {
    // OFF and ASCII PLY share these lines: "x y z" per vertex, "k i0 .. ik-1" per face (0-based).
    auto put_ascii_vertices = [&] {
      for (Eigen::Index i = 0; i < V.rows(); ++i) {
        std::string l = fmt(V(i, 0)) + " " + fmt(V(i, 1)) + " " + fmt(V(i, 2));
        if (has_n && ext == ".ply") l += " " + fmt(N(i, 0)) + " " + fmt(N(i, 1)) + " " + fmt(N(i, 2));
        put(f, l + "\n", file);
      }
    };
    auto put_counted_faces = [&] {
      for (const auto& p : faces) {
        std::string s = std::to_string(p.size());
        for (int x : p) s += " " + std::to_string(x);
        put(f, s + "\n", file);
      }
    };
    if (ext == ".obj") {
      auto vertex = [&](Eigen::Index i, const std::string* tail) {
        std::string s = "v " + fmt(V(i, 0)) + " " + fmt(V(i, 1)) + " " + fmt(V(i, 2));
        if (tail && !tail->empty()) s += " " + *tail;
        s += "\n";
        if (has_n) s += "vn " + fmt(N(i, 0)) + " " + fmt(N(i, 1)) + " " + fmt(N(i, 2)) + "\n";
        put(f, s, file);
      };
      // v, v/vt, v//vn or v/vt/vn; the normal of a corner is its vertex's (one vn per vertex)
      auto face = [&](std::size_t j, const std::vector<int>* vt) {
        std::string s = "f";
        const auto& p = faces[j];
        for (std::size_t k = 0; k < p.size(); ++k) {
          const std::string v = std::to_string(p[k] + 1);
          const int t = vt ? (*vt)[k] : -1;
          s += " " + v;
          if (t >= 0) s += "/" + std::to_string(t + 1);
          if (has_n) s += (t >= 0 ? "/" : "//") + v;
        }
        put(f, s + "\n", file);
      };
      if (attr) {
        for (const auto& r : attr->obj_records) {
          using Kind = SurfaceAttributes::ObjRecord::Kind;
          const auto i = static_cast<std::size_t>(r.index);
          if (r.kind == Kind::text) put(f, r.text + "\n", file);
          else if (r.kind == Kind::vertex)
            vertex(r.index, attr->obj_vertex_tail.empty() ? nullptr : &attr->obj_vertex_tail[i]);
          else face(i, &attr->obj_face_vt[i]);
        }
      } else {
        for (Eigen::Index i = 0; i < V.rows(); ++i) vertex(i, nullptr);
        for (std::size_t j = 0; j < faces.size(); ++j) face(j, nullptr);
      }
    } else if (ext == ".off") {
      put(f, "OFF\n" + std::to_string(V.rows()) + " " + std::to_string(faces.size()) + " 0\n",
          file);
      put_ascii_vertices();
      put_counted_faces();
    } else if (ext == ".ply" && attr) {
      write_ply_attributes(f, file, *attr, V, N, faces, binary, big);
    } else if (ext == ".ply") {
      std::size_t max_k = 0;
      for (const auto& p : faces) max_k = std::max(max_k, p.size());
      const bool wide = max_k > 255;
      put(f,
          std::string("ply\nformat ") + (binary ? "binary_little_endian" : "ascii") +
              " 1.0\ncomment written by mbi\nelement vertex " + std::to_string(V.rows()) +
              "\nproperty double x\nproperty double y\nproperty double z\n" +
              (has_n ? "property double nx\nproperty double ny\nproperty double nz\n" : "") +
              "element face " + std::to_string(faces.size()) + "\nproperty list " +
              (wide ? "int" : "uchar") + " int vertex_indices\nend_header\n",
          file);
      if (binary) {
        std::string out;
        for (Eigen::Index i = 0; i < V.rows(); ++i) {
          for (int c = 0; c < 3; ++c) append_bytes<double>(out, V(i, c), false);
          if (has_n)
            for (int c = 0; c < 3; ++c) append_bytes<double>(out, N(i, c), false);
          put_le_buffered(out, f, file);
        }
        for (const auto& p : faces) {
          if (wide) append_bytes<std::int32_t>(out, static_cast<std::int32_t>(p.size()), false);
          else append_bytes<std::uint8_t>(out, static_cast<std::uint8_t>(p.size()), false);
          for (int x : p) append_bytes<std::int32_t>(out, x, false);
          put_le_buffered(out, f, file);
        }
        put(f, out.data(), out.size(), file);
      } else {
        put_ascii_vertices();
        put_counted_faces();
      }
    } else {  // .stl: facet normals from the positions
      auto normal = [&](const std::vector<int>& p) {
        const Eigen::Vector3d a = V.row(p[0]).transpose();
        const Eigen::Vector3d e1 = V.row(p[1]).transpose() - a;
        const Eigen::Vector3d e2 = V.row(p[2]).transpose() - a;
        Eigen::Vector3d n = e1.cross(e2);
        const double len = n.norm();
        if (len > 0) n /= len;
        return Eigen::Vector3d(n.array() + 0.0);  // -0 written as 0
      };
      if (binary) {
        std::string out;
        if (attr && attr->binary) {
          out = attr->stl_header;
        } else {
          char header[80] = {};
          std::snprintf(header, sizeof header, "binary STL written by mbi");
          out.assign(header, 80);
        }
        append_bytes<std::uint32_t>(out, static_cast<std::uint32_t>(faces.size()), false);
        for (std::size_t t = 0; t < faces.size(); ++t) {
          const auto& p = faces[t];
          const Eigen::Vector3d n = normal(p);
          for (int c = 0; c < 3; ++c) append_bytes<float>(out, static_cast<float>(n(c)), false);
          for (int k = 0; k < 3; ++k)
            for (int c = 0; c < 3; ++c) append_bytes<float>(out, static_cast<float>(V(p[k], c)), false);
          const std::uint16_t word =
              attr && !attr->stl_attributes.empty() ? attr->stl_attributes[t] : 0;
          append_bytes<std::uint16_t>(out, word, false);
          put_le_buffered(out, f, file);
        }
        put(f, out.data(), out.size(), file);
      } else {
        const std::string name = attr && !attr->binary && !attr->stl_header.empty()
                                     ? attr->stl_header : std::string("mbi");
        put(f, "solid " + name + "\n", file);
        for (const auto& p : faces) {
          const Eigen::Vector3d n = normal(p);
          std::string s = " facet normal " + fmt(n(0)) + " " + fmt(n(1)) + " " + fmt(n(2)) +
                          "\n  outer loop\n";
          for (int k = 0; k < 3; ++k)
            s += "   vertex " + fmt(V(p[k], 0)) + " " + fmt(V(p[k], 1)) + " " +
                 fmt(V(p[k], 2)) + "\n";
          put(f, s + "  endloop\n endfacet\n", file);
        }
        put(f, "endsolid " + name + "\n", file);
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
