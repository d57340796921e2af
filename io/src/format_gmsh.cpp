// Gmsh .msh: format 2.2, 4.0 and 4.1, ASCII or binary (either endianness). Nodes, and the
// tetrahedra or triangles (of any order) among the elements; other sections are skipped.
#include "control.hpp"
#include "cursor.hpp"

#include <array>
#include <map>
#include <unordered_map>

namespace mbi::io {
namespace {

using detail::Cursor;
using detail::fail;
using std::filesystem::path;

constexpr long long kTag = 1LL << 62;  // the largest node or element tag accepted

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

// The header of a 4.x $Nodes or $Elements section, and of each of its blocks.
struct Msh4Section {
  long long blocks = 0, total = 0;
};
struct Msh4Block {
  long long dim = 0;
  long long value = 0;  // nodes: the parametric flag; elements: the element type
  long long count = 0;
};

// Reads the sections of a .msh file into MshData.
class MshReader {
 public:
  MshReader(std::string_view data, const path& file) : c_{data, file}, file_(file) {}

  MshData read() {
    while (!c_.at_end()) {
      const std::string_view key = c_.word("a section");
      if (key == "$MeshFormat") format();
      else if (key == "$Nodes") nodes();
      else if (key == "$Elements") elements();
      else if (key.size() > 1 && key[0] == '$' && key.substr(0, 4) != "$End") skip_section(key);
      else c_.fail_here("unexpected '" + std::string(key.substr(0, 40)) + "' outside a section");
    }
    if (version_.empty()) fail(file_, 0, "no $MeshFormat section (not a Gmsh file?)");
    return std::move(out_);
  }

 private:
  bool v41() const { return version_ == "4.1"; }

  void format() {
    version_ = std::string(c_.word("format version"));
    const long long type = c_.integer("format file-type", 0, 1);
    size_bytes_ = static_cast<int>(c_.integer("format data-size", 4, 8));
    if (version_ != "2.2" && version_ != "2" && version_ != "2.0" && version_ != "2.1" &&
        version_ != "4" && version_ != "4.0" && version_ != "4.1")
      c_.fail_here("format: version " + version_ + " not supported (2.2, 4.0 and 4.1 are)");
    c_.binary = type == 1;
    if (c_.binary) {
      c_.end_of_line();
      const std::int32_t one = c_.get<std::int32_t>("binary endianness marker");
      if (one != 1) {
        c_.swap = true;
        if (__builtin_bswap32(static_cast<std::uint32_t>(one)) != 1)
          c_.fail_here("binary: expected the int 1 after the format line");
      }
    }
    c_.expect("$EndMeshFormat", "");
  }

  // Any other section ($PhysicalNames, $Entities, $NodeData, ...): skipped to its $End line.
  void skip_section(std::string_view key) {
    const std::string end = "\n$End" + std::string(key.substr(1));
    const std::size_t at = c_.d.find(end, c_.pos);
    if (at == std::string_view::npos) c_.fail_here("section " + std::string(key) + " not closed");
    c_.pos = at + end.size();
  }

  // "numBlocks numItems", then in 4.1 "minTag maxTag"; item: "node" or "element".
  Msh4Section section_v4(const std::string& item) {
    if (c_.binary) c_.end_of_line();
    Msh4Section s;
    s.blocks = c_.size(item + " block count", 0, kMaxCount, size_bytes_);
    s.total = c_.size(item + " count", 0, kMaxCount, size_bytes_);
    if (v41()) {
      c_.size("min " + item + " tag", 0, kTag, size_bytes_);
      c_.size("max " + item + " tag", 0, kTag, size_bytes_);
    }
    return s;
  }

  // "entityDim entityTag" (4.0: "entityTag entityDim"), the int `value` in [lo, hi], then the
  // count of the block's items (at most `total`).
  Msh4Block block_v4(const std::string& item, const std::string& value, long long lo, long long hi,
                     long long total) {
    Msh4Block b;
    if (v41()) {
      b.dim = c_.i32(item + " block entity dimension", 0, 3);
      c_.i32(item + " block entity tag", -kMaxCount, kMaxCount);
    } else {
      c_.i32(item + " block entity tag", -kMaxCount, kMaxCount);
      b.dim = c_.i32(item + " block entity dimension", 0, 3);
    }
    b.value = c_.i32(value, lo, hi);
    b.count = c_.size(item + "s in block", 0, total, size_bytes_);
    return b;
  }

  void add_node(long long tag, int params) {
    const std::string field = "node " + std::to_string(tag);
    std::array<double, 3> p{};
    for (int k = 0; k < 3; ++k) {
      const double x = c_.real(field + " coordinate " + std::to_string(k));
      if (!(std::abs(x) <= kMaxCoordinate)) c_.fail_here(field + ": coordinate larger in magnitude than 1e300, the largest accepted");
      p[static_cast<std::size_t>(k)] = x;
    }
    for (int k = 0; k < params; ++k) c_.real(field + " parametric coordinate");  // -save_parametric
    if (!index_of_.emplace(tag, static_cast<int>(out_.xyz.size())).second)
      c_.fail_here("node " + std::to_string(tag) + ": duplicate node tag");
    out_.xyz.push_back(p);
  }

  void nodes() {
    if (version_.empty()) c_.fail_here("$Nodes before $MeshFormat");
    if (version_[0] == '2') {
      const long long n = c_.integer("node count", 0, kMaxCount);
      c_.room(n, c_.binary ? 28 : 8, "nodes");
      if (c_.binary) c_.end_of_line();
      for (long long k = 0; k < n; ++k) add_node(c_.i32("node tag", 0, kMaxCount), 0);
    } else {
      const Msh4Section s = section_v4("node");
      c_.room(s.total, c_.binary ? 32 : 8, "nodes");
      for (long long b = 0; b < s.blocks; ++b) {
        const Msh4Block blk = block_v4("node", "node block parametric flag", 0, 1, s.total);
        const int params = blk.value ? static_cast<int>(blk.dim) : 0;
        if (v41()) {  // the block's tags, then its coordinates
          std::vector<long long> tags(static_cast<std::size_t>(blk.count));
          for (auto& t : tags) t = c_.size("node tag", 1, kTag, size_bytes_);
          for (long long t : tags) add_node(t, params);
        } else {
          for (long long k = 0; k < blk.count; ++k) add_node(c_.i32("node tag", 1, kMaxCount), params);
        }
      }
    }
    c_.expect("$EndNodes", " (node count wrong?)");
  }

  // An element of `type` with node tags tags_ (line: 0 in binary files).
  void add_elem(int type, long long tag, int line) {
    ++out_.count_of_type[type];
    const bool tet = msh_tet(type), tri = msh_tri(type);
    if (!tet && !tri) return;
    MshData::Elem e{type, {-1, -1, -1, -1}, line};
    for (int k = 0; k < (tet ? 4 : 3); ++k) {
      const long long node = tags_[static_cast<std::size_t>(k)];
      const auto it = index_of_.find(node);
      if (it == index_of_.end())
        fail(file_, line, "element " + std::to_string(tag) + ": unknown node tag " + std::to_string(node));
      e.corners[static_cast<std::size_t>(k)] = it->second;
    }
    (tet ? out_.tets : out_.tris).push_back(e);
  }

  // Nodes per element of a type this reader knows; fails otherwise.
  int nodes_of(int type) {
    const int k = msh_nodes(type);
    if (k < 0) c_.fail_here("element type " + std::to_string(type) + " unknown to this reader");
    return k;
  }

  void elements() {
    if (version_.empty()) c_.fail_here("$Elements before $MeshFormat");
    if (version_[0] == '2') {
      const long long m = c_.integer("element count", 0, kMaxCount);
      c_.room(m, c_.binary ? 12 : 8, "elements");
      if (c_.binary) elements_v2_binary(m);
      else elements_v2_ascii(m);
    } else {
      elements_v4();
    }
    c_.expect("$EndElements", " (element count wrong?)");
  }

  // Runs of elements of one type: "type count tagCount", then per element its tag, tags and nodes.
  void elements_v2_binary(long long m) {
    c_.end_of_line();
    long long done = 0;
    while (done < m) {
      const int type = static_cast<int>(c_.i32("element type", 1, 1000));
      const long long follow = c_.i32("elements following", 1, m - done);
      const long long ntags = c_.i32("element tag count", 0, 1000);
      const int k = nodes_of(type);
      for (long long e = 0; e < follow; ++e) {
        const long long tag = c_.i32("element tag", 0, kMaxCount);
        for (long long t = 0; t < ntags; ++t) c_.i32("element tag", -kMaxCount, kMaxCount);
        tags_.assign(static_cast<std::size_t>(k), 0);
        for (auto& t : tags_) t = c_.i32("element node", 0, kMaxCount);
        add_elem(type, tag, 0);
      }
      done += follow;
    }
  }

  // One line an element: "tag type tagCount tags... nodes...".
  void elements_v2_ascii(long long m) {
    for (long long e = 0; e < m; ++e) {
      const long long tag = c_.integer("element tag", 0, kTag);
      const int line = c_.line_at(c_.last);
      const int type = static_cast<int>(c_.integer("element type", 1, 1000));
      const long long ntags = c_.integer("element tag count", 0, 1000);
      for (long long t = 0; t < ntags; ++t) c_.integer("element tag", -kTag, kTag);
      const int k = msh_nodes(type);
      if (k < 0) fail(file_, line, "element " + std::to_string(tag) + ": type " + std::to_string(type) + " unknown to this reader");
      tags_.assign(static_cast<std::size_t>(k), 0);
      for (auto& t : tags_) t = c_.integer("element " + std::to_string(tag) + " node tag", 0, kTag);
      if (c_.line_at(c_.last) != line) fail(file_, line, "element " + std::to_string(tag) + ": expected " + std::to_string(k) + " nodes");
      add_elem(type, tag, line);
    }
  }

  void elements_v4() {
    const Msh4Section s = section_v4("element");
    c_.room(s.total, c_.binary ? 8 : 4, "elements");
    for (long long b = 0; b < s.blocks; ++b) {
      const Msh4Block blk = block_v4("element", "element type", 1, 1000, s.total);
      const int type = static_cast<int>(blk.value);
      const int k = nodes_of(type);
      for (long long e = 0; e < blk.count; ++e) {
        const long long tag = v41() ? c_.size("element tag", 0, kTag, size_bytes_) : c_.i32("element tag", 0, kMaxCount);
        const int line = c_.line_at(c_.last);
        const std::string what = "element " + std::to_string(tag) + " node tag";
        tags_.assign(static_cast<std::size_t>(k), 0);
        for (auto& t : tags_) t = v41() ? c_.size(what, 0, kTag, size_bytes_) : c_.i32(what, 0, kMaxCount);
        add_elem(type, tag, line);
      }
    }
  }

  Cursor c_;
  const path& file_;
  MshData out_;
  std::string version_;
  int size_bytes_ = 8;
  std::unordered_map<long long, int> index_of_;  // node tag -> index in out_.xyz
  std::vector<long long> tags_;                  // node tags of the element being read
};

MshData parse_msh(std::string_view bytes, const path& file) {
  return MshReader(detail::skip_bom(bytes), file).read();
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
  detail::check_elements(file, line_of, m.U, m.T);
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

}  // namespace mbi::io
