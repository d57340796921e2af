// Control meshes: TetGen .node/.ele (and .face output), Gmsh .msh (2.2, 4.0, 4.1; ASCII and
// binary), legacy VTK output.
#include "io_common.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <bit>
#include <array>
#include <cctype>
#include <cmath>
#include <cstring>
#include <map>
#include <unordered_map>

namespace mbi::io {
namespace {

using detail::fail;
using detail::Line;
using std::filesystem::path;

constexpr long long kMax = kMaxCount;

path with_ext(const path& base, const char* ext) {
  path p = base;
  const std::string e = detail::extension(base);
  if (e == ".node" || e == ".ele" || e == ".face") p.replace_extension();
  p += ext;
  return p;
}

void check_remaining(const path& file, const Line& header, long long count, std::size_t left,
                     const std::string& what) {
  if (count > static_cast<long long>(left))
    fail(file, header.number,
         "header: " + std::to_string(count) + " " + what + " but only " + std::to_string(left) +
             " data lines follow");
}

struct NodeFile {
  Eigen::MatrixXd X;
  long long base = 0;
};

NodeFile node_file(std::string_view text, const path& file) {
  const auto lines = detail::tokenize(detail::skip_bom(text));
  if (lines.empty()) fail(file, 0, "empty .node file");
  const Line& h = lines[0];
  if (h.tok.size() < 2) fail(file, h.number, "header: expected '<points> <dim> <attributes> <markers>'");
  const long long n = detail::to_int(h.tok[0], file, h.number, "header point count", 0, kMax);
  const long long d = detail::to_int(h.tok[1], file, h.number, "header dimension", 2, 3);
  const long long na = h.tok.size() > 2 ? detail::to_int(h.tok[2], file, h.number,
                                                         "header attribute count", 0, 1000000)
                                        : 0;
  const long long nm = h.tok.size() > 3
                           ? detail::to_int(h.tok[3], file, h.number, "header marker flag", 0, 1)
                           : 0;
  check_remaining(file, h, n, lines.size() - 1, "points");
  NodeFile out;
  out.X.resize(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(d));
  for (long long i = 0; i < n; ++i) {
    const Line& l = lines[static_cast<std::size_t>(i + 1)];
    const std::string field = "point " + std::to_string(i);
    if (static_cast<long long>(l.tok.size()) < 1 + d + na + nm)
      fail(file, l.number, field + ": expected " + std::to_string(1 + d + na + nm) +
                               " values, found " + std::to_string(l.tok.size()));
    const long long num = detail::to_int(l.tok[0], file, l.number, field + " number", 0, kMax);
    if (i == 0) {
      if (num != 0 && num != 1)
        fail(file, l.number, field + ": first point number must be 0 or 1, found " +
                                 std::to_string(num));
      out.base = num;
    } else if (num != out.base + i) {
      fail(file, l.number, field + ": number " + std::to_string(num) + ", expected " +
                               std::to_string(out.base + i) + " (consecutive numbering)");
    }
    for (long long c = 0; c < d; ++c)
      out.X(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(c)) =
          detail::to_coordinate(l.tok[static_cast<std::size_t>(1 + c)], file, l.number,
                                field + " coordinate " + std::to_string(c));
  }
  return out;
}

// Determinant of the element's edge vectors divided by its longest edge (scale-free: no
// overflow or underflow for coordinates anywhere in the readers' range); 0 for a zero-length edge
// set.
double relative_measure(const Eigen::MatrixXd& U, const Eigen::MatrixXi& T, Eigen::Index e) {
  const int d = static_cast<int>(U.cols());
  Eigen::MatrixXd E(d, d);
  for (int k = 0; k < d; ++k) E.col(k) = (U.row(T(e, k + 1)) - U.row(T(e, 0))).transpose();
  const double h = E.cwiseAbs().maxCoeff();
  if (!(h > 0) || !std::isfinite(h)) return 0.0;
  E /= h;
  return E.determinant();
}

/// Rejects repeated vertices and zero-volume elements (relative to the longest edge).
void check_elements(const path& file, const std::vector<int>& line_of, const Eigen::MatrixXd& U,
                    const Eigen::MatrixXi& T) {
  const int d = static_cast<int>(U.cols());
  for (Eigen::Index e = 0; e < T.rows(); ++e) {
    const int ln = line_of.empty() ? 0 : line_of[static_cast<std::size_t>(e)];
    for (int a = 0; a <= d; ++a)
      for (int b = a + 1; b <= d; ++b)
        if (T(e, a) == T(e, b))
          fail(file, ln, "element " + std::to_string(e) + ": vertex " +
                             std::to_string(T(e, a)) + " repeated");
    if (!(std::abs(relative_measure(U, T, e)) > 1e-12))
      fail(file, ln, "element " + std::to_string(e) + ": degenerate (zero " +
                         (d == 3 ? "volume" : "area") + ")");
  }
}

}  // namespace

Eigen::MatrixXd read_node(const path& file) { return node_file(detail::slurp(file), file).X; }

Eigen::MatrixXd parse_node(std::string_view data, const path& file) {
  return node_file(data, file).X;
}

ControlMesh read_tetgen(const path& p) {
  const std::string node = detail::slurp(with_ext(p, ".node"));
  return parse_tetgen(node, detail::slurp(with_ext(p, ".ele")), p);
}

ControlMesh parse_tetgen(std::string_view node_text, std::string_view ele_text, const path& p) {
  const path node = with_ext(p, ".node");
  const path ele = with_ext(p, ".ele");
  NodeFile nf = node_file(node_text, node);
  ControlMesh m;
  m.U = std::move(nf.X);
  const long long n = m.U.rows();
  const int d = static_cast<int>(m.U.cols());
  const auto lines = detail::tokenize(detail::skip_bom(ele_text));
  if (lines.empty()) fail(ele, 0, "empty .ele file");
  const Line& h = lines[0];
  if (h.tok.size() < 2) fail(ele, h.number, "header: expected '<elements> <nodes per element> <attributes>'");
  const long long m_count = detail::to_int(h.tok[0], ele, h.number, "header element count", 0, kMax);
  const long long k = detail::to_int(h.tok[1], ele, h.number, "header nodes per element", d + 1,
                                     d == 3 ? 10 : 6);
  if (k != d + 1 && k != (d == 3 ? 10 : 6))
    fail(ele, h.number, "header nodes per element: " + std::to_string(k) + " (expected " +
                            std::to_string(d + 1) + " or " + (d == 3 ? "10" : "6") + ")");
  check_remaining(ele, h, m_count, lines.size() - 1, "elements");
  if (k != d + 1 && m_count > 0)
    m.notes.push_back(ele.string() + ": " + std::to_string(m_count) + " " + std::to_string(k) + "-node " +
                      (d == 3 ? "tetrahedra" : "triangles") + " used by their corners; their other nodes stay in the numbering, unconnected");
  m.T.resize(static_cast<Eigen::Index>(m_count), d + 1);
  std::vector<int> line_of(static_cast<std::size_t>(m_count));
  for (long long e = 0; e < m_count; ++e) {
    const Line& l = lines[static_cast<std::size_t>(e + 1)];
    const std::string field = "element " + std::to_string(e);
    if (static_cast<long long>(l.tok.size()) < 1 + k)
      fail(ele, l.number, field + ": expected " + std::to_string(k) + " node numbers");
    detail::to_int(l.tok[0], ele, l.number, field + " number", 0, kMax);
    for (int c = 0; c <= d; ++c)
      m.T(static_cast<Eigen::Index>(e), c) = static_cast<int>(
          detail::to_int(l.tok[static_cast<std::size_t>(1 + c)], ele, l.number, field + " node",
                         nf.base, nf.base + n - 1) - nf.base);
    line_of[static_cast<std::size_t>(e)] = l.number;
  }
  check_elements(ele, line_of, m.U, m.T);

  return m;
}

void write_node(const path& file, const Eigen::Ref<const Eigen::MatrixXd>& X) {
  if (X.cols() != 2 && X.cols() != 3)
    fail(file, 0, "positions must be n x 2 or n x 3, got n x " + std::to_string(X.cols()));
  detail::check_finite(X, file, "point");
  detail::write_atomic(file, [&](std::FILE* f) {
    detail::put(f, std::to_string(X.rows()) + " " + std::to_string(X.cols()) + " 0 0\n", file);
    for (Eigen::Index i = 0; i < X.rows(); ++i) {
      std::string s = std::to_string(i);
      for (Eigen::Index c = 0; c < X.cols(); ++c) s += " " + detail::fmt(X(i, c));
      detail::put(f, s + "\n", file);
    }
  });
}

void write_tetgen(const path& base, const Eigen::Ref<const Eigen::MatrixXd>& U,
                  const Eigen::Ref<const Eigen::MatrixXi>& T,
                  const Eigen::Ref<const Eigen::MatrixXi>& faces) {
  const path node = with_ext(base, ".node"), ele = with_ext(base, ".ele");
  const long long d = U.cols();
  if (T.cols() != d + 1)
    fail(ele, 0, "elements must be m x " + std::to_string(d + 1) + " for " + std::to_string(d) +
                     "D positions, got m x " + std::to_string(T.cols()));
  detail::check_indices(T, U.rows(), ele, "element");
  if (faces.rows() > 0) {
    if (d != 3 || faces.cols() != 3) fail(with_ext(base, ".face"), 0, "faces must be b x 3 (3D)");
    detail::check_indices(faces, U.rows(), with_ext(base, ".face"), "face");
  }
  write_node(node, U);
  detail::write_atomic(ele, [&](std::FILE* f) {
    detail::put(f, std::to_string(T.rows()) + " " + std::to_string(T.cols()) + " 0\n", ele);
    for (Eigen::Index e = 0; e < T.rows(); ++e) {
      std::string s = std::to_string(e);
      for (Eigen::Index c = 0; c < T.cols(); ++c) s += " " + std::to_string(T(e, c));
      detail::put(f, s + "\n", ele);
    }
  });
  if (faces.rows() > 0) {
    const path fp = with_ext(base, ".face");
    detail::write_atomic(fp, [&](std::FILE* f) {
      detail::put(f, std::to_string(faces.rows()) + " 0\n", fp);
      for (Eigen::Index i = 0; i < faces.rows(); ++i)
        detail::put(f, std::to_string(i) + " " + std::to_string(faces(i, 0)) + " " +
                           std::to_string(faces(i, 1)) + " " + std::to_string(faces(i, 2)) + "\n",
                    fp);
    });
  }
}

// --------------------------------------------------------------------------------------- Gmsh
namespace {

// Reads numbers from a .msh file, ASCII (blank-separated words) or binary (the file's
// endianness, found from the int 1 after the format line). Messages name the line (ASCII) or
// the byte offset (binary).
struct MshCursor {
  std::string_view d;
  const path& file;
  std::size_t pos = 0;
  std::size_t last = 0;  // where the last word / value began
  bool binary = false, swap = false;
  detail::LineCounter lines{d};

  int line_at(std::size_t at) {
    return binary && at > 0 ? 0 : lines.line_of(at);
  }
  [[noreturn]] void fail_here(const std::string& what) {
    if (binary) fail(file, 0, what + " (byte " + std::to_string(last) + ")");
    fail(file, line_at(last), what);
  }
  bool at_end() {
    while (pos < d.size() && std::isspace(static_cast<unsigned char>(d[pos]))) ++pos;
    return pos >= d.size();
  }
  std::string_view word(const char* what) {
    if (at_end()) {
      last = d.size();
      fail(file, 0, std::string("file truncated: expected ") + what);
    }
    last = pos;
    while (pos < d.size() && !std::isspace(static_cast<unsigned char>(d[pos]))) ++pos;
    return d.substr(last, pos - last);
  }
  // After a section keyword of a binary file: exactly one newline, then binary data.
  void end_of_line() {
    while (pos < d.size() && d[pos] != '\n') ++pos;
    if (pos < d.size()) ++pos;
  }
  template <typename T>
  T get(const std::string& what) {
    last = pos;
    if (d.size() - pos < sizeof(T)) fail(file, 0, what + ": file truncated (byte " + std::to_string(pos) + ")");
    unsigned char b[sizeof(T)];
    std::memcpy(b, d.data() + pos, sizeof(T));
    pos += sizeof(T);
    if (swap) std::reverse(b, b + sizeof(T));
    T x;
    std::memcpy(&x, b, sizeof(T));
    return x;
  }
  long long integer(const std::string& what, long long lo, long long hi) {
    const std::string_view w = word(what.c_str());
    return detail::to_int(w, file, line_at(last), what, lo, hi);
  }
  double real(const std::string& what) {
    if (binary) {
      const double x = get<double>(what);
      if (!std::isfinite(x)) fail_here(what + ": non-finite value");
      return x;
    }
    const std::string_view w = word(what.c_str());
    return detail::to_double(w, file, line_at(last), what);
  }
  // An int (binary: int32) / a size (binary: `size_bytes` unsigned) / in ASCII a word.
  long long i32(const std::string& what, long long lo, long long hi) {
    if (!binary) return integer(what, lo, hi);
    const long long x = get<std::int32_t>(what);
    if (x < lo || x > hi) fail_here(what + ": " + std::to_string(x) + " out of range [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    return x;
  }
  long long size(const std::string& what, long long lo, long long hi, int size_bytes) {
    if (!binary) return integer(what, lo, hi);
    const unsigned long long x = size_bytes == 8 ? get<std::uint64_t>(what) : get<std::uint32_t>(what);
    if (x > static_cast<unsigned long long>(hi) || static_cast<long long>(x) < lo)
      fail_here(what + ": " + std::to_string(x) + " out of range [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    return static_cast<long long>(x);
  }
  // Fails unless `count` items of at least `bytes` each can follow.
  void room(long long count, std::size_t bytes, const std::string& what) {
    const long double need = static_cast<long double>(count) * static_cast<long double>(bytes);
    if (need > static_cast<long double>(d.size() - pos))
      fail_here("header says " + std::to_string(count) + " " + what + " but only " + std::to_string(d.size() - pos) + " bytes follow");
  }
  void expect(const char* keyword, const char* hint) {
    const std::string_view w = word(keyword);
    if (w != keyword) fail_here(std::string("expected ") + keyword + ", found '" + std::string(w.substr(0, 40)) + "'" + hint);
  }
};

// Gmsh element types: number of nodes, and for triangles / tetrahedra of any order, which.
int msh_nodes(int type) {
  switch (type) {
    case 1: return 2;   case 2: return 3;   case 3: return 4;   case 4: return 4;
    case 5: return 8;   case 6: return 6;   case 7: return 5;   case 8: return 3;
    case 9: return 6;   case 10: return 9;  case 11: return 10; case 12: return 27;
    case 13: return 18; case 14: return 14; case 15: return 1;  case 16: return 8;
    case 17: return 20; case 18: return 15; case 19: return 13; case 20: return 9;
    case 21: return 10; case 22: return 12; case 23: return 15; case 24: return 15;
    case 25: return 21; case 26: return 4;  case 27: return 5;  case 28: return 6;
    case 29: return 20; case 30: return 35; case 31: return 56;
    default: return -1;
  }
}
bool msh_tet(int type) { return type == 4 || type == 11 || (type >= 29 && type <= 31); }
bool msh_tri(int type) { return type == 2 || type == 9 || (type >= 20 && type <= 25); }
std::string msh_type_name(int type) {
  const char* n = "elements";
  switch (type) {
    case 1: case 8: case 26: case 27: case 28: n = "lines"; break;
    case 15: n = "points"; break;
    case 3: case 10: case 16: n = "quadrangles"; break;
    case 5: case 12: case 17: n = "hexahedra"; break;
    case 6: case 13: case 18: n = "prisms"; break;
    case 7: case 14: case 19: n = "pyramids"; break;
    default: if (msh_tet(type)) n = "tetrahedra"; else if (msh_tri(type)) n = "triangles";
  }
  return std::string(n) + " (type " + std::to_string(type) + ")";
}

struct MshData {
  std::vector<std::array<double, 3>> xyz;  // every node, file order
  struct Elem {
    int type;
    std::array<int, 4> corners;  // node indices (first 3 or 4 used)
    int line;
  };
  std::vector<Elem> tets, tris;
  std::map<int, long long> count_of_type;
};

MshData parse_msh(std::string_view bytes, const path& file) {
  const std::string_view data = detail::skip_bom(bytes);
  MshCursor c{data, file};
  MshData out;
  std::string version;
  int size_bytes = 8;
  std::unordered_map<long long, int> index_of;
  auto add_node = [&](long long tag, const std::array<double, 3>& p) {
    if (!index_of.emplace(tag, static_cast<int>(out.xyz.size())).second)
      c.fail_here("node " + std::to_string(tag) + ": duplicate node tag");
    out.xyz.push_back(p);
  };
  auto node_xyz = [&](const std::string& field, int params) {
    std::array<double, 3> p{};
    for (int k = 0; k < 3; ++k) {
      const double x = c.real(field + " coordinate " + std::to_string(k));
      if (!(std::abs(x) <= kMaxCoordinate)) c.fail_here(field + ": coordinate larger in magnitude than 1e300, the largest accepted");
      p[static_cast<std::size_t>(k)] = x;
    }
    for (int k = 0; k < params; ++k) c.real(field + " parametric coordinate");  // -save_parametric
    return p;
  };
  auto add_elem = [&](int type, const std::vector<long long>& tags, long long tag, int line) {
    ++out.count_of_type[type];
    const bool tet = msh_tet(type), tri = msh_tri(type);
    if (!tet && !tri) return;
    MshData::Elem e{type, {-1, -1, -1, -1}, line};
    for (int k = 0; k < (tet ? 4 : 3); ++k) {
      const auto it = index_of.find(tags[static_cast<std::size_t>(k)]);
      if (it == index_of.end())
        fail(file, line, "element " + std::to_string(tag) + ": unknown node tag " + std::to_string(tags[static_cast<std::size_t>(k)]));
      e.corners[static_cast<std::size_t>(k)] = it->second;
    }
    (tet ? out.tets : out.tris).push_back(e);
  };
  const long long kTag = 1LL << 62;
  while (!c.at_end()) {
    const std::string_view key = c.word("a section");
    if (key == "$MeshFormat") {
      version = std::string(c.word("format version"));
      const long long type = c.integer("format file-type", 0, 1);
      size_bytes = static_cast<int>(c.integer("format data-size", 4, 8));
      if (version != "2.2" && version != "2" && version != "2.0" && version != "2.1" &&
          version != "4" && version != "4.0" && version != "4.1")
        c.fail_here("format: version " + version + " not supported (2.2, 4.0 and 4.1 are)");
      c.binary = type == 1;
      if (c.binary) {
        c.end_of_line();
        const std::int32_t one = c.get<std::int32_t>("binary endianness marker");
        if (one != 1) {
          c.swap = true;
          if (__builtin_bswap32(static_cast<std::uint32_t>(one)) != 1)
            c.fail_here("binary: expected the int 1 after the format line");
        }
      }
      c.expect("$EndMeshFormat", "");
    } else if (key == "$Nodes") {
      if (version.empty()) c.fail_here("$Nodes before $MeshFormat");
      if (version[0] == '2') {
        const long long n = c.integer("node count", 0, kMax);
        c.room(n, c.binary ? 28 : 8, "nodes");
        if (c.binary) c.end_of_line();
        for (long long k = 0; k < n; ++k) {
          const long long tag = c.i32("node tag", 0, kMax);
          add_node(tag, node_xyz("node " + std::to_string(tag), 0));
        }
      } else {
        const bool v41 = version == "4.1";
        if (c.binary) c.end_of_line();
        const long long blocks = c.size("node block count", 0, kMax, size_bytes);
        const long long total = c.size("node count", 0, kMax, size_bytes);
        if (v41) {
          c.size("min node tag", 0, kTag, size_bytes);
          c.size("max node tag", 0, kTag, size_bytes);
        }
        c.room(total, c.binary ? 32 : 8, "nodes");
        for (long long b = 0; b < blocks; ++b) {
          long long dim = 0, param = 0, nb = 0;
          if (v41) {
            dim = c.i32("node block entity dimension", 0, 3);
            c.i32("node block entity tag", -kMax, kMax);
            param = c.i32("node block parametric flag", 0, 1);
            nb = c.size("nodes in block", 0, total, size_bytes);
          } else {
            c.i32("node block entity tag", -kMax, kMax);
            dim = c.i32("node block entity dimension", 0, 3);
            param = c.i32("node block parametric flag", 0, 1);
            nb = c.size("nodes in block", 0, total, size_bytes);
          }
          const int params = param ? static_cast<int>(dim) : 0;
          if (v41) {
            std::vector<long long> tags(static_cast<std::size_t>(nb));
            for (auto& t : tags) t = c.size("node tag", 1, kTag, size_bytes);
            for (long long t : tags) add_node(t, node_xyz("node " + std::to_string(t), params));
          } else {
            for (long long k = 0; k < nb; ++k) {
              const long long tag = c.i32("node tag", 1, kMax);
              add_node(tag, node_xyz("node " + std::to_string(tag), params));
            }
          }
        }
      }
      c.expect("$EndNodes", " (node count wrong?)");
    } else if (key == "$Elements") {
      if (version.empty()) c.fail_here("$Elements before $MeshFormat");
      std::vector<long long> tags;
      if (version[0] == '2') {
        const long long m = c.integer("element count", 0, kMax);
        c.room(m, c.binary ? 12 : 8, "elements");
        if (c.binary) {
          c.end_of_line();
          long long done = 0;
          while (done < m) {
            const int type = static_cast<int>(c.i32("element type", 1, 1000));
            const long long follow = c.i32("elements following", 1, m - done);
            const long long ntags = c.i32("element tag count", 0, 1000);
            const int k = msh_nodes(type);
            if (k < 0) c.fail_here("element type " + std::to_string(type) + " unknown to this reader");
            for (long long e = 0; e < follow; ++e) {
              const long long tag = c.i32("element tag", 0, kMax);
              for (long long t = 0; t < ntags; ++t) c.i32("element tag", -kMax, kMax);
              tags.assign(static_cast<std::size_t>(k), 0);
              for (auto& t : tags) t = c.i32("element node", 0, kMax);
              add_elem(type, tags, tag, 0);
            }
            done += follow;
          }
        } else {
          for (long long e = 0; e < m; ++e) {
            const long long tag = c.integer("element tag", 0, kTag);
            const int line = c.line_at(c.last);
            const int type = static_cast<int>(c.integer("element type", 1, 1000));
            const long long ntags = c.integer("element tag count", 0, 1000);
            for (long long t = 0; t < ntags; ++t) c.integer("element tag", -kTag, kTag);
            const int k = msh_nodes(type);
            if (k < 0) fail(file, line, "element " + std::to_string(tag) + ": type " + std::to_string(type) + " unknown to this reader");
            tags.assign(static_cast<std::size_t>(k), 0);
            for (auto& t : tags) t = c.integer("element " + std::to_string(tag) + " node tag", 0, kTag);
            if (c.line_at(c.last) != line) fail(file, line, "element " + std::to_string(tag) + ": expected " + std::to_string(k) + " nodes");
            add_elem(type, tags, tag, line);
          }
        }
      } else {
        const bool v41 = version == "4.1";
        if (c.binary) c.end_of_line();
        const long long blocks = c.size("element block count", 0, kMax, size_bytes);
        const long long total = c.size("element count", 0, kMax, size_bytes);
        if (v41) {
          c.size("min element tag", 0, kTag, size_bytes);
          c.size("max element tag", 0, kTag, size_bytes);
        }
        c.room(total, c.binary ? 8 : 4, "elements");
        for (long long b = 0; b < blocks; ++b) {
          int type = 0;
          if (v41) {
            c.i32("element block entity dimension", 0, 3);
            c.i32("element block entity tag", -kMax, kMax);
          } else {
            c.i32("element block entity tag", -kMax, kMax);
            c.i32("element block entity dimension", 0, 3);
          }
          type = static_cast<int>(c.i32("element type", 1, 1000));
          const long long nb = c.size("elements in block", 0, total, size_bytes);
          const int k = msh_nodes(type);
          if (k < 0) c.fail_here("element type " + std::to_string(type) + " unknown to this reader");
          for (long long e = 0; e < nb; ++e) {
            const long long tag = v41 ? c.size("element tag", 0, kTag, size_bytes) : c.i32("element tag", 0, kMax);
            const int line = c.line_at(c.last);
            tags.assign(static_cast<std::size_t>(k), 0);
            for (auto& t : tags)
              t = v41 ? c.size("element " + std::to_string(tag) + " node tag", 0, kTag, size_bytes)
                      : c.i32("element " + std::to_string(tag) + " node tag", 0, kMax);
            add_elem(type, tags, tag, line);
          }
        }
      }
      c.expect("$EndElements", " (element count wrong?)");
    } else if (key.size() > 1 && key[0] == '$' && key.substr(0, 4) != "$End") {
      // Any other section ($PhysicalNames, $Entities, $NodeData, ...): skipped to its $End line.
      const std::string end = "\n$End" + std::string(key.substr(1));
      const std::size_t at = data.find(end, c.pos);
      if (at == std::string_view::npos) c.fail_here("section " + std::string(key) + " not closed");
      c.pos = at + end.size();
    } else {
      c.fail_here("unexpected '" + std::string(key.substr(0, 40)) + "' outside a section");
    }
  }
  if (version.empty()) fail(file, 0, "no $MeshFormat section (not a Gmsh file?)");
  return out;
}

std::string found_list(const MshData& m) {
  std::string s;
  for (const auto& [type, n] : m.count_of_type)
    s += (s.empty() ? "" : ", ") + std::to_string(n) + " " + msh_type_name(type);
  return s.empty() ? "no elements" : s;
}

}  // namespace

ControlMesh read_gmsh(const path& file) { return parse_gmsh(detail::slurp(file), file); }

ControlMesh parse_gmsh(std::string_view data, const path& file) {
  const MshData msh = parse_msh(data, file);
  const bool three_d = !msh.tets.empty();
  if (!three_d && msh.tris.empty())
    fail(file, 0, "no tetrahedra or triangles (found " + found_list(msh) + ")");
  const int d = three_d ? 3 : 2;
  const auto& elems = three_d ? msh.tets : msh.tris;
  ControlMesh m;
  const auto n = static_cast<Eigen::Index>(msh.xyz.size());
  m.U.resize(n, d);
  for (Eigen::Index v = 0; v < n; ++v)
    for (int c = 0; c < d; ++c) m.U(v, c) = msh.xyz[static_cast<std::size_t>(v)][static_cast<std::size_t>(c)];
  if (!three_d)
    for (Eigen::Index v = 1; v < n; ++v)
      if (msh.xyz[static_cast<std::size_t>(v)][2] != msh.xyz[0][2])
        fail(file, 0, "no tetrahedra, and the " + std::to_string(msh.tris.size()) +
                          " triangles are not in one plane z = const (nodes at z = " +
                          detail::fmt(msh.xyz[0][2]) + " and " + detail::fmt(msh.xyz[static_cast<std::size_t>(v)][2]) +
                          "): a surface mesh of a 3D model? Mesh the volume (gmsh -3) and save it "
                          "(a Physical Volume, or -save_all); found " + found_list(msh));
  m.T.resize(static_cast<Eigen::Index>(elems.size()), d + 1);
  std::vector<int> line_of;
  long long higher = 0;
  for (std::size_t e = 0; e < elems.size(); ++e) {
    for (int c = 0; c <= d; ++c) m.T(static_cast<Eigen::Index>(e), c) = elems[e].corners[static_cast<std::size_t>(c)];
    line_of.push_back(elems[e].line);
    higher += elems[e].type != (three_d ? 4 : 2);
  }
  if (higher > 0)
    m.notes.push_back(file.string() + ": " + std::to_string(higher) + " higher-order " +
                      (three_d ? "tetrahedra" : "triangles") + " used by their corners; their other nodes stay in the numbering, unconnected");
  check_elements(file, line_of, m.U, m.T);
  return m;
}

Eigen::MatrixXd read_gmsh_nodes(const path& file) {
  return parse_gmsh_nodes(detail::slurp(file), file);
}

Eigen::MatrixXd parse_gmsh_nodes(std::string_view data, const path& file) {
  const MshData msh = parse_msh(data, file);
  Eigen::MatrixXd X(static_cast<Eigen::Index>(msh.xyz.size()), 3);
  for (std::size_t v = 0; v < msh.xyz.size(); ++v)
    for (int c = 0; c < 3; ++c) X(static_cast<Eigen::Index>(v), c) = msh.xyz[v][static_cast<std::size_t>(c)];
  return X;
}

// ------------------------------------------------------------------------------ VTK (reading)
namespace {

struct VtkData {
  Eigen::MatrixXd P;  // n x 3
  struct Cell {
    int type;
    std::vector<long long> nodes;
  };
  std::vector<Cell> cells;
};

// One value of a legacy VTK data type (binary: big endian).
double vtk_value(MshCursor& c, const std::string& type, const std::string& what) {
  if (!c.binary) return c.real(what);
  if (type == "float") return static_cast<double>(c.get<float>(what));
  if (type == "double") return c.get<double>(what);
  if (type == "int" || type == "vtktypeint32") return c.get<std::int32_t>(what);
  if (type == "unsigned_int" || type == "vtktypeuint32") return c.get<std::uint32_t>(what);
  if (type == "long" || type == "vtktypeint64") return static_cast<double>(c.get<std::int64_t>(what));
  if (type == "unsigned_long" || type == "vtktypeuint64") return static_cast<double>(c.get<std::uint64_t>(what));
  if (type == "short") return c.get<std::int16_t>(what);
  if (type == "unsigned_short") return c.get<std::uint16_t>(what);
  if (type == "char") return c.get<std::int8_t>(what);
  if (type == "unsigned_char") return c.get<std::uint8_t>(what);
  c.fail_here("data type '" + type + "' not supported");
}
std::size_t vtk_size(const std::string& type) {
  if (type == "double" || type == "long" || type == "unsigned_long" || type.find("64") != std::string::npos) return 8;
  if (type == "short" || type == "unsigned_short") return 2;
  if (type == "char" || type == "unsigned_char") return 1;
  return 4;
}

VtkData parse_vtk(std::string_view bytes, const path& file) {
  const std::string_view data = detail::skip_bom(bytes);
  if (data.compare(0, 22, "# vtk DataFile Version") != 0)
    fail(file, 1, "not a legacy VTK file (expected '# vtk DataFile Version')");
  // the version line and the title: each ends at LF, CR LF or a lone CR
  auto line_end = [&](std::size_t from) {
    const std::size_t e = data.find_first_of("\r\n", from);
    if (e == std::string_view::npos) return e;
    return e + (data[e] == '\r' && e + 1 < data.size() && data[e + 1] == '\n' ? 1 : 0);
  };
  std::size_t at = line_end(0);
  const std::size_t title_end = at == std::string_view::npos ? at : line_end(at + 1);
  if (title_end == std::string_view::npos) fail(file, 0, "file truncated: expected the title and ASCII/BINARY lines");
  MshCursor c{data, file};
  c.pos = title_end + 1;
  const std::string_view enc = c.word("ASCII or BINARY");
  if (enc == "BINARY") c.binary = true, c.swap = std::endian::native == std::endian::little;
  else if (enc != "ASCII") c.fail_here("expected ASCII or BINARY, found '" + std::string(enc.substr(0, 40)) + "'");
  const bool binary = c.binary;
  c.binary = false;  // keywords are text; data after them follows the encoding
  VtkData out;
  bool have_points = false;
  std::vector<long long> offsets, connectivity;
  long long legacy_cells = -1;
  std::vector<int> types;
  auto numbers = [&](long long count, const std::string& type, const std::string& what, std::vector<long long>& v) {
    c.room(count, binary ? vtk_size(type) : 2, what);
    if (binary) c.end_of_line();
    c.binary = binary;
    v.resize(static_cast<std::size_t>(count));
    for (auto& x : v) {
      const double y = vtk_value(c, type, what);
      if (y != std::floor(y) || std::abs(y) > 9e15) c.fail_here(what + ": not an integer");
      x = static_cast<long long>(y);
    }
    c.binary = false;
  };
  while (!c.at_end()) {
    const std::string key(c.word("a keyword"));
    if (key == "DATASET") {
      const std::string_view t = c.word("dataset type");
      if (t != "UNSTRUCTURED_GRID")
        c.fail_here("dataset " + std::string(t) + " (only UNSTRUCTURED_GRID is a control mesh)");
    } else if (key == "POINTS") {
      const long long n = c.integer("point count", 0, kMax);
      const std::string type(c.word("point data type"));
      c.room(3 * n, binary ? vtk_size(type) : 2, "point coordinates");
      if (binary) c.end_of_line();
      c.binary = binary;
      out.P.resize(n, 3);
      for (long long i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) {
          const double x = vtk_value(c, type, "point " + std::to_string(i) + " coordinate " + std::to_string(k));
          if (!std::isfinite(x)) c.fail_here("point " + std::to_string(i) + ": non-finite coordinate");
          if (std::abs(x) > kMaxCoordinate)
            c.fail_here("point " + std::to_string(i) + ": coordinate larger in magnitude than 1e300, the largest accepted");
          out.P(i, k) = x;
        }
      c.binary = false;
      have_points = true;
    } else if (key == "CELLS") {
      const long long m = c.integer("cell count", 0, kMax);
      const long long size = c.integer("cell list size", 0, kMax);
      const std::size_t save = c.pos;
      const std::string_view next = c.word("cell data");
      if (next == "OFFSETS") {  // format 5.1: offsets (m of them, cells + 1), then connectivity
        const std::string otype(c.word("offsets type"));
        numbers(m, otype, "cell offsets", offsets);
        c.expect("CONNECTIVITY", "");
        const std::string ctype(c.word("connectivity type"));
        numbers(size, ctype, "cell connectivity", connectivity);
      } else {
        c.pos = save;
        std::vector<long long> flat;
        numbers(size, "int", "cell list", flat);
        legacy_cells = m;
        offsets.assign(1, 0);
        std::size_t i = 0;
        for (long long e = 0; e < m; ++e) {
          if (i >= flat.size()) c.fail_here("CELLS: the list is shorter than its " + std::to_string(m) + " cells");
          const long long k = flat[i++];
          if (k < 0 || i + static_cast<std::size_t>(k) > flat.size()) c.fail_here("cell " + std::to_string(e) + ": bad point count " + std::to_string(k));
          connectivity.insert(connectivity.end(), flat.begin() + static_cast<long>(i), flat.begin() + static_cast<long>(i + static_cast<std::size_t>(k)));
          i += static_cast<std::size_t>(k);
          offsets.push_back(static_cast<long long>(connectivity.size()));
        }
      }
    } else if (key == "CELL_TYPES") {
      const long long m = c.integer("cell type count", 0, kMax);
      std::vector<long long> t;
      numbers(m, "int", "cell types", t);
      types.assign(t.begin(), t.end());
    } else if (key == "POINT_DATA" || key == "CELL_DATA") {
      break;  // attributes: not needed
    } else if (key == "FIELD" || key == "METADATA") {
      break;
    } else {
      c.fail_here("unexpected '" + key.substr(0, 40) + "'");
    }
  }
  if (!have_points) fail(file, 0, "no POINTS");
  const long long cells = static_cast<long long>(offsets.empty() ? 0 : offsets.size() - 1);
  (void)legacy_cells;
  if (static_cast<long long>(types.size()) != cells)
    fail(file, 0, "CELLS has " + std::to_string(cells) + " cells but CELL_TYPES " + std::to_string(types.size()));
  for (long long e = 0; e < cells; ++e) {
    VtkData::Cell cell{types[static_cast<std::size_t>(e)], {}};
    const long long b = offsets[static_cast<std::size_t>(e)], en = offsets[static_cast<std::size_t>(e + 1)];
    if (b < 0 || en < b || en > static_cast<long long>(connectivity.size()))
      fail(file, 0, "cell " + std::to_string(e) + ": bad offsets");
    for (long long k = b; k < en; ++k) {
      const long long v = connectivity[static_cast<std::size_t>(k)];
      if (v < 0 || v >= out.P.rows())
        fail(file, 0, "cell " + std::to_string(e) + ": point index " + std::to_string(v) + " out of range [0, " + std::to_string(out.P.rows()) + ")");
      cell.nodes.push_back(v);
    }
    out.cells.push_back(std::move(cell));
  }
  return out;
}

}  // namespace

ControlMesh read_vtk_mesh(const path& file) { return parse_vtk_mesh(detail::slurp(file), file); }

ControlMesh parse_vtk_mesh(std::string_view data, const path& file) {
  const VtkData v = parse_vtk(data, file);
  // tetrahedra (10; quadratic 24 by its corners), else triangles (5; quadratic 22)
  long long tets = 0, tris = 0, higher = 0;
  std::map<int, long long> other;
  for (const auto& c : v.cells) {
    if (c.type == 10 || c.type == 24) ++tets;
    else if (c.type == 5 || c.type == 22) ++tris;
    else ++other[c.type];
  }
  if (tets == 0 && tris == 0) {
    std::string found;
    for (const auto& [t, n] : other) found += (found.empty() ? "" : ", ") + std::to_string(n) + " of type " + std::to_string(t);
    fail(file, 0, "no tetrahedra (cell type 10) or triangles (type 5); found " + (found.empty() ? std::string("no cells") : found));
  }
  const int d = tets > 0 ? 3 : 2;
  ControlMesh m;
  m.U = v.P.leftCols(d);
  if (d == 2 && v.P.rows() > 0 && (v.P.col(2).array() != v.P(0, 2)).any())
    fail(file, 0, "no tetrahedra, and the triangles are not in one plane z = const (a surface mesh of a 3D model?)");
  m.T.resize(d == 3 ? tets : tris, d + 1);
  Eigen::Index r = 0;
  for (const auto& c : v.cells) {
    const bool use = d == 3 ? (c.type == 10 || c.type == 24) : (c.type == 5 || c.type == 22);
    if (!use) continue;
    const std::size_t need = static_cast<std::size_t>(c.type == 24 ? 10 : c.type == 22 ? 6 : d + 1);
    if (c.nodes.size() != need)
      fail(file, 0, "cell " + std::to_string(r) + " of type " + std::to_string(c.type) + ": " + std::to_string(c.nodes.size()) + " points, expected " + std::to_string(need));
    higher += c.type == 24 || c.type == 22;
    for (int k = 0; k <= d; ++k) m.T(r, k) = static_cast<int>(c.nodes[static_cast<std::size_t>(k)]);
    ++r;
  }
  if (higher > 0)
    m.notes.push_back(file.string() + ": " + std::to_string(higher) + " quadratic cells used by their corners; their other points stay in the numbering, unconnected");
  check_elements(file, {}, m.U, m.T);
  return m;
}

Eigen::MatrixXd read_vtk_points(const path& file) {
  return parse_vtk_points(detail::slurp(file), file);
}

Eigen::MatrixXd parse_vtk_points(std::string_view data, const path& file) {
  return parse_vtk(data, file).P;
}

ControlMesh read_control_mesh(const path& file) {
  const std::string ext = detail::extension(file);
  if (ext == ".msh") return read_gmsh(file);
  if (ext == ".vtk") return read_vtk_mesh(file);
  return read_tetgen(file);
}

// ---------------------------------------------------------------------------------------- VTK
void write_vtk(const path& file, const Eigen::Ref<const Eigen::MatrixXd>& U,
               const Eigen::Ref<const Eigen::MatrixXi>& T,
               const Eigen::Ref<const Eigen::MatrixXd>& point_vectors,
               const std::string& point_data) {
  const long long d = U.cols();
  if (d != 2 && d != 3) fail(file, 0, "positions must be n x 2 or n x 3");
  if (T.cols() != d + 1) fail(file, 0, "elements must be m x " + std::to_string(d + 1));
  detail::check_finite(U, file, "point");
  detail::check_indices(T, U.rows(), file, "element");
  const bool vectors = point_vectors.rows() > 0;
  if (vectors) {
    if (point_vectors.rows() != U.rows() || point_vectors.cols() != d)
      fail(file, 0, "point data '" + point_data + "' must be n x d");
    detail::check_finite(point_vectors, file, "point data row");
    for (char c : point_data)
      if (c == ' ' || c == '\n' || c == '\t')
        fail(file, 0, "point data name must not contain blanks");
  }
  detail::write_atomic(file, [&](std::FILE* f) {
    using detail::fmt;
    using detail::put;
    put(f, "# vtk DataFile Version 3.0\nmbi control mesh\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS " +
               std::to_string(U.rows()) + " double\n", file);
    for (Eigen::Index i = 0; i < U.rows(); ++i)
      put(f, fmt(U(i, 0)) + " " + fmt(U(i, 1)) + " " + (d == 3 ? fmt(U(i, 2)) : "0") + "\n", file);
    put(f, "CELLS " + std::to_string(T.rows()) + " " + std::to_string(T.rows() * (d + 2)) + "\n",
        file);
    for (Eigen::Index e = 0; e < T.rows(); ++e) {
      std::string s = std::to_string(d + 1);
      for (Eigen::Index c = 0; c <= d; ++c) s += " " + std::to_string(T(e, c));
      put(f, s + "\n", file);
    }
    put(f, "CELL_TYPES " + std::to_string(T.rows()) + "\n", file);
    const std::string type = d == 3 ? "10\n" : "5\n";
    for (Eigen::Index e = 0; e < T.rows(); ++e) put(f, type, file);
    if (vectors) {
      put(f, "POINT_DATA " + std::to_string(U.rows()) + "\nVECTORS " + point_data + " double\n",
          file);
      for (Eigen::Index i = 0; i < U.rows(); ++i)
        put(f, fmt(point_vectors(i, 0)) + " " + fmt(point_vectors(i, 1)) + " " +
                   (d == 3 ? fmt(point_vectors(i, 2)) : "0") + "\n", file);
    }
  });
}

}  // namespace mbi::io
