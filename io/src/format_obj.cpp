// Wavefront OBJ: "v" and "f" lines (v, v/t, v//n, v/t/n, negative relative indices), "vn" for
// the normals; every other record is kept as written, to be written back.
//
// Read and written here rather than through OpenMesh's IO layer, which hands OBJ vertices to
// its importer as float (losing the %.17g round trip) and duplicates the vertices of
// non-manifold faces.
#include "surface.hpp"

#include <mbi/io/obj_text.hpp>

#include <array>

namespace mbi::io::detail {
namespace {

using std::filesystem::path;
using Kind = ObjAttributes::Record::Kind;

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

// A face as written, its indices resolved but not yet checked against the counts (an index
// may name a vertex of a later line).
struct RawFace {
  int line;
  std::vector<long long> v, vt, vn;  // 0-based, -1 = none
};

// The records of an OBJ file that make the mesh.
struct ObjRead {
  std::vector<std::array<double, 3>> v, vn;
  long long nvt = 0;
  bool any_tail = false;
  std::vector<RawFace> faces;
};

using Words = std::vector<std::string_view>;

void read_vertex(const Words& tok, int number, const path& file, ObjRead& r, ObjAttributes& a) {
  const std::string field = "vertex " + std::to_string(r.v.size());
  if (tok.size() < 4) fail(file, number, field + ": expected 3 coordinates");
  std::array<double, 3> p{};
  for (int c = 0; c < 3; ++c)
    p[c] = to_coordinate(tok[c + 1], file, number, field + " coordinate " + std::to_string(c));
  std::string tail;
  if (tok.size() > 4) {  // w or vertex colours: kept as written
    tail.assign(tok[4].data(),
                static_cast<std::size_t>(tok.back().data() + tok.back().size() - tok[4].data()));
    r.any_tail = true;
  }
  a.vertex_tail.push_back(std::move(tail));
  a.records.push_back({Kind::vertex, static_cast<int>(r.v.size()), {}});
  r.v.push_back(p);
}

void read_normal(const Words& tok, int number, const path& file, ObjRead& r) {
  const std::string field = "normal " + std::to_string(r.vn.size());
  if (tok.size() < 4) fail(file, number, field + ": expected 3 numbers");
  std::array<double, 3> n{};
  for (int c = 0; c < 3; ++c) n[c] = to_double(tok[c + 1], file, number, field);
  r.vn.push_back(n);
}

RawFace read_face(const Words& tok, int number, const path& file, const ObjRead& r) {
  const std::string field = "face " + std::to_string(r.faces.size());
  if (tok.size() < 4) fail(file, number, field + ": fewer than 3 vertices");
  // name: "face 3", "face 3 texture" or "face 3 normal"
  auto index = [&](std::string_view s, const std::string& name, long long count) {
    const long long i = to_int(s, file, number, name + " index", -kMaxCount, kMaxCount);
    return obj_index(i, count, file, number, name);
  };
  RawFace f{number, {}, {}, {}};
  for (std::size_t k = 1; k < tok.size(); ++k) {
    const std::string_view s = tok[k];
    std::string_view parts[3];  // v, vt, vn
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
    f.v.push_back(index(parts[0], field, static_cast<long long>(r.v.size())));
    f.vt.push_back(parts[1].empty() ? -1 : index(parts[1], field + " texture", r.nvt));
    f.vn.push_back(parts[2].empty() ? -1 : index(parts[2], field + " normal",
                                                  static_cast<long long>(r.vn.size())));
  }
  return f;
}

// The mesh of the records read: faces checked against the counts, a vertex's normal from the
// first corner that names it, the others' from their faces.
SurfaceMesh assemble(const ObjRead& r, const path& file, ObjAttributes& a) {
  SurfaceMesh m;
  const long long nv = static_cast<long long>(r.v.size());
  const long long nn = static_cast<long long>(r.vn.size());
  set_vertices(m, r.v);
  std::vector<char> have(r.v.size(), 0);
  bool any_normal = false;
  if (nn > 0) m.N = Eigen::MatrixXd::Zero(nv, 3);
  for (std::size_t j = 0; j < r.faces.size(); ++j) {
    const RawFace& f = r.faces[j];
    const std::string field = "face " + std::to_string(j);
    std::vector<int> p;
    for (std::size_t k = 0; k < f.v.size(); ++k) {
      const long long i = f.v[k];
      if (i >= nv)
        fail(file, f.line, field + ": index " + std::to_string(i + 1) +
                               " > number of vertices " + std::to_string(nv));
      if (f.vt[k] >= r.nvt)
        fail(file, f.line, field + ": texture index " + std::to_string(f.vt[k] + 1) +
                               " > number of texture coordinates " + std::to_string(r.nvt));
      if (f.vn[k] >= nn)
        fail(file, f.line, field + ": normal index " + std::to_string(f.vn[k] + 1) +
                               " > number of normals " + std::to_string(nn));
      if (f.vn[k] >= 0 && !have[static_cast<std::size_t>(i)]) {
        const auto& n = r.vn[static_cast<std::size_t>(f.vn[k])];
        m.N.row(i) << n[0], n[1], n[2];
        have[static_cast<std::size_t>(i)] = 1;
        any_normal = true;
      }
      p.push_back(static_cast<int>(i));
    }
    m.polygons.push_back(std::move(p));
    a.face_vt.emplace_back(f.vt.begin(), f.vt.end());
  }
  fan(m);
  if (any_normal) complete_normals(m, std::move(have));
  else m.N.resize(0, 0);
  return m;
}

}  // namespace

SurfaceMesh parse_obj(std::string_view data, const path& file) {
  auto attr = std::make_shared<SurfaceAttributes>();
  attr->format = ".obj";
  ObjAttributes& a = attr->obj;
  a.file = file;
  ObjRead r;
  LineReader lines(skip_bom(data));
  std::string_view raw;
  while (lines.next(raw)) {
    const Words tok = words(raw);
    if (tok.empty()) continue;  // blank line or comment
    const int number = lines.number();
    if (tok[0] == "v") {
      read_vertex(tok, number, file, r, a);
    } else if (tok[0] == "vn") {
      read_normal(tok, number, file, r);
    } else if (tok[0] == "f") {
      r.faces.push_back(read_face(tok, number, file, r));
      a.records.push_back({Kind::face, static_cast<int>(r.faces.size() - 1), {}});
    } else {  // vt, g, o, usemtl, mtllib, s, l, ...: kept as written
      if (tok[0] == "vt") ++r.nvt;
      a.records.push_back({Kind::text, 0, std::string(raw)});
    }
  }
  if (!r.any_tail) a.vertex_tail.clear();
  SurfaceMesh m = assemble(r, file, a);
  attr->vertices = m.V.rows();
  m.attributes = std::move(attr);
  return m;
}

bool obj_attributes_fit(const SurfaceAttributes& a, const std::vector<std::vector<int>>& faces) {
  if (a.obj.face_vt.size() != faces.size()) return false;
  for (std::size_t i = 0; i < faces.size(); ++i)
    if (a.obj.face_vt[i].size() != faces[i].size()) return false;
  return true;
}

void write_obj(std::FILE* f, const SurfaceOutput& out) {
  const auto& V = out.V;
  const auto& N = out.N;
  const bool has_n = out.has_normals();
  auto vertex = [&](Eigen::Index i, const std::string* tail) {
    std::string s = "v " + fmt(V(i, 0)) + " " + fmt(V(i, 1)) + " " + fmt(V(i, 2));
    if (tail && !tail->empty()) s += " " + *tail;
    s += "\n";
    if (has_n) s += "vn " + fmt(N(i, 0)) + " " + fmt(N(i, 1)) + " " + fmt(N(i, 2)) + "\n";
    put(f, s, out.file);
  };
  // v, v/vt, v//vn or v/vt/vn; the normal of a corner is its vertex's (one vn per vertex)
  auto face = [&](std::size_t j, const std::vector<int>* vt) {
    std::string s = "f";
    const auto& p = out.faces[j];
    for (std::size_t k = 0; k < p.size(); ++k) {
      const std::string v = std::to_string(p[k] + 1);
      const int t = vt ? (*vt)[k] : -1;
      s += " " + v;
      if (t >= 0) s += "/" + std::to_string(t + 1);
      if (has_n) s += (t >= 0 ? "/" : "//") + v;
    }
    put(f, s + "\n", out.file);
  };
  if (!out.attributes) {
    for (Eigen::Index i = 0; i < V.rows(); ++i) vertex(i, nullptr);
    for (std::size_t j = 0; j < out.faces.size(); ++j) face(j, nullptr);
    return;
  }
  const ObjAttributes& a = out.attributes->obj;
  for (const auto& r : a.records) {
    const auto i = static_cast<std::size_t>(r.index);
    if (r.kind == Kind::text) put(f, r.text + "\n", out.file);
    else if (r.kind == Kind::vertex) vertex(r.index, a.vertex_tail.empty() ? nullptr : &a.vertex_tail[i]);
    else face(i, &a.face_vt[i]);
  }
}

}  // namespace mbi::io::detail

namespace mbi::io {

SurfaceMesh parse_obj_text(std::string_view text, const std::filesystem::path& name) {
  return detail::parse_obj(text, name);
}

}  // namespace mbi::io
