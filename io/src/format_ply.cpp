// PLY: a text header (format, elements and their scalar or list properties, comments) up to
// "end_header", then the records of each element in ASCII or binary of either endianness.
// Positions are vertex x, y, z of any scalar type, normals nx, ny, nz, faces the list
// "vertex_indices" (or "vertex_index"); every other property and element is kept.
//
// Read and written here rather than through OpenMesh's IO layer, whose importer interface
// cannot receive PLY double coordinates.
#include "surface.hpp"

#include <array>
#include <charconv>
#include <cmath>
#include <limits>

namespace mbi::io::detail {
namespace {

using std::filesystem::path;

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
    const char* p = data.data() + pos;
    pos += n;
    switch (t) {
      case PlyType::i8: return load_bytes<std::int8_t>(p, swap);
      case PlyType::u8: return load_bytes<std::uint8_t>(p, swap);
      case PlyType::i16: return load_bytes<std::int16_t>(p, swap);
      case PlyType::u16: return load_bytes<std::uint16_t>(p, swap);
      case PlyType::i32: return load_bytes<std::int32_t>(p, swap);
      case PlyType::u32: return load_bytes<std::uint32_t>(p, swap);
      case PlyType::f32: return load_bytes<float>(p, swap);
      case PlyType::f64: return load_bytes<double>(p, swap);
    }
    return 0.0;
  }
};

// --------------------------------------------------------------------------------- reading
enum class PlyFormat { none, ascii, le, be };

struct PlyHeader {
  PlyFormat format = PlyFormat::none;
  std::vector<PlyElement> elements;
  std::size_t body = 0;  // offset of the first record's byte
  int lines = 0;         // lines up to end_header (ASCII records are numbered after them)
};

// The offset just past the "end_header" line, or npos.
std::size_t find_body(std::string_view data) {
  std::size_t p = 0;
  while (p < data.size()) {
    const std::size_t e = data.find('\n', p);
    if (e == std::string_view::npos) break;
    std::string_view l(data.data() + p, e - p);
    while (!l.empty() && (l.back() == '\r' || l.back() == ' ')) l.remove_suffix(1);
    if (l == "end_header") return e + 1;
    p = e + 1;
  }
  return std::string_view::npos;
}

PlyProp read_property(const std::vector<std::string_view>& t, int number, const path& file) {
  PlyProp p;
  if (t.size() == 3) {
    if (!ply_type(t[1], p.type)) fail(file, number, "property: unknown type '" + std::string(t[1]) + "'");
    p.type_name = std::string(t[1]);
    p.name = std::string(t[2]);
  } else if (t.size() == 5 && t[1] == "list") {
    p.list = true;
    if (!ply_type(t[2], p.count_type) || !ply_type(t[3], p.type))
      fail(file, number, "property list: unknown type");
    if (p.count_type == PlyType::f32 || p.count_type == PlyType::f64)
      fail(file, number, "property list: count type must be an integer type");
    p.count_type_name = std::string(t[2]);
    p.type_name = std::string(t[3]);
    p.name = std::string(t[4]);
  } else {
    fail(file, number, "property: malformed");
  }
  p.line = number;
  return p;
}

// The header; its comment and obj_info lines go to `comments`.
PlyHeader read_header(std::string_view data, const path& file, std::vector<std::string>& comments) {
  PlyHeader h;
  h.body = find_body(data);
  if (data.compare(0, 3, "ply") != 0) fail(file, 1, "not a PLY file (missing 'ply' magic)");
  if (h.body == std::string_view::npos) fail(file, 0, "header: missing 'end_header'");
  const auto header = tokenize(std::string_view(data.data(), h.body), 0);
  for (std::size_t i = 1; i < header.size(); ++i) {
    const auto& l = header[i];
    const auto& t = l.tok;
    if (t[0] == "format") {
      if (t.size() < 2) fail(file, l.number, "format: missing");
      if (t[1] == "ascii") h.format = PlyFormat::ascii;
      else if (t[1] == "binary_little_endian") h.format = PlyFormat::le;
      else if (t[1] == "binary_big_endian") h.format = PlyFormat::be;
      else fail(file, l.number, "format: unknown '" + std::string(t[1]) + "'");
    } else if (t[0] == "element") {
      if (t.size() != 3) fail(file, l.number, "element: expected 'element <name> <count>'");
      PlyElement e;
      e.name = std::string(t[1]);
      e.count = to_int(t[2], file, l.number, "element " + e.name + " count", 0, kMaxCount);
      e.line = l.number;
      h.elements.push_back(std::move(e));
    } else if (t[0] == "property") {
      if (h.elements.empty()) fail(file, l.number, "property before any element");
      h.elements.back().props.push_back(read_property(t, l.number, file));
    } else if (t[0] == "comment" || t[0] == "obj_info") {
      const char* b = t[0].data();
      const char* e = b;
      while (e < data.data() + h.body && *e != '\n' && *e != '\r') ++e;
      comments.emplace_back(b, static_cast<std::size_t>(e - b));
    } else if (t[0] != "end_header") {
      fail(file, l.number, "header: unknown keyword '" + std::string(t[0]) + "'");
    }
  }
  if (h.format == PlyFormat::none) fail(file, 0, "header: missing 'format' line");
  h.lines = header.empty() ? 0 : header.back().number;
  return h;
}

// Which element and properties hold the mesh.
struct PlyLayout {
  const PlyElement* ve = nullptr;  // the vertex element
  const PlyElement* fe = nullptr;  // the face element, if any
  int x = -1, y = -1, z = -1, nx = -1, ny = -1, nz = -1;  // properties of ve
  int indices = -1;                                       // the list property of fe
  bool normals = false;
};

PlyLayout layout_of(const PlyHeader& h, const path& file) {
  PlyLayout lay;
  for (const auto& e : h.elements) {
    for (auto [name, at] : {std::pair{"vertex", &lay.ve}, {"face", &lay.fe}})
      if (e.name == name) {
        if (*at) fail(file, e.line, "element " + e.name + " given twice (also line " + std::to_string((*at)->line) + ")");
        *at = &e;
      }
  }
  if (!lay.ve) fail(file, 0, "header: no 'vertex' element");
  for (std::size_t k = 0; k < lay.ve->props.size(); ++k) {
    const auto& p = lay.ve->props[k];
    if (p.list) continue;
    for (auto [name, at] : {std::pair{"x", &lay.x}, {"y", &lay.y}, {"z", &lay.z},
                            {"nx", &lay.nx}, {"ny", &lay.ny}, {"nz", &lay.nz}})
      if (p.name == name) {
        // a second one would be read over the first and written into both
        if (*at >= 0)
          fail(file, p.line, "element vertex: property '" + p.name + "' given twice (also line " +
                                 std::to_string(lay.ve->props[static_cast<std::size_t>(*at)].line) + ")");
        *at = static_cast<int>(k);
      }
  }
  lay.normals = lay.nx >= 0 && lay.ny >= 0 && lay.nz >= 0;
  if (lay.x < 0 || lay.y < 0 || lay.z < 0)
    fail(file, lay.ve->line, "element vertex: needs properties x, y, z");
  if (lay.fe) {
    for (std::size_t k = 0; k < lay.fe->props.size(); ++k) {
      const auto& p = lay.fe->props[k];
      if (!p.list || (p.name != "vertex_indices" && p.name != "vertex_index")) continue;
      if (lay.indices >= 0)
        fail(file, p.line, "element face: a second vertex index list '" + p.name + "' (also line " +
                               std::to_string(lay.fe->props[static_cast<std::size_t>(lay.indices)].line) + ")");
      lay.indices = static_cast<int>(k);
    }
    if (lay.indices < 0) fail(file, lay.fe->line, "element face: needs a list property 'vertex_indices'");
  }
  return lay;
}

// Fails unless the records the header declares fit in what follows it (before anything is
// allocated for them).
void check_counts(const PlyHeader& h, std::size_t remaining, std::size_t ascii_lines,
                  const path& file) {
  if (h.format == PlyFormat::ascii) {
    long long total = 0;
    for (const auto& e : h.elements) total += e.count;
    if (total > static_cast<long long>(ascii_lines))
      fail(file, 0, "header: " + std::to_string(total) + " elements but only " +
                        std::to_string(ascii_lines) + " data lines follow");
    return;
  }
  long double need = 0;
  for (const auto& e : h.elements) {
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

// One record as read: its values (appended to the element's), its scalars by property, and
// for the face element the vertex indices of its list.
struct PlyRecord {
  std::vector<double> scalars;
  std::vector<long long> list;
};

PlyRecord read_ascii_record(const Line& l, int ln, const PlyElement& e, int indices, long long nv,
                            const std::string& field, std::vector<double>& values, const path& file) {
  PlyRecord r{std::vector<double>(e.props.size(), 0.0), {}};
  std::size_t t = 0;
  for (std::size_t k = 0; k < e.props.size(); ++k) {
    const auto& p = e.props[k];
    if (t >= l.tok.size()) fail(file, ln, field + ": too few values");
    if (!p.list) {
      r.scalars[k] = to_double(l.tok[t++], file, ln, field + " " + p.name);
      values.push_back(r.scalars[k]);
      continue;
    }
    const std::string_view count = l.tok[t++];
    const long long n = to_int(count, file, ln, field + " " + p.name + " count", 0,
                               static_cast<long long>(l.tok.size() - t));
    values.push_back(static_cast<double>(n));
    for (long long j = 0; j < n; ++j, ++t) {
      if (static_cast<int>(k) == indices) {
        r.list.push_back(to_int(l.tok[t], file, ln, field + " index", 0, nv - 1));
        values.push_back(static_cast<double>(r.list.back()));
      } else {
        values.push_back(to_double(l.tok[t], file, ln, field + " " + p.name));
      }
    }
  }
  if (indices >= 0 && r.list.size() < 3) fail(file, ln, field + ": fewer than 3 vertices");
  return r;
}

PlyRecord read_binary_record(BinaryCursor& cur, const PlyElement& e, int indices, long long nv,
                             const std::string& field, std::vector<double>& values, const path& file) {
  PlyRecord r{std::vector<double>(e.props.size(), 0.0), {}};
  for (std::size_t k = 0; k < e.props.size(); ++k) {
    const auto& p = e.props[k];
    if (!p.list) {
      r.scalars[k] = cur.read(p.type, field + " " + p.name);
      values.push_back(r.scalars[k]);
      continue;
    }
    const double nd = cur.read(p.count_type, field + " " + p.name + " count");
    values.push_back(nd);
    if (nd < 0) fail(file, 0, field + ": negative list count");
    const auto n = static_cast<std::size_t>(nd);
    if (n > (cur.data.size() - cur.pos) / ply_size(p.type))
      fail(file, 0, field + ": list of " + std::to_string(n) + " exceeds the file size");
    for (std::size_t j = 0; j < n; ++j) {
      const double x = cur.read(p.type, field + " index");
      values.push_back(x);
      if (static_cast<int>(k) == indices) {
        if (!(x >= 0 && x < static_cast<double>(nv)) || x != std::floor(x))
          fail(file, 0, field + ": index " + fmt(x) + " out of range [0, " +
                            std::to_string(nv) + ")");
        r.list.push_back(static_cast<long long>(x));
      }
    }
  }
  if (indices >= 0 && r.list.size() < 3) fail(file, 0, field + ": fewer than 3 vertices");
  return r;
}

// What the records give besides the values kept in the attributes.
struct PlyMesh {
  std::vector<std::array<double, 3>> v, vn;
  std::vector<std::vector<int>> polygons;
};

// Reads every record of every element: all values into a.values, the mesh into the result.
PlyMesh read_records(std::string_view data, const PlyHeader& h, const PlyLayout& lay,
                     const path& file, PlyAttributes& a) {
  const bool ascii = h.format == PlyFormat::ascii;
  const std::vector<Line> lines = ascii ? tokenize(data.substr(h.body), 0) : std::vector<Line>{};
  check_counts(h, data.size() - h.body, lines.size(), file);
  const long long nv = lay.ve->count;
  PlyMesh out;
  out.v.resize(static_cast<std::size_t>(nv));
  out.vn.resize(lay.normals ? static_cast<std::size_t>(nv) : 0);
  a.values.resize(h.elements.size());
  BinaryCursor cur{data, h.body, h.format == PlyFormat::be ? std::endian::native == std::endian::little
                                                          : std::endian::native == std::endian::big,
                   file};
  std::size_t line_at = 0;
  for (std::size_t ei = 0; ei < h.elements.size(); ++ei) {
    const auto& e = h.elements[ei];
    const bool is_v = &e == lay.ve, is_f = &e == lay.fe;
    const int indices = is_f ? lay.indices : -1;
    for (long long i = 0; i < e.count; ++i) {
      const std::string field = e.name + " " + std::to_string(i);
      const int ln = ascii ? h.lines + lines[line_at].number : 0;
      const PlyRecord r = ascii ? read_ascii_record(lines[line_at++], ln, e, indices, nv, field, a.values[ei], file)
                                : read_binary_record(cur, e, indices, nv, field, a.values[ei], file);
      const auto at = static_cast<std::size_t>(i);
      auto scalar = [&](int k) { return r.scalars[static_cast<std::size_t>(k)]; };
      if (is_v) {
        out.v[at] = {scalar(lay.x), scalar(lay.y), scalar(lay.z)};
        for (double c : out.v[at]) check_coordinate(c, file, ln, field);
        if (lay.normals) out.vn[at] = {scalar(lay.nx), scalar(lay.ny), scalar(lay.nz)};
      }
      if (is_f) {
        out.polygons.emplace_back(r.list.begin(), r.list.end());
        a.face_sizes.push_back(static_cast<int>(r.list.size()));
      }
    }
  }
  return out;
}

}  // namespace

SurfaceMesh parse_ply(std::string_view bytes, const path& file) {
  const std::string_view data = skip_bom(bytes);
  auto attr = std::make_shared<SurfaceAttributes>();
  attr->format = ".ply";
  PlyAttributes& a = attr->ply;
  const PlyHeader h = read_header(data, file, a.comments);
  const PlyLayout lay = layout_of(h, file);
  PlyMesh read = read_records(data, h, lay, file, a);
  SurfaceMesh m;
  m.polygons = std::move(read.polygons);
  set_vertices(m, read.v);
  fan(m);
  const long long nv = lay.ve->count;
  if (lay.normals) {
    m.N.resize(nv, 3);
    std::vector<char> have(static_cast<std::size_t>(nv), 1);
    for (Eigen::Index i = 0; i < nv; ++i) {
      const auto& n = read.vn[static_cast<std::size_t>(i)];
      m.N.row(i) << n[0], n[1], n[2];
      if (!m.N.row(i).allFinite()) have[static_cast<std::size_t>(i)] = 0, m.N.row(i).setZero();
    }
    complete_normals(m, std::move(have));
  }
  attr->binary = h.format != PlyFormat::ascii;
  attr->big_endian = h.format == PlyFormat::be;
  attr->vertices = nv;
  a.elements = h.elements;
  m.attributes = std::move(attr);
  return m;
}

// --------------------------------------------------------------------------------- writing
namespace {

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

int find_prop(const PlyElement& e, const char* name, bool list) {
  for (std::size_t k = 0; k < e.props.size(); ++k)
    if (e.props[k].name == name && e.props[k].list == list) return static_cast<int>(k);
  return -1;
}

// Where the mesh goes among the elements and properties of a file's attributes.
struct PlyTarget {
  int ve = -1, fe = -1;                                   // vertex and face element
  int pos[3] = {-1, -1, -1}, nrm[3] = {-1, -1, -1}, indices = -1;  // their properties
  bool add_normals = false;  // normals to write that the file had not: nx, ny, nz added
};

PlyTarget target_of(const PlyAttributes& a, bool has_n) {
  PlyTarget t;
  for (std::size_t i = 0; i < a.elements.size(); ++i) {
    if (a.elements[i].name == "vertex" && t.ve < 0) t.ve = static_cast<int>(i);
    if (a.elements[i].name == "face" && t.fe < 0) t.fe = static_cast<int>(i);
  }
  if (t.ve >= 0) {
    const auto& e = a.elements[static_cast<std::size_t>(t.ve)];
    const char* pn[3] = {"x", "y", "z"};
    const char* nn[3] = {"nx", "ny", "nz"};
    for (int c = 0; c < 3; ++c) {
      t.pos[c] = find_prop(e, pn[c], false);
      t.nrm[c] = find_prop(e, nn[c], false);
    }
    t.add_normals = has_n && (t.nrm[0] < 0 || t.nrm[1] < 0 || t.nrm[2] < 0);
    if (t.add_normals) t.nrm[0] = t.nrm[1] = t.nrm[2] = -1;
  }
  if (t.fe >= 0) {
    const auto& e = a.elements[static_cast<std::size_t>(t.fe)];
    t.indices = find_prop(e, "vertex_indices", true);
    if (t.indices < 0) t.indices = find_prop(e, "vertex_index", true);
  }
  return t;
}

bool is_integer(PlyType t) { return t != PlyType::f32 && t != PlyType::f64; }

// The file's elements as written: positions (and the normals written) of an integer type become
// float64, in ASCII and binary alike. Deformed positions are real numbers: rounding them (or
// clamping them to 0..255 for uchar) would move the model silently, and real numbers under an
// integer header would make an invalid file.
std::vector<PlyElement> written_elements(const PlyAttributes& a, const PlyTarget& t, bool has_n) {
  std::vector<PlyElement> out = a.elements;
  if (t.ve < 0) return out;
  auto& props = out[static_cast<std::size_t>(t.ve)].props;
  for (int c = 0; c < 3; ++c)
    for (int k : {t.pos[c], has_n ? t.nrm[c] : -1})
      if (k >= 0 && is_integer(props[static_cast<std::size_t>(k)].type)) {
        props[static_cast<std::size_t>(k)].type = PlyType::f64;
        props[static_cast<std::size_t>(k)].type_name = "double";
      }
  return out;
}

std::string kept_header(const PlyAttributes& a, const std::vector<PlyElement>& elements,
                        const PlyTarget& t, bool binary, bool big) {
  std::string h = std::string("ply\nformat ") +
                  (binary ? (big ? "binary_big_endian" : "binary_little_endian") : "ascii") +
                  " 1.0\n";
  for (const auto& c : a.comments) h += c + "\n";
  for (std::size_t i = 0; i < elements.size(); ++i) {
    const auto& e = elements[i];
    h += "element " + e.name + " " + std::to_string(e.count) + "\n";
    for (const auto& p : e.props)
      h += p.list ? "property list " + p.count_type_name + " " + p.type_name + " " + p.name + "\n"
                  : "property " + p.type_name + " " + p.name + "\n";
    if (static_cast<int>(i) == t.ve && t.add_normals)
      h += "property double nx\nproperty double ny\nproperty double nz\n";
  }
  return h + "end_header\n";
}

// The file's elements and values (attributes), with the positions, normals and faces of `out`
// in place of the file's.
void write_ply_kept(std::FILE* f, const SurfaceOutput& out) {
  const PlyAttributes& a = out.attributes->ply;
  const bool has_n = out.has_normals(), binary = out.binary, big = out.big_endian;
  const PlyTarget tg = target_of(a, has_n);
  const std::vector<PlyElement> elements = written_elements(a, tg, has_n);
  put(f, kept_header(a, elements, tg, binary, big), out.file);
  std::string buf;
  for (std::size_t ei = 0; ei < elements.size(); ++ei) {
    const auto& e = elements[ei];
    const auto& vals = a.values[ei];
    const bool is_v = static_cast<int>(ei) == tg.ve, is_f = static_cast<int>(ei) == tg.fe;
    std::size_t at = 0;
    for (long long r = 0; r < e.count; ++r) {
      bool first = true;
      auto emit = [&](double x, PlyType t, bool exact) {
        if (binary) {
          append_ply_binary(buf, x, t, big);
          return;
        }
        if (!first) buf += ' ';
        first = false;
        if (exact) buf += fmt(x);
        else append_ply_ascii(buf, x, t);
      };
      for (std::size_t k = 0; k < e.props.size(); ++k) {
        const auto& p = e.props[k];
        const int ki = static_cast<int>(k);
        if (!p.list) {
          double x = vals[at++];
          bool exact = false;
          if (is_v)
            for (int c = 0; c < 3; ++c) {
              if (ki == tg.pos[c]) x = out.V(r, c), exact = true;
              if (ki == tg.nrm[c] && has_n) x = out.N(r, c), exact = true;
            }
          emit(x, p.type, exact);
          continue;
        }
        const auto n = static_cast<std::size_t>(vals[at++]);
        emit(static_cast<double>(n), p.count_type, false);
        for (std::size_t j = 0; j < n; ++j) {
          double x = vals[at++];
          if (is_f && ki == tg.indices) x = out.faces[static_cast<std::size_t>(r)][j];
          emit(x, p.type, false);
        }
      }
      if (is_v && tg.add_normals)
        for (int c = 0; c < 3; ++c) emit(out.N(r, c), PlyType::f64, true);
      if (!binary) buf += '\n';
      put_buffered(buf, f, out.file);
    }
  }
  put(f, buf.data(), buf.size(), out.file);
}

// A PLY file of the mesh alone: float64 coordinates and normals, int32 indices (uchar list
// counts while every face has at most 255 corners).
void write_ply_fresh(std::FILE* f, const SurfaceOutput& out) {
  const auto& V = out.V;
  const auto& N = out.N;
  const bool has_n = out.has_normals();
  std::size_t max_k = 0;
  for (const auto& p : out.faces) max_k = std::max(max_k, p.size());
  const bool wide = max_k > 255;
  put(f,
      std::string("ply\nformat ") + (out.binary ? "binary_little_endian" : "ascii") +
          " 1.0\ncomment written by mbi\nelement vertex " + std::to_string(V.rows()) +
          "\nproperty double x\nproperty double y\nproperty double z\n" +
          (has_n ? "property double nx\nproperty double ny\nproperty double nz\n" : "") +
          "element face " + std::to_string(out.faces.size()) + "\nproperty list " +
          (wide ? "int" : "uchar") + " int vertex_indices\nend_header\n",
      out.file);
  if (!out.binary) {
    put_vertex_lines(f, out, has_n);
    put_counted_faces(f, out);
    return;
  }
  std::string buf;
  for (Eigen::Index i = 0; i < V.rows(); ++i) {
    for (int c = 0; c < 3; ++c) append_bytes<double>(buf, V(i, c), false);
    if (has_n)
      for (int c = 0; c < 3; ++c) append_bytes<double>(buf, N(i, c), false);
    put_buffered(buf, f, out.file);
  }
  for (const auto& p : out.faces) {
    if (wide) append_bytes<std::int32_t>(buf, static_cast<std::int32_t>(p.size()), false);
    else append_bytes<std::uint8_t>(buf, static_cast<std::uint8_t>(p.size()), false);
    for (int x : p) append_bytes<std::int32_t>(buf, x, false);
    put_buffered(buf, f, out.file);
  }
  put(f, buf.data(), buf.size(), out.file);
}

}  // namespace

bool ply_attributes_fit(const SurfaceAttributes& a, const std::vector<std::vector<int>>& faces) {
  if (a.ply.face_sizes.size() != faces.size()) return false;
  for (std::size_t i = 0; i < faces.size(); ++i)
    if (static_cast<std::size_t>(a.ply.face_sizes[i]) != faces[i].size()) return false;
  return true;
}

void write_ply(std::FILE* f, const SurfaceOutput& out) {
  if (out.attributes) write_ply_kept(f, out);
  else write_ply_fresh(f, out);
}

}  // namespace mbi::io::detail
