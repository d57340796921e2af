// TetGen: BASE.node (points) and BASE.ele (tetrahedra or triangles) read and written, BASE.face
// (boundary triangles) written only.
#include "control.hpp"

namespace mbi::io {
namespace {

using detail::fail;
using detail::Line;
using detail::tetgen_file;
using std::filesystem::path;

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
  const long long n = detail::to_int(h.tok[0], file, h.number, "header point count", 0, kMaxCount);
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
    const long long num = detail::to_int(l.tok[0], file, l.number, field + " number", 0, kMaxCount);
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

}  // namespace

Eigen::MatrixXd read_node(const path& file) { return node_file(detail::slurp(file), file).X; }

Eigen::MatrixXd parse_node(std::string_view data, const path& file) {
  return node_file(data, file).X;
}

ControlMesh read_tetgen(const path& p) {
  const std::string node = detail::slurp(tetgen_file(p, ".node"));
  return parse_tetgen(node, detail::slurp(tetgen_file(p, ".ele")), p);
}

ControlMesh parse_tetgen(std::string_view node_text, std::string_view ele_text, const path& p) {
  const path node = tetgen_file(p, ".node");
  const path ele = tetgen_file(p, ".ele");
  NodeFile nf = node_file(node_text, node);
  ControlMesh m;
  m.U = std::move(nf.X);
  const long long n = m.U.rows();
  const int d = static_cast<int>(m.U.cols());
  const auto lines = detail::tokenize(detail::skip_bom(ele_text));
  if (lines.empty()) fail(ele, 0, "empty .ele file");
  const Line& h = lines[0];
  if (h.tok.size() < 2) fail(ele, h.number, "header: expected '<elements> <nodes per element> <attributes>'");
  const long long m_count = detail::to_int(h.tok[0], ele, h.number, "header element count", 0, kMaxCount);
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
    detail::to_int(l.tok[0], ele, l.number, field + " number", 0, kMaxCount);
    for (int c = 0; c <= d; ++c)
      m.T(static_cast<Eigen::Index>(e), c) = static_cast<int>(
          detail::to_int(l.tok[static_cast<std::size_t>(1 + c)], ele, l.number, field + " node",
                         nf.base, nf.base + n - 1) - nf.base);
    line_of[static_cast<std::size_t>(e)] = l.number;
  }
  detail::check_elements(ele, line_of, m.U, m.T);
  return m;
}

namespace {
std::string entry(double x) { return detail::fmt(x); }
std::string entry(int x) { return std::to_string(x); }

// A TetGen file: its header line, then a line a row of M: the row's 0-based number, its entries.
template <typename Matrix>
void write_numbered(const path& file, const std::string& header, const Matrix& M) {
  detail::write_atomic(file, [&](std::FILE* f) {
    detail::put(f, header, file);
    for (Eigen::Index i = 0; i < M.rows(); ++i) {
      std::string s = std::to_string(i);
      for (Eigen::Index c = 0; c < M.cols(); ++c) s += " " + entry(M(i, c));
      detail::put(f, s + "\n", file);
    }
  });
}
}  // namespace

void write_node(const path& file, const Eigen::Ref<const Eigen::MatrixXd>& X) {
  if (X.cols() != 2 && X.cols() != 3)
    fail(file, 0, "positions must be n x 2 or n x 3, got n x " + std::to_string(X.cols()));
  detail::check_finite(X, file, "point");
  write_numbered(file, std::to_string(X.rows()) + " " + std::to_string(X.cols()) + " 0 0\n", X);
}

void write_tetgen(const path& base, const Eigen::Ref<const Eigen::MatrixXd>& U,
                  const Eigen::Ref<const Eigen::MatrixXi>& T,
                  const Eigen::Ref<const Eigen::MatrixXi>& faces) {
  const path node = tetgen_file(base, ".node"), ele = tetgen_file(base, ".ele"),
             face = tetgen_file(base, ".face");
  const long long d = U.cols();
  if (T.cols() != d + 1)
    fail(ele, 0, "elements must be m x " + std::to_string(d + 1) + " for " + std::to_string(d) +
                     "D positions, got m x " + std::to_string(T.cols()));
  detail::check_indices(T, U.rows(), ele, "element");
  if (faces.rows() > 0) {
    if (d != 3 || faces.cols() != 3) fail(face, 0, "faces must be b x 3 (3D)");
    detail::check_indices(faces, U.rows(), face, "face");
  }
  write_node(node, U);
  write_numbered(ele, std::to_string(T.rows()) + " " + std::to_string(T.cols()) + " 0\n", T);
  if (faces.rows() > 0) write_numbered(face, std::to_string(faces.rows()) + " 0\n", faces);
}

namespace detail {

// Only these are dropped: TetGen's numbered names ("box.1") keep their extension.
path tetgen_file(const path& base, const char* ext) {
  path p = base;
  const std::string e = lower_extension(base);
  if (e == ".node" || e == ".ele" || e == ".face") p.replace_extension();
  p += ext;
  return p;
}

std::vector<path> tetgen_files(const path& base) {
  return {tetgen_file(base, ".node"), tetgen_file(base, ".ele")};
}

}  // namespace detail
}  // namespace mbi::io
