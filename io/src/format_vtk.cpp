// Legacy VTK unstructured grids: read (format 2.0-5.1, ASCII or BINARY; points, cells and cell
// types; the point data for read_point_data) and written (ASCII, with optional point vectors).
#include "control.hpp"
#include "cursor.hpp"

#include <bit>
#include <map>

namespace mbi::io {
namespace {

using detail::Cursor;
using detail::fail;
using std::filesystem::path;

struct VtkData {
  Eigen::MatrixXd P;  // n x 3
  std::vector<detail::VtkCell> cells;
  std::vector<PointField> fields;  // when asked for
};

// One value of a legacy VTK data type (binary: big endian).
double vtk_value(Cursor& c, const std::string& type, const std::string& what) {
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

// The end of the line that starts at `from` (its last byte: LF, the LF of CR LF, or a lone
// CR), or npos.
std::size_t line_end(std::string_view data, std::size_t from) {
  const std::size_t e = data.find_first_of("\r\n", from);
  if (e == std::string_view::npos) return e;
  return e + (data[e] == '\r' && e + 1 < data.size() && data[e + 1] == '\n' ? 1 : 0);
}

// Reads the keywords of a legacy VTK file and the data after them.
class VtkReader {
 public:
  // `fields`: read the point data too (else it is not looked at)
  VtkReader(std::string_view data, const path& file, bool fields = false) : c_{data, file}, file_(file), want_fields_(fields) {}

  VtkData read() {
    encoding();
    while (!c_.at_end()) {
      const std::string key(c_.word("a keyword"));
      if (key == "DATASET") {
        const std::string_view t = c_.word("dataset type");
        if (t != "UNSTRUCTURED_GRID")
          c_.fail_here("dataset " + std::string(t) + " (only UNSTRUCTURED_GRID is a control mesh)");
      } else if (key == "POINTS") {
        points();
      } else if (key == "CELLS") {
        cells();
      } else if (key == "CELL_TYPES") {
        const long long m = c_.integer("cell type count", 0, kMaxCount);
        std::vector<long long> t;
        numbers(m, "int", "cell types", t);
        types_.assign(t.begin(), t.end());
      } else if (want_fields_ && (key == "POINT_DATA" || key == "CELL_DATA")) {
        if (!attributes(c_.integer(key + " count", 0, kMaxCount), key == "POINT_DATA")) break;
      } else if (key == "POINT_DATA" || key == "CELL_DATA" || key == "FIELD" || key == "METADATA") {
        break;  // attributes: not needed
      } else {
        c_.fail_here("unexpected '" + key.substr(0, 40) + "'");
      }
    }
    return assemble();
  }

 private:
  // The version line, the title, then ASCII or BINARY.
  void encoding() {
    const std::string_view data = c_.d;
    if (data.compare(0, 22, "# vtk DataFile Version") != 0)
      fail(file_, 1, "not a legacy VTK file (expected '# vtk DataFile Version')");
    const std::size_t at = line_end(data, 0);
    const std::size_t title_end = at == std::string_view::npos ? at : line_end(data, at + 1);
    if (title_end == std::string_view::npos) fail(file_, 0, "file truncated: expected the title and ASCII/BINARY lines");
    c_.pos = title_end + 1;
    const std::string_view enc = c_.word("ASCII or BINARY");
    if (enc == "BINARY") binary_ = true, c_.swap = std::endian::native == std::endian::little;
    else if (enc != "ASCII") c_.fail_here("expected ASCII or BINARY, found '" + std::string(enc.substr(0, 40)) + "'");
  }

  // The arrays of one POINT_DATA or CELL_DATA section of `n` tuples, kept in out_.fields when
  // `keep`; false at a METADATA block (not read: what follows is left unread).
  bool attributes(long long n, bool keep) {
    while (!c_.at_end()) {
      const std::size_t save = c_.pos;
      const std::string key(c_.word("a data keyword"));
      if (key == "POINT_DATA" || key == "CELL_DATA") {
        c_.pos = save;
        return true;
      }
      if (key == "METADATA") return false;
      if (key == "FIELD") {
        c_.word("field name");
        const long long arrays = c_.integer("FIELD array count", 0, kMaxCount);
        for (long long a = 0; a < arrays; ++a) {
          const std::string name(c_.word("array name"));
          if (name == "METADATA") return false;
          const long long comps = c_.integer(name + ": component count", 1, 1 << 20);
          const long long tuples = c_.integer(name + ": tuple count", 0, kMaxCount);
          const std::string type(c_.word("data type"));
          array(name, type, comps, tuples, keep && tuples == n);
        }
        continue;
      }
      const std::string name(c_.word("array name"));
      const std::string byte_type = binary_ ? "unsigned_char" : "float";
      if (key == "SCALARS") {
        const std::string type(c_.word("data type"));
        const std::size_t at = c_.pos;
        long long comps = 1;
        if (const std::string_view w = c_.word("LOOKUP_TABLE"); w != "LOOKUP_TABLE") {
          c_.pos = at;
          comps = c_.integer(name + ": component count", 1, 4);
          c_.expect("LOOKUP_TABLE", "");
        }
        c_.word("lookup table name");
        array(name, type, comps, n, keep);
      } else if (key == "VECTORS" || key == "NORMALS" || key == "TENSORS") {
        const std::string type(c_.word("data type"));
        array(name, type, key == "TENSORS" ? 9 : 3, n, keep);
      } else if (key == "TEXTURE_COORDINATES") {
        const long long comps = c_.integer(name + ": dimension", 1, 3);
        const std::string type(c_.word("data type"));
        array(name, type, comps, n, keep);
      } else if (key == "COLOR_SCALARS") {
        array(name, byte_type, c_.integer(name + ": component count", 1, 4), n, keep);
      } else if (key == "LOOKUP_TABLE") {
        array(name, byte_type, 4, c_.integer(name + ": size", 0, kMaxCount), false);
      } else {
        c_.fail_here("unexpected '" + key.substr(0, 40) + "' in " + (keep ? "POINT_DATA" : "CELL_DATA"));
      }
    }
    return true;
  }

  // One data array of `tuples` x `comps` values of `type`, kept as a point field when `keep`.
  void array(const std::string& name, const std::string& type, long long comps, long long tuples, bool keep) {
    c_.room(comps * tuples, binary_ ? vtk_size(type) : 2, name + " values");
    if (binary_) c_.end_of_line();
    c_.binary = binary_;
    PointField f{name, Eigen::MatrixXd(keep ? tuples : 0, comps)};
    for (long long i = 0; i < tuples; ++i)
      for (long long k = 0; k < comps; ++k) {
        const double x = vtk_value(c_, type, name + ": tuple " + std::to_string(i));
        if (keep) f.values(i, k) = x;
      }
    c_.binary = false;
    if (keep) out_.fields.push_back(std::move(f));
  }

  // `count` integers of `type` (keywords are text; the data after them follows the encoding).
  void numbers(long long count, const std::string& type, const std::string& what, std::vector<long long>& v) {
    c_.room(count, binary_ ? vtk_size(type) : 2, what);
    if (binary_) c_.end_of_line();
    c_.binary = binary_;
    v.resize(static_cast<std::size_t>(count));
    for (auto& x : v) {
      const double y = vtk_value(c_, type, what);
      if (y != std::floor(y) || std::abs(y) > 9e15) c_.fail_here(what + ": not an integer");
      x = static_cast<long long>(y);
    }
    c_.binary = false;
  }

  void points() {
    const long long n = c_.integer("point count", 0, kMaxCount);
    const std::string type(c_.word("point data type"));
    c_.room(3 * n, binary_ ? vtk_size(type) : 2, "point coordinates");
    if (binary_) c_.end_of_line();
    c_.binary = binary_;
    out_.P.resize(n, 3);
    for (long long i = 0; i < n; ++i)
      for (int k = 0; k < 3; ++k) {
        const std::string field = "point " + std::to_string(i);
        const double x = vtk_value(c_, type, field + " coordinate " + std::to_string(k));
        if (!std::isfinite(x)) c_.fail_here(field + ": non-finite coordinate");
        if (std::abs(x) > kMaxCoordinate)
          c_.fail_here(field + ": coordinate larger in magnitude than 1e300, the largest accepted");
        out_.P(i, k) = x;
      }
    c_.binary = false;
    have_points_ = true;
  }

  // Format 5.1: OFFSETS (cells + 1 of them) and CONNECTIVITY; before: one list, each cell's
  // point count followed by its points.
  void cells() {
    const long long m = c_.integer("cell count", 0, kMaxCount);
    const long long size = c_.integer("cell list size", 0, kMaxCount);
    const std::size_t save = c_.pos;
    if (c_.word("cell data") == "OFFSETS") {
      const std::string otype(c_.word("offsets type"));
      numbers(m, otype, "cell offsets", offsets_);
      c_.expect("CONNECTIVITY", "");
      const std::string ctype(c_.word("connectivity type"));
      numbers(size, ctype, "cell connectivity", connectivity_);
      return;
    }
    c_.pos = save;
    std::vector<long long> flat;
    numbers(size, "int", "cell list", flat);
    offsets_.assign(1, 0);
    std::size_t i = 0;
    for (long long e = 0; e < m; ++e) {
      if (i >= flat.size()) c_.fail_here("CELLS: the list is shorter than its " + std::to_string(m) + " cells");
      const long long k = flat[i++];
      if (k < 0 || i + static_cast<std::size_t>(k) > flat.size()) c_.fail_here("cell " + std::to_string(e) + ": bad point count " + std::to_string(k));
      connectivity_.insert(connectivity_.end(), flat.begin() + static_cast<long>(i), flat.begin() + static_cast<long>(i + static_cast<std::size_t>(k)));
      i += static_cast<std::size_t>(k);
      offsets_.push_back(static_cast<long long>(connectivity_.size()));
    }
  }

  // The cells from offsets, connectivity and types, checked against each other and the points.
  VtkData assemble() {
    if (!have_points_) fail(file_, 0, "no POINTS");
    const long long cells = static_cast<long long>(offsets_.empty() ? 0 : offsets_.size() - 1);
    if (static_cast<long long>(types_.size()) != cells)
      fail(file_, 0, "CELLS has " + std::to_string(cells) + " cells but CELL_TYPES " + std::to_string(types_.size()));
    for (long long e = 0; e < cells; ++e) {
      detail::VtkCell cell{types_[static_cast<std::size_t>(e)], {}};
      const long long b = offsets_[static_cast<std::size_t>(e)], en = offsets_[static_cast<std::size_t>(e + 1)];
      if (b < 0 || en < b || en > static_cast<long long>(connectivity_.size()))
        fail(file_, 0, "cell " + std::to_string(e) + ": bad offsets");
      for (long long k = b; k < en; ++k) {
        const long long v = connectivity_[static_cast<std::size_t>(k)];
        if (v < 0 || v >= out_.P.rows())
          fail(file_, 0, "cell " + std::to_string(e) + ": point index " + std::to_string(v) + " out of range [0, " + std::to_string(out_.P.rows()) + ")");
        cell.nodes.push_back(v);
      }
      out_.cells.push_back(std::move(cell));
    }
    return std::move(out_);
  }

  Cursor c_;
  const path& file_;
  bool binary_ = false;  // the data's encoding (c_.binary is set only while reading data)
  VtkData out_;
  bool have_points_ = false;
  bool want_fields_ = false;
  std::vector<long long> offsets_, connectivity_;
  std::vector<int> types_;
};

VtkData parse_vtk(std::string_view bytes, const path& file, bool fields = false) {
  return VtkReader(detail::skip_bom(bytes), file, fields).read();
}

}  // namespace

ControlMesh read_vtk_mesh(const path& file) { return parse_vtk_mesh(detail::slurp(file), file); }

ControlMesh parse_vtk_mesh(std::string_view data, const path& file) {
  const VtkData v = parse_vtk(data, file);
  return detail::vtk_control_mesh(v.P, v.cells, file);
}

ControlMesh detail::vtk_control_mesh(const Eigen::MatrixXd& P, const std::vector<VtkCell>& cells, const path& file) {
  // tetrahedra (10; quadratic 24 by its corners), else triangles (5; quadratic 22)
  long long tets = 0, tris = 0, higher = 0;
  std::map<int, long long> other;
  for (const auto& c : cells) {
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
  m.U = P.leftCols(d);
  if (d == 2 && P.rows() > 0 && (P.col(2).array() != P(0, 2)).any())
    fail(file, 0, "no tetrahedra, and the triangles are not in one plane z = const (a surface mesh of a 3D model?)");
  m.T.resize(d == 3 ? tets : tris, d + 1);
  Eigen::Index r = 0;
  for (const auto& c : cells) {
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
  detail::check_elements(file, {}, m.U, m.T);
  return m;
}

Eigen::MatrixXd read_vtk_points(const path& file) {
  return parse_vtk_points(detail::slurp(file), file);
}

Eigen::MatrixXd parse_vtk_points(std::string_view data, const path& file) {
  return parse_vtk(data, file).P;
}

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

namespace mbi::io::detail {

PointData read_vtk_point_data(const path& file) {
  VtkData d = parse_vtk(slurp(file), file, true);
  return {std::move(d.P), std::move(d.fields)};
}

}  // namespace mbi::io::detail
