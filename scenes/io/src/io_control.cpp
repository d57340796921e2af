// Control meshes: TetGen .node/.ele (and .face output), Gmsh .msh (2.2 and 4.1 ASCII), legacy VTK output.
#include "io_common.hpp"

#include <Eigen/Dense>

#include <array>
#include <cmath>
#include <unordered_map>

namespace mbi::io {
namespace {

using detail::fail;
using detail::Line;
using std::filesystem::path;

constexpr long long kMax = 2147483647LL;

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

NodeFile parse_node(const path& file) {
  const std::string text = detail::slurp(file);
  const auto lines = detail::tokenize(text);
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
          detail::to_double(l.tok[static_cast<std::size_t>(1 + c)], file, l.number,
                            field + " coordinate " + std::to_string(c));
  }
  return out;
}

double simplex_measure(const Eigen::MatrixXd& U, const Eigen::MatrixXi& T, Eigen::Index e,
                       double& scale) {
  const int d = static_cast<int>(U.cols());
  Eigen::MatrixXd E(d, d);
  for (int k = 0; k < d; ++k) E.col(k) = (U.row(T(e, k + 1)) - U.row(T(e, 0))).transpose();
  scale = E.colwise().norm().maxCoeff();
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
    double h = 0.0;
    const double det = simplex_measure(U, T, e, h);
    if (!(std::abs(det) > 1e-12 * std::pow(h, d)))
      fail(file, ln, "element " + std::to_string(e) + ": degenerate (zero " +
                         (d == 3 ? "volume" : "area") + ")");
  }
}

}  // namespace

Eigen::MatrixXd read_node(const path& file) { return parse_node(file).X; }

ControlMesh read_tetgen(const path& p) {
  const path node = with_ext(p, ".node");
  const path ele = with_ext(p, ".ele");
  NodeFile nf = parse_node(node);
  ControlMesh m;
  m.U = std::move(nf.X);
  const long long n = m.U.rows();
  const int d = static_cast<int>(m.U.cols());
  const std::string text = detail::slurp(ele);
  const auto lines = detail::tokenize(text);
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
ControlMesh read_gmsh(const path& file) {
  const std::string text = detail::slurp(file);
  const auto lines = detail::tokenize(text, 0);
  std::size_t i = 0;
  auto need = [&](std::size_t at, const char* what) -> const Line& {
    if (at >= lines.size()) fail(file, 0, std::string("file truncated: expected ") + what);
    return lines[at];
  };
  std::string version;
  std::vector<std::array<double, 3>> xyz;
  std::unordered_map<long long, int> index_of;
  struct Elem {
    int type;
    std::vector<int> nodes;
    int line;
  };
  std::vector<Elem> elems;
  auto add_node = [&](long long tag, const Line& l, std::size_t tok0) {
    const std::string field = "node " + std::to_string(tag);
    if (l.tok.size() < tok0 + 3) fail(file, l.number, field + ": expected x y z");
    std::array<double, 3> p{};
    for (int c = 0; c < 3; ++c)
      p[c] = detail::to_double(l.tok[tok0 + static_cast<std::size_t>(c)], file, l.number,
                               field + " coordinate " + std::to_string(c));
    if (!index_of.emplace(tag, static_cast<int>(xyz.size())).second)
      fail(file, l.number, field + ": duplicate node tag");
    xyz.push_back(p);
  };
  auto node_index = [&](std::string_view s, const Line& l, const std::string& field) {
    const long long tag = detail::to_int(s, file, l.number, field + " node tag", 0, 1LL << 62);
    const auto it = index_of.find(tag);
    if (it == index_of.end())
      fail(file, l.number, field + ": unknown node tag " + std::to_string(tag));
    return it->second;
  };
  auto nodes_per = [](int type) {
    switch (type) {
      case 1: return 2;  case 2: return 3;  case 3: return 4;  case 4: return 4;
      case 5: return 8;  case 6: return 6;  case 7: return 5;  case 8: return 3;
      case 9: return 6;  case 10: return 9; case 11: return 10; case 15: return 1;
      default: return -1;
    }
  };
  while (i < lines.size()) {
    const Line& l = lines[i];
    const std::string_view key = l.tok[0];
    if (key == "$MeshFormat") {
      const Line& f = need(i + 1, "format line");
      if (f.tok.size() < 3) fail(file, f.number, "format: expected '<version> <binary> <size>'");
      version = std::string(f.tok[0]);
      if (version != "2.2" && version != "4.1" && version != "2" && version != "4")
        fail(file, f.number, "format: version " + version + " not supported (2.2 or 4.1)");
      if (f.tok[1] != "0") fail(file, f.number, "format: binary .msh not supported (ASCII only)");
      if (need(i + 2, "$EndMeshFormat").tok[0] != "$EndMeshFormat")
        fail(file, lines[i + 2].number, "expected $EndMeshFormat");
      i += 3;
    } else if (key == "$Nodes") {
      if (version.empty()) fail(file, l.number, "$Nodes before $MeshFormat");
      const Line& h = need(i + 1, "node count");
      std::size_t at = i + 2;
      if (version[0] == '2') {
        const long long n = detail::to_int(h.tok[0], file, h.number, "node count", 0, kMax);
        check_remaining(file, h, n, lines.size() - at, "nodes");
        for (long long k = 0; k < n; ++k, ++at) {
          const Line& nl = lines[at];
          add_node(detail::to_int(nl.tok[0], file, nl.number, "node tag", 0, 1LL << 62), nl, 1);
        }
      } else {
        if (h.tok.size() < 4) fail(file, h.number, "$Nodes header: expected 4 numbers");
        const long long blocks = detail::to_int(h.tok[0], file, h.number, "node block count", 0, kMax);
        const long long total = detail::to_int(h.tok[1], file, h.number, "node count", 0, kMax);
        check_remaining(file, h, blocks + 2 * total, lines.size() - at, "node lines");
        for (long long b = 0; b < blocks; ++b) {
          const Line& bh = need(at++, "node block header");
          if (bh.tok.size() < 4) fail(file, bh.number, "node block: expected 4 numbers");
          const long long param = detail::to_int(bh.tok[2], file, bh.number, "parametric flag", 0, 1);
          const long long nb = detail::to_int(bh.tok[3], file, bh.number, "nodes in block", 0, kMax);
          check_remaining(file, bh, 2 * nb, lines.size() - at, "node lines in the block");
          if (param) fail(file, bh.number, "parametric nodes are not supported");
          for (long long k = 0; k < nb; ++k) {
            const Line& tl = lines[at + static_cast<std::size_t>(k)];
            const Line& cl = lines[at + static_cast<std::size_t>(nb + k)];
            add_node(detail::to_int(tl.tok[0], file, tl.number, "node tag", 0, 1LL << 62), cl, 0);
          }
          at += static_cast<std::size_t>(2 * nb);
        }
      }
      if (need(at, "$EndNodes").tok[0] != "$EndNodes")
        fail(file, lines[at].number, "expected $EndNodes (node count wrong?)");
      i = at + 1;
    } else if (key == "$Elements") {
      if (version.empty()) fail(file, l.number, "$Elements before $MeshFormat");
      const Line& h = need(i + 1, "element count");
      std::size_t at = i + 2;
      auto add_elem = [&](int type, const Line& el, std::size_t tok0) {
        const int k = nodes_per(type);
        if (type != 2 && type != 4) return;  // other types skipped
        const std::string field = "element " + std::string(el.tok[0]);
        if (el.tok.size() < tok0 + static_cast<std::size_t>(k))
          fail(file, el.number, field + ": expected " + std::to_string(k) + " nodes");
        Elem e{type, {}, el.number};
        for (int c = 0; c < k; ++c)
          e.nodes.push_back(node_index(el.tok[tok0 + static_cast<std::size_t>(c)], el, field));
        elems.push_back(std::move(e));
      };
      if (version[0] == '2') {
        const long long m = detail::to_int(h.tok[0], file, h.number, "element count", 0, kMax);
        check_remaining(file, h, m, lines.size() - at, "elements");
        for (long long k = 0; k < m; ++k, ++at) {
          const Line& el = lines[at];
          if (el.tok.size() < 3) fail(file, el.number, "element: expected '<tag> <type> <ntags> ...'");
          const int type = static_cast<int>(detail::to_int(el.tok[1], file, el.number, "element type", 1, 1000));
          const long long nt = detail::to_int(el.tok[2], file, el.number, "element tag count", 0, 1000);
          add_elem(type, el, static_cast<std::size_t>(3 + nt));
        }
      } else {
        if (h.tok.size() < 4) fail(file, h.number, "$Elements header: expected 4 numbers");
        const long long blocks = detail::to_int(h.tok[0], file, h.number, "element block count", 0, kMax);
        const long long total = detail::to_int(h.tok[1], file, h.number, "element count", 0, kMax);
        check_remaining(file, h, blocks + total, lines.size() - at, "element lines");
        for (long long b = 0; b < blocks; ++b) {
          const Line& bh = need(at++, "element block header");
          if (bh.tok.size() < 4) fail(file, bh.number, "element block: expected 4 numbers");
          const int type = static_cast<int>(detail::to_int(bh.tok[2], file, bh.number, "element type", 1, 1000));
          const long long nb = detail::to_int(bh.tok[3], file, bh.number, "elements in block", 0, kMax);
          check_remaining(file, bh, nb, lines.size() - at, "element lines in the block");
          for (long long k = 0; k < nb; ++k) add_elem(type, lines[at++], 1);
        }
      }
      if (need(at, "$EndElements").tok[0] != "$EndElements")
        fail(file, lines[at].number, "expected $EndElements (element count wrong?)");
      i = at + 1;
    } else if (key.size() > 1 && key[0] == '$' && key.substr(0, 4) != "$End") {
      // Unknown section: skip to its $End line.
      const std::string end = "$End" + std::string(key.substr(1));
      std::size_t at = i + 1;
      while (at < lines.size() && lines[at].tok[0] != end) ++at;
      if (at >= lines.size()) fail(file, l.number, "section " + std::string(key) + " not closed");
      i = at + 1;
    } else {
      fail(file, l.number, "unexpected '" + std::string(key) + "' outside a section");
    }
  }
  if (version.empty()) fail(file, 0, "no $MeshFormat section (not a Gmsh file?)");
  bool has_tet = false, has_tri = false;
  for (const auto& e : elems) (e.type == 4 ? has_tet : has_tri) = true;
  if (!has_tet && !has_tri) fail(file, 0, "no tetrahedra (type 4) or triangles (type 2)");
  const int want = has_tet ? 4 : 2;
  const int d = has_tet ? 3 : 2;
  std::vector<int> remap(xyz.size(), -1);
  std::vector<int> line_of;
  int n = 0;
  for (const auto& e : elems)
    if (e.type == want)
      for (int v : e.nodes) remap[static_cast<std::size_t>(v)] = 0;
  for (auto& r : remap)
    if (r == 0) r = n++;
  ControlMesh m;
  m.U.resize(n, d);
  double z0 = 0.0;
  bool first = true;
  for (std::size_t v = 0; v < xyz.size(); ++v) {
    if (remap[v] < 0) continue;
    for (int c = 0; c < d; ++c) m.U(remap[v], c) = xyz[v][static_cast<std::size_t>(c)];
    if (d == 2) {
      if (first) z0 = xyz[v][2];
      else if (xyz[v][2] != z0)
        fail(file, 0, "2D mesh (triangles only) with nodes at different z (" +
                          detail::fmt(z0) + " and " + detail::fmt(xyz[v][2]) + ")");
      first = false;
    }
  }
  long long count = 0;
  for (const auto& e : elems) count += e.type == want;
  m.T.resize(static_cast<Eigen::Index>(count), d + 1);
  Eigen::Index r = 0;
  for (const auto& e : elems) {
    if (e.type != want) continue;
    for (int c = 0; c <= d; ++c) m.T(r, c) = remap[static_cast<std::size_t>(e.nodes[static_cast<std::size_t>(c)])];
    line_of.push_back(e.line);
    ++r;
  }
  check_elements(file, line_of, m.U, m.T);
  return m;
}

ControlMesh read_control_mesh(const path& file) {
  if (detail::extension(file) == ".msh") return read_gmsh(file);
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
