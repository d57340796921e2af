// OFF: "OFF" (or a prefixed variant such as "NOFF"), the counts on the header line or the next,
// then "x y z" per vertex and "k i0 .. ik-1" per face. ASCII only. The prefix "4" (4OFF, C4OFF,
// ...) gives each vertex a homogeneous w after z: the point is (x, y, z) / w. The prefix "n"
// (a dimension other than 3 on its own line) is refused.
#include "surface.hpp"

#include <array>

namespace mbi::io::detail {

using std::filesystem::path;

namespace {
// One vertex line: x y z, or x y z w of a homogeneous 4OFF, the point being (x, y, z) / w.
std::array<double, 3> read_vertex(const Line& l, const std::string& field, bool homogeneous, const path& file) {
  const std::size_t want = homogeneous ? 4 : 3;
  if (l.tok.size() < want)
    fail(file, l.number, field + (homogeneous ? ": expected 4 coordinates (x y z w: 4OFF)" : ": expected 3 coordinates"));
  std::array<double, 3> p{};
  for (int c = 0; c < 3; ++c)
    p[c] = to_coordinate(l.tok[c], file, l.number, field + " coordinate " + std::to_string(c));
  if (!homogeneous) return p;
  const double w = to_coordinate(l.tok[3], file, l.number, field + " w");
  if (w == 0) fail(file, l.number, field + ": w = 0 (a point at infinity)");
  for (int c = 0; c < 3; ++c) {
    p[c] /= w;  // a tiny w can make it overflow: checked as any coordinate
    check_coordinate(p[c], file, l.number, field + " coordinate " + std::to_string(c) + " / w");
  }
  return p;
}
}  // namespace

SurfaceMesh parse_off(std::string_view data, const path& file) {
  const auto lines = tokenize(skip_bom(data));
  if (lines.empty()) fail(file, 0, "empty file (expected an OFF header)");
  const auto& h = lines[0];
  const std::string_view magic = h.tok[0];
  if (magic.size() < 3 || magic.substr(magic.size() - 3) != "OFF")
    fail(file, h.number, "header: expected 'OFF', found '" + std::string(magic) + "'");
  if (h.tok.size() > 1 && h.tok[1] == "BINARY")
    fail(file, h.number, "header: binary OFF is not supported (use ASCII OFF or PLY)");
  const std::string_view prefix = magic.substr(0, magic.size() - 3);
  if (prefix.find('n') != std::string_view::npos)
    fail(file, h.number, "header: '" + std::string(magic) + "' (a dimension other than 3) is not supported");
  const bool homogeneous = prefix.find('4') != std::string_view::npos;
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
  const long long nv = to_int(counts[0], file, count_line, "vertex count", 0, kMaxCount);
  const long long nf = to_int(counts[1], file, count_line, "face count", 0, kMaxCount);
  const long long remaining = static_cast<long long>(lines.size() - li - 1);
  if (nv + nf > remaining)
    fail(file, count_line,
         "header: " + std::to_string(nv) + " vertices and " + std::to_string(nf) +
             " faces but only " + std::to_string(remaining) + " data lines follow");
  SurfaceMesh m;
  std::vector<std::array<double, 3>> v(static_cast<std::size_t>(nv));
  std::size_t at = li + 1;
  for (long long i = 0; i < nv; ++i, ++at)
    v[static_cast<std::size_t>(i)] = read_vertex(lines[at], "vertex " + std::to_string(i), homogeneous, file);
  m.polygons.reserve(static_cast<std::size_t>(nf));
  for (long long f = 0; f < nf; ++f, ++at) {
    const auto& l = lines[at];
    const std::string field = "face " + std::to_string(f);
    const long long k = to_int(l.tok[0], file, l.number, field + " vertex count", 3,
                               static_cast<long long>(l.tok.size()) - 1);
    std::vector<int> p;
    for (long long j = 1; j <= k; ++j)
      p.push_back(static_cast<int>(
          to_int(l.tok[static_cast<std::size_t>(j)], file, l.number, field + " index", 0, nv - 1)));
    m.polygons.push_back(std::move(p));
  }
  set_vertices(m, v);
  fan(m);
  return m;
}

void write_off(std::FILE* f, const SurfaceOutput& out) {
  put(f, "OFF\n" + std::to_string(out.V.rows()) + " " + std::to_string(out.faces.size()) + " 0\n",
      out.file);
  put_vertex_lines(f, out, false);
  put_counted_faces(f, out);
}

}  // namespace mbi::io::detail
