#include <mbi/scenes/limits.hpp>
#include <mbi/scenes/scene.hpp>

#include <toml.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <set>
#include <sstream>
#include <vector>

namespace mbi::scenes {
namespace {

using toml_value = toml::value;

std::string first_line(const std::string& s) {
  std::string out;
  std::istringstream in(s);
  std::string line;
  while (std::getline(in, line)) {
    // toml11 messages start with "[error] ..." followed by a source excerpt
    if (!line.empty()) {
      out = line;
      break;
    }
  }
  const std::string tag = "[error] ";
  if (out.rfind(tag, 0) == 0) out = out.substr(tag.size());
  return out;
}

// A TOML table whose keys are checked: every key must be read through this class, or finish()
// reports it as unknown.
class Table {
 public:
  Table(const toml_value& v, std::string prefix, std::string file)
      : v_(v), prefix_(std::move(prefix)), file_(std::move(file)) {}

  bool has(const std::string& key) {
    if (!v_.as_table().count(key)) return false;
    used_.insert(key);
    return true;
  }
  const toml_value& at(const std::string& key) {
    used_.insert(key);
    return v_.as_table().at(key);
  }
  std::string where(const toml_value& v) const {
    return file_ + ":" + std::to_string(v.location().line());
  }
  std::string key_name(const std::string& key) const {
    return prefix_.empty() ? key : prefix_ + "." + key;
  }
  [[noreturn]] void fail(const std::string& key, const std::string& msg) {
    const toml_value& v = v_.as_table().count(key) ? v_.as_table().at(key) : v_;
    throw Error(where(v) + ": " + key_name(key) + ": " + msg);
  }

  double number(const std::string& key, double def, double lo = -HUGE_VAL, double hi = HUGE_VAL,
                bool lo_open = false) {
    if (!has(key)) return def;
    const toml_value& v = at(key);
    double x;
    if (v.is_floating())
      x = v.as_floating();
    else if (v.is_integer())
      x = static_cast<double>(v.as_integer());
    else
      fail(key, "expected a number");
    if (!std::isfinite(x)) fail(key, "must be finite");
    if (x < lo || x > hi || (lo_open && x == lo)) {
      std::ostringstream m;
      m << "value " << x << " out of range " << (lo_open ? "(" : "[") << lo << ", " << hi << "]";
      fail(key, m.str());
    }
    return x;
  }
  int integer(const std::string& key, int def, long lo, long hi) {
    if (!has(key)) return def;
    const toml_value& v = at(key);
    if (!v.is_integer()) fail(key, "expected an integer");
    const auto x = v.as_integer();
    if (x < lo || x > hi)
      fail(key, "value " + std::to_string(x) + " out of range [" + std::to_string(lo) + ", " +
                    std::to_string(hi) + "]");
    return static_cast<int>(x);
  }
  bool boolean(const std::string& key, bool def) {
    if (!has(key)) return def;
    const toml_value& v = at(key);
    if (!v.is_boolean()) fail(key, "expected true or false");
    return v.as_boolean();
  }
  /// A string key naming a value of an enum's table: unknown names list the accepted ones.
  template <typename E, std::size_t N>
  E choice(const std::string& key, E def, const NameTable<E, N>& names) {
    if (!has(key)) return def;
    const std::string s = string(key, "");
    if (const std::optional<E> value = names.find(s)) return *value;
    fail(key, names.unknown(s));
  }
  std::string string(const std::string& key, const std::string& def) {
    if (!has(key)) return def;
    const toml_value& v = at(key);
    if (!v.is_string()) fail(key, "expected a string");
    return v.as_string();
  }
  Eigen::Vector3d vec(const std::string& key, const Eigen::Vector3d& def, int dims = 3) {
    if (!has(key)) return def;
    const toml_value& v = at(key);
    if (!v.is_array()) fail(key, "expected an array of " + std::to_string(dims) + " numbers");
    const auto& a = v.as_array();
    if (static_cast<int>(a.size()) != dims && !(dims == 2 && a.size() == 3))
      fail(key, std::string("expected ") + (dims == 2 ? "2 or 3" : std::to_string(dims)) +
                    " numbers, got " + std::to_string(a.size()));
    Eigen::Vector3d out = Eigen::Vector3d::Zero();
    for (size_t i = 0; i < a.size(); ++i) {
      if (a[i].is_floating())
        out[static_cast<Eigen::Index>(i)] = a[i].as_floating();
      else if (a[i].is_integer())
        out[static_cast<Eigen::Index>(i)] = static_cast<double>(a[i].as_integer());
      else
        fail(key, "element " + std::to_string(i) + " is not a number");
      if (!std::isfinite(out[static_cast<Eigen::Index>(i)])) fail(key, "must be finite");
    }
    return out;
  }
  Table sub(const std::string& key) {
    const toml_value& v = at(key);
    if (!v.is_table()) fail(key, "expected a table");
    return Table(v, key_name(key), file_);
  }
  std::vector<Table> array_of_tables(const std::string& key) {
    std::vector<Table> out;
    if (!has(key)) return out;
    const toml_value& v = at(key);
    if (!v.is_array()) fail(key, "expected an array of tables ([[" + key_name(key) + "]])");
    const auto& arr = v.as_array();
    for (size_t i = 0; i < arr.size(); ++i) {
      if (!arr[i].is_table())
        throw Error(where(arr[i]) + ": " + key_name(key) + "[" + std::to_string(i) +
                         "]: expected a table");
      out.emplace_back(arr[i], key_name(key) + "[" + std::to_string(i) + "]", file_);
    }
    return out;
  }
  /// Every key of this table must have been read.
  void finish() {
    std::vector<std::string> unknown;
    for (const auto& [k, v] : v_.as_table())
      if (!used_.count(k)) unknown.push_back(k);
    if (unknown.empty()) return;
    std::sort(unknown.begin(), unknown.end());
    const toml_value& v = v_.as_table().at(unknown.front());
    throw Error(where(v) + ": " + key_name(unknown.front()) + ": unknown key");
  }
  const std::string& file() const { return file_; }
  const toml_value& value() const { return v_; }

 private:
  const toml_value& v_;
  std::string prefix_, file_;
  std::set<std::string> used_;
};

Selection parse_selection(Table t) {
  Selection s;
  s.where = t.where(t.value());
  if (t.has("box")) {
    Table b = t.sub("box");
    const Eigen::Vector3d lo = b.vec("min", Eigen::Vector3d::Constant(-HUGE_VAL));
    const Eigen::Vector3d hi = b.vec("max", Eigen::Vector3d::Constant(HUGE_VAL));
    if ((hi - lo).minCoeff() < 0) b.fail("max", "max must be >= min in every coordinate");
    b.finish();
    s.box = std::make_pair(lo, hi);
  }
  if (t.has("box_relative")) {
    Table b = t.sub("box_relative");
    const Eigen::Vector3d lo = b.vec("min", Eigen::Vector3d::Zero());
    const Eigen::Vector3d hi = b.vec("max", Eigen::Vector3d::Ones());
    if ((hi - lo).minCoeff() < 0) b.fail("max", "max must be >= min in every coordinate");
    b.finish();
    s.box_relative = std::make_pair(lo, hi);
  }
  if (t.has("half_space")) {
    Table h = t.sub("half_space");
    const Eigen::Vector3d p = h.vec("point", Eigen::Vector3d::Zero());
    const Eigen::Vector3d n = h.vec("normal", Eigen::Vector3d::UnitZ());
    if (n.norm() == 0) h.fail("normal", "normal must be non-zero");
    h.finish();
    s.half_space = std::make_pair(p, n);
  }
  if (t.has("indices")) {
    const toml_value& v = t.at("indices");
    if (!v.is_array()) t.fail("indices", "expected an array of integers");
    for (const auto& x : v.as_array()) {
      if (!x.is_integer() || x.as_integer() < 0 || x.as_integer() > (1 << 30))
        t.fail("indices", "expected non-negative integers");
      s.indices.push_back(static_cast<int>(x.as_integer()));
    }
  }
  if (!s.box && !s.box_relative && !s.half_space && s.indices.empty())
    throw Error(s.where + ": " + t.key_name("") +
                     " needs box, box_relative, half_space or indices");
  t.finish();
  return s;
}

}  // namespace

std::filesystem::path resolve_path(const Scene& sc, const std::filesystem::path& p) {
  if (p.is_absolute()) return p;
  return sc.file.parent_path() / p;
}

namespace {

// Refuses a TOML text whose arrays and inline tables nest deeper than kMaxSceneNesting, or
// whose dotted keys (a.b.c = 1, [a.b.c]) have more parts than that: toml11 parses and
// destroys nested values recursively, and 50,000 levels overflow the stack. Brackets, braces
// and dots in strings (basic, literal, multi-line) and comments are not counted; table headers
// ([a], [[a]]) count as the brackets they are, and close on their line.
// Refuses what TOML forbids anywhere, before toml11 sees it: bytes that are not UTF-8 and
// control characters other than tab, LF and CR LF (toml11 3.7 reads past its buffer on some
// such input: found by fuzz_scene).
void check_characters(std::string_view t, const std::string& fname) {
  int line = 1;
  for (std::size_t i = 0; i < t.size();) {
    const auto c = static_cast<unsigned char>(t[i]);
    auto refuse = [&](const std::string& what) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "0x%02X", c);
      throw Error(fname + ":" + std::to_string(line) + ": syntax error: " + what + " (byte " +
                       hex + ")");
    };
    if (c == '\n') {
      ++line;
      ++i;
    } else if (c == '\r') {
      if (i + 1 >= t.size() || t[i + 1] != '\n') refuse("a CR not followed by LF");
      ++i;
    } else if (c < 0x20 || c == 0x7F) {
      if (c != '\t') refuse("control character");
      ++i;
    } else if (c < 0x80) {
      ++i;
    } else {
      // UTF-8: 2 to 4 bytes, no overlong forms, no surrogates, at most U+10FFFF
      const int n = c >= 0xC2 && c <= 0xDF ? 2 : c >= 0xE0 && c <= 0xEF ? 3 : c >= 0xF0 && c <= 0xF4 ? 4 : 0;
      if (n == 0 || i + n > t.size()) refuse("not UTF-8 text");
      const auto c1 = static_cast<unsigned char>(t[i + 1]);
      const unsigned char lo = c == 0xE0 ? 0xA0 : c == 0xF0 ? 0x90 : 0x80;
      const unsigned char hi = c == 0xED ? 0x9F : c == 0xF4 ? 0x8F : 0xBF;
      if (c1 < lo || c1 > hi) refuse("not UTF-8 text");
      for (int k = 2; k < n; ++k)
        if ((static_cast<unsigned char>(t[i + k]) & 0xC0) != 0x80) refuse("not UTF-8 text");
      i += n;
    }
  }
}

void check_nesting(std::string_view t, const std::string& fname) {
  int line = 1, dots = 0;
  std::vector<char> open;  // the brackets open at this point: '[' or '{'
  bool key = true;         // in a key: at a line start outside brackets, or after '{' / ','
                           // in an inline table; until '='
  std::size_t i = 0;
  auto starts = [&](const char* s) { return t.compare(i, std::strlen(s), s) == 0; };
  auto refuse = [&](const char* what) {
    throw Error(fname + ":" + std::to_string(line) + ": " + what + " nest deeper than " +
                     std::to_string(kMaxSceneNesting) + " levels");
  };
  auto start_key = [&] {
    key = true;
    dots = 0;
  };
  while (i < t.size()) {
    const char ch = t[i];
    if (ch == '\n') {
      ++line;
      ++i;
      if (open.empty()) start_key();
    } else if (ch == '#') {
      while (i < t.size() && t[i] != '\n') ++i;
    } else if (starts("\"\"\"") || starts("'''")) {
      const std::string_view close = t.substr(i, 3);
      const bool basic = ch == '"';
      i += 3;
      while (i < t.size() && t.compare(i, 3, close) != 0) {
        if (t[i] == '\n') ++line;
        i += basic && t[i] == '\\' && i + 1 < t.size() && t[i + 1] != '\n' ? 2 : 1;
      }
      i += 3;
      while (i < t.size() && t[i] == ch) ++i;  // """a"""" : up to two quotes end the string
    } else if (ch == '"' || ch == '\'') {
      ++i;
      while (i < t.size() && t[i] != ch && t[i] != '\n')
        i += ch == '"' && t[i] == '\\' && i + 1 < t.size() && t[i + 1] != '\n' ? 2 : 1;
      if (i < t.size() && t[i] == ch) ++i;
    } else {
      if (ch == '[' || ch == '{') {
        open.push_back(ch);
        if (static_cast<int>(open.size()) > kMaxSceneNesting) refuse("arrays and inline tables");
        if (ch == '{') start_key();
      } else if ((ch == ']' || ch == '}') && !open.empty()) {
        open.pop_back();
      } else if (ch == '=') {
        key = false;
      } else if (ch == ',' && !open.empty() && open.back() == '{') {
        start_key();
      } else if (ch == '.' && key && ++dots >= kMaxSceneNesting) {
        refuse("dotted keys");
      }
      ++i;
    }
  }
}

}  // namespace

namespace {

// One function per table of the scene file, in the order parse_scene reads them.

void parse_dense(Table t, DenseSpec& d) {
  if (t.has("path")) d.path = t.string("path", "");
  d.builtin = t.choice("builtin", DenseBuiltin::None, kDenseBuiltinNames);
  if (d.path.empty() == (d.builtin == DenseBuiltin::None))
    throw Error(t.where(t.value()) + ": dense: give exactly one of path or builtin");
  d.subdivide = t.integer("subdivide", 0, 0, 4);
  if (t.has("image")) d.image = t.string("image", "");
  d.grid = t.integer("grid", 128, 2, 4096);
  t.finish();
}

// [dense], or several [[dense]] entries: the first is sc.dense, the others (files only) follow it.
void parse_dense_models(Table& top, Scene& sc) {
  if (!top.at("dense").is_array()) return parse_dense(top.sub("dense"), sc.dense);
  std::vector<Table> entries = top.array_of_tables("dense");
  if (entries.empty()) throw Error(top.where(top.at("dense")) + ": dense: give at least one [[dense]] entry");
  for (std::size_t k = 0; k < entries.size(); ++k) {
    DenseSpec d;
    parse_dense(entries[k], d);
    if (entries.size() > 1 && d.path.empty())
      throw Error(entries[k].where(entries[k].value()) + ": dense: several dense models are files (path), not built-ins");
    if (k == 0) sc.dense = d;
    else sc.more_dense.push_back(d);
  }
}

// cells = [nx, ny(, nz)] of a built-in box or grid, counted in 64 bits before it is built.
Eigen::Vector3i parse_cells(Table& t, ControlBuiltin builtin) {
  Eigen::Vector3d c = t.vec("cells", Eigen::Vector3d(2, 2, 8), 2);
  if (t.value().as_table().count("cells") && t.value().as_table().at("cells").as_array().size() == 2)
    c.z() = 1;
  if (c.minCoeff() < 1 || c.maxCoeff() > 1000 || (c - c.array().round().matrix()).norm() > 0)
    t.fail("cells", "expected positive integers <= 1000");
  if (t.has("cells")) {
    const bool flat = builtin == ControlBuiltin::Grid2D;  // [nx, ny] for box: nz = 1
    const auto nx = static_cast<long long>(c.x()), ny = static_cast<long long>(c.y()),
               nz = static_cast<long long>(c.z());
    const long long verts = (nx + 1) * (ny + 1) * (flat ? 1 : nz + 1);
    const long long elems = flat ? 2 * nx * ny : 6 * nx * ny * nz;
    const std::string over = over_memory_floor(0, verts, elems, flat ? 2 : 3);
    if (!over.empty())
      t.fail("cells", "makes " + std::to_string(verts) + " control vertices and " + std::to_string(elems) +
                          (flat ? " triangles" : " tetrahedra") + ", which " + over + " (see docs/limits.md)");
  }
  return c.cast<int>();
}

void parse_control(Table t, ControlSpec& c) {
  if (t.has("path")) c.path = t.string("path", "");
  c.builtin = t.choice("builtin", ControlBuiltin::None, kControlBuiltinNames);
  c.generate_vertices = t.integer("generate_vertices", 0, 4, 1 << 30);
  // a generated mesh has about 3 to 6 tetrahedra a vertex: 6 for the floor's check
  if (const std::string over = over_memory_floor(0, c.generate_vertices, 6LL * c.generate_vertices, 3); !over.empty())
    t.fail("generate_vertices", std::to_string(c.generate_vertices) + " control vertices " + over + " (see docs/limits.md)");
  c.mesher = t.choice("mesher", generate::Mesher::Voxel, generate::kMesherNames);
  const int given = int(!c.path.empty()) + int(c.builtin != ControlBuiltin::None) +
                    int(c.generate_vertices > 0);
  if (given != 1)
    throw Error(t.where(t.value()) +
                     ": control: give exactly one of path, builtin or generate_vertices");
  c.cells = parse_cells(t, c.builtin);
  t.finish();
}

void parse_material(Table t, sim::Material& m) {
  // physical ranges (beyond them the stiffness and mass matrices lose their digits): the
  // stiffest solid (diamond) is about 1.2e12 Pa, the densest element (osmium) 22,590 kg/m^3
  m.youngs_modulus = t.number("young", m.youngs_modulus, 0, 1e13, true);
  m.poisson_ratio = t.number("poisson", m.poisson_ratio, -0.999, 0.499);
  m.density = t.number("density", m.density, 0, 1e5, true);
  t.finish();
}

// The height of the ground plane when it becomes a collider (contact = surface).
std::optional<double> parse_simulation(Table t, SimulationSpec& s) {
  sim::Parameters& p = s.parameters;
  s.contact = t.choice("contact", s.contact, pipeline::kContactModeNames);
  const bool surface = s.contact == pipeline::ContactMode::Surface;
  const std::string needs_surface = std::string("needs contact = \"") +
                                    pipeline::kContactModeNames.name(pipeline::ContactMode::Surface) + "\"";
  p.dt = t.number("dt", p.dt, 0, 10, true);
  p.substeps = t.integer("substeps", p.substeps, 1, 1000);
  s.frames = t.integer("frames", s.frames, 1, 1000000);
  p.newton_iterations = t.integer("newton_iterations", surface ? kSurfaceNewtonIterations : p.newton_iterations, 1, 100);
  if (t.has("newton_tolerance")) s.newton_tolerance = t.number("newton_tolerance", 0.0, 0, 1e30);
  p.gravity = t.vec("gravity", p.gravity);
  if (p.gravity.norm() > 1e6) t.fail("gravity", "magnitude above 1e6 m/s^2");
  p.mass_damping = t.number("damping_mass", p.mass_damping, 0, 1e6);
  p.stiffness_damping = t.number("damping_stiffness", p.stiffness_damping, 0, 1e3);
  if (surface && p.stiffness_damping > 0)
    t.fail("damping_stiffness", "must be 0 with contact = \"surface\" (the step with contact minimises a potential)");
  if (t.has("contact_stiffness")) {
    if (!surface) t.fail("contact_stiffness", needs_surface);
    s.contact_stiffness = t.number("contact_stiffness", 0.0, 0, 1e15, true);
  }
  for (const char* key : {"contact_max_depth", "contact_friction_velocity"}) {
    if (!t.has(key)) continue;
    if (!surface) t.fail(key, needs_surface);
    (std::string(key) == "contact_max_depth" ? s.contact_max_depth : s.contact_friction_velocity) =
        t.number(key, 0.0, 0, 1e15, true);
  }
  if (t.has("contact_select")) {
    if (!surface) t.fail("contact_select", needs_surface);
    s.contact_select = parse_selection(t.sub("contact_select"));
  }
  std::optional<double> ground;
  if (t.has("ground")) {  // the height of a ground plane, y up
    if (surface) {
      ground = t.number("ground", 0.0);
    } else {
      p.ground = true;
      p.ground_plane.normal = Eigen::Vector3d::UnitY();
      p.ground_plane.offset = t.number("ground", 0.0);
    }
  }
  t.finish();
  return ground;
}

// A rigid motion (kinematic constraints, colliders); the scene file's defaults: about z, no stop.
void parse_motion(Table m, sim::RigidMotion& r) {
  r.axis = m.vec("twist_axis", r.axis);
  if (r.axis.norm() == 0) m.fail("twist_axis", "axis must be non-zero");
  r.center = m.vec("twist_center", r.center);
  r.angular_velocity = m.number("twist_rate", 0.0, -1e4, 1e4);
  r.velocity = m.vec("velocity", r.velocity);
  r.start = m.number("start", 0.0, 0, HUGE_VAL);
  r.stop = m.number("stop", 1e30, 0, HUGE_VAL);
  if (r.stop < r.start) m.fail("stop", "stop must be >= start");
  m.finish();
}

ConstraintSpec parse_constraint(Table& t) {
  ConstraintSpec c;
  c.kind = t.choice("type", ConstraintSpec::Kind::Fixed, kConstraintKindNames);
  if (!t.has("select")) throw Error(t.where(t.value()) + ": " + t.key_name("select") + ": missing");
  c.select = parse_selection(t.sub("select"));
  if (t.has("motion")) {
    if (c.kind != ConstraintSpec::Kind::Kinematic)
      t.fail("motion", "only kinematic constraints have a motion");
    parse_motion(t.sub("motion"), c.motion);
  }
  t.finish();
  return c;
}

PokeSpec parse_poke(Table& t) {
  PokeSpec p;
  p.first = t.integer("first", 0, 0, 1 << 30);
  p.last = t.integer("last", 1 << 30, 0, 1 << 30);  // default: to the end of the run
  if (p.last < p.first) t.fail("last", "last must be >= first");
  const bool has_point = t.has("point"), has_at = t.has("at");
  if (has_point == has_at)
    throw Error(t.where(t.value()) + ": " + t.key_name("") + ": give exactly one of point or at");
  p.relative = has_at;
  p.point = has_at ? t.vec("at", p.point) : t.vec("point", p.point);
  if (t.has("force")) p.force = t.vec("force", Eigen::Vector3d::Zero());
  if (t.has("target")) p.target = t.vec("target", Eigen::Vector3d::Zero());
  if (t.has("offset")) {
    if (p.target) t.fail("offset", "give target or offset, not both");
    p.target = t.vec("offset", Eigen::Vector3d::Zero());
    p.target_relative = true;
  }
  if (t.has("offset_relative")) {
    if (p.target) t.fail("offset_relative", "give one of target, offset or offset_relative");
    p.target = t.vec("offset_relative", Eigen::Vector3d::Zero());
    p.target_relative = true;
    p.offset_in_sizes = true;
  }
  p.stiffness = t.number("stiffness", 0.0, 0, 1e15);
  if (p.force.has_value() == p.target.has_value())
    throw Error(t.where(t.value()) + ": " + t.key_name("") + ": give exactly one of force or target");
  if (p.target && p.stiffness <= 0) t.fail("stiffness", "a target poke needs stiffness > 0 (N/m)");
  t.finish();
  return p;
}

DragSpec parse_drag(Table& t) {
  DragSpec d;
  d.vertex = t.integer("vertex", -1, 0, 1 << 30);
  if (t.has("near")) d.near = t.vec("near", Eigen::Vector3d::Zero(), 2);
  if (t.has("select")) d.select = parse_selection(t.sub("select"));
  if (int(d.vertex >= 0) + int(d.near.has_value()) + int(d.select.has_value()) != 1)
    throw Error(t.where(t.value()) + ": " + t.key_name("") +
                     ": give exactly one of vertex, near or select");
  if (!t.has("keys")) throw Error(t.where(t.value()) + ": " + t.key_name("keys") + ": missing");
  const toml_value& keys = t.at("keys");
  if (!keys.is_array() || keys.as_array().empty())
    t.fail("keys", "expected an array of [frame, x, y(, z)] arrays");
  for (const auto& k : keys.as_array()) {
    if (!k.is_array() || (k.as_array().size() != 3 && k.as_array().size() != 4))
      t.fail("keys", "each key is [frame, x, y] (2D) or [frame, x, y, z]");
    Eigen::Vector4d q = Eigen::Vector4d::Zero();
    for (size_t i = 0; i < k.as_array().size(); ++i) {
      const auto& x = k.as_array()[i];
      if (x.is_floating())
        q[static_cast<Eigen::Index>(i)] = x.as_floating();
      else if (x.is_integer())
        q[static_cast<Eigen::Index>(i)] = static_cast<double>(x.as_integer());
      else
        t.fail("keys", "key entries must be numbers");
    }
    if (!q.allFinite()) t.fail("keys", "key entries must be finite");
    if (!d.keys.empty() && q[0] <= d.keys.back().first) t.fail("keys", "frames must increase");
    d.keys.emplace_back(q[0], q.tail<3>());
  }
  t.finish();
  return d;
}

// A key the shape needs: "<file>:<line>: colliders[i].<key>: missing" without it.
void require(Table& t, const std::string& key) {
  if (!t.has(key)) throw Error(t.where(t.value()) + ": " + t.key_name(key) + ": missing");
}

// A box's axes: [[x, y, z], [x, y, z], [x, y, z]], its three unit axes (the columns of axes).
Eigen::Matrix3d parse_axes(Table& t) {
  const toml_value& v = t.at("axes");
  if (!v.is_array() || v.as_array().size() != 3) t.fail("axes", "expected three axes [[x, y, z], [x, y, z], [x, y, z]]");
  Eigen::Matrix3d A;
  for (int k = 0; k < 3; ++k) {
    const toml_value& a = v.as_array()[static_cast<size_t>(k)];
    if (!a.is_array() || a.as_array().size() != 3) t.fail("axes", "each axis is [x, y, z]");
    for (int c = 0; c < 3; ++c) {
      const toml_value& x = a.as_array()[static_cast<size_t>(c)];
      if (!x.is_floating() && !x.is_integer()) t.fail("axes", "axis entries must be numbers");
      A(c, k) = x.is_floating() ? x.as_floating() : static_cast<double>(x.as_integer());
    }
  }
  if (!A.allFinite()) t.fail("axes", "must be finite");
  return A;
}

// shape = "mesh": its file and level-set options (the level set is built from the file later,
// read_collider_meshes) and its placement, the mesh's point v at point + axes v.
ColliderMesh parse_mesh_keys(Table& t, pipeline::Collider& c) {
  ColliderMesh m;
  require(t, "path");
  m.path = t.string("path", "");
  if (m.path.empty()) t.fail("path", "must name a file (a closed triangle mesh: .obj, .off, .ply or .stl)");
  m.where_path = m.where_voxel_size = t.where(t.at("path"));
  if (t.has("voxel_size")) {
    m.options.voxel_size = t.number("voxel_size", 0.0, 0, HUGE_VAL, true);
    m.where_voxel_size = t.where(t.at("voxel_size"));
  }
  m.options.band_voxels = t.number("band_voxels", m.options.band_voxels, 1, 100);
  c.point = t.vec("point", c.point);
  if (t.has("axes")) c.axes = parse_axes(t);
  return m;
}

pipeline::Collider parse_collider(Table& t, std::size_t index, Scene& sc) {
  using pipeline::ColliderShape;
  require(t, "shape");
  pipeline::Collider c;
  c.shape = t.choice("shape", ColliderShape::Plane, kColliderShapeNames);
  const double inf = HUGE_VAL;
  if (c.shape == ColliderShape::Mesh) {
    sc.collider_meshes.push_back(parse_mesh_keys(t, c));
    sc.collider_meshes.back().index = index;
  } else if (c.shape == ColliderShape::Plane) {
    c.point = t.vec("point", c.point);
    c.normal = t.vec("normal", c.normal);
  } else if (c.shape == ColliderShape::Capsule) {
    require(t, "a");
    require(t, "b");
    c.point = t.vec("a", c.point);
    c.end = t.vec("b", c.end);
  } else {
    require(t, "center");
    c.point = t.vec("center", c.point);
  }
  if (c.shape == ColliderShape::Sphere || c.shape == ColliderShape::Capsule) {
    require(t, "radius");
    c.radius = t.number("radius", 0.0, 0, inf, true);
  }
  if (c.shape == ColliderShape::Box) {
    require(t, "half_extents");
    c.half_extents = t.vec("half_extents", c.half_extents);
    if (t.has("axes")) c.axes = parse_axes(t);
  }
  c.friction = t.number("friction", 0.0, 0, inf);
  c.motion = sim::RigidMotion{.axis = Eigen::Vector3d::UnitZ(), .stop = 1e30};
  if (t.has("motion")) parse_motion(t.sub("motion"), c.motion);
  t.finish();
  pipeline::Collider checked = c;
  if (c.shape == ColliderShape::Mesh) checked.shape = ColliderShape::Box;  // no level set yet: a box's checks of the rest
  try {
    pipeline::check_collider(checked, "colliders[" + std::to_string(index) + "]");
  } catch (const mbi::Error& e) {
    throw Error(t.where(t.value()) + ": " + e.what());
  }
  return c;
}

void parse_interpolation(Table t, InterpolationSpec& i) {
  i.method = t.choice("method", i.method, pipeline::kMethodNames);
  if (t.has("alpha")) {
    const double alpha = t.number("alpha", 0.0);
    try {
      i.options.alpha = interp::check_alpha(alpha);
    } catch (const interp::Error& e) {
      t.fail("alpha", e.what());
    }
  }
  i.options.pin_boundary = t.boolean("pin_boundary", false);
  i.compare_pinned = t.boolean("compare_pinned", false);
  i.gpu = t.choice("gpu", i.gpu, kGpuUseNames);
  i.handles = t.choice("handles", i.handles, kHandleModeNames);
  t.finish();
}

void parse_output(Table t, OutputSpec& o) {
  o.every = t.integer("every", o.every, 1, 1 << 30);
  o.mesh_format = t.choice("mesh_format", o.mesh_format, kMeshFormatNames);
  o.pc2 = t.boolean("pc2", o.pc2);
  o.control_vtk = t.boolean("control_vtk", o.control_vtk);
  o.metrics = t.boolean("metrics", o.metrics);
  o.image = t.boolean("image", o.image);
  o.creases = t.boolean("creases", o.creases);
  o.up = t.vec("up", o.up);
  if (o.up.norm() == 0) t.fail("up", "must be non-zero");
  t.finish();
}

// The TOML tree of a scene text that passed check_characters and check_nesting.
toml_value parse_toml(std::string_view text, const std::string& fname) {
  try {
    // a final newline: toml11 reads past the end of some texts without one
    std::istringstream in{std::string(text) + "\n"};
    return toml::parse(in, fname);
  } catch (const toml::exception& e) {
    throw Error(fname + ":" + std::to_string(e.location().line()) +
                     ": syntax error: " + first_line(e.what()));
  } catch (const std::exception& e) {
    throw Error(fname + ": " + first_line(e.what()));
  }
}

}  // namespace

Scene parse_scene(std::string_view text, const std::filesystem::path& file) {
  const std::string fname = file.string();
  if (text.size() >= 3 && text.compare(0, 3, "\xEF\xBB\xBF") == 0) text.remove_prefix(3);  // BOM
  check_characters(text, fname);
  check_nesting(text, fname);
  const toml_value root = parse_toml(text, fname);
  Scene sc;
  sc.file = file;
  Table top(root, "", fname);
  sc.name = top.string("name", file.stem().string());
  sc.mode = top.choice("mode", Mode::Simulate, kModeNames);
  if (!top.has("dense")) throw Error(fname + ":1: dense: missing table [dense]");
  parse_dense_models(top, sc);
  if (!top.has("control")) throw Error(fname + ":1: control: missing table [control]");
  parse_control(top.sub("control"), sc.control);
  if (top.has("material")) parse_material(top.sub("material"), sc.material);
  std::optional<double> ground;
  if (top.has("simulation")) ground = parse_simulation(top.sub("simulation"), sc.simulation);
  for (Table& t : top.array_of_tables("constraints")) sc.constraints.push_back(parse_constraint(t));
  for (Table& t : top.array_of_tables("pokes")) sc.pokes.push_back(parse_poke(t));
  for (Table& t : top.array_of_tables("drags")) sc.drags.push_back(parse_drag(t));
  std::vector<Table> colliders = top.array_of_tables("colliders");
  const bool surface = sc.simulation.contact == pipeline::ContactMode::Surface;
  if (!colliders.empty() && !surface)
    top.fail("colliders", "[[colliders]] need simulation.contact = \"surface\" (contact at the dense surface)");
  for (std::size_t k = 0; k < colliders.size(); ++k) sc.colliders.push_back(parse_collider(colliders[k], k, sc));
  if (ground) sc.colliders.push_back(pipeline::Collider::plane({0, *ground, 0}, {0, 1, 0}));
  if (surface && sc.colliders.empty())
    throw Error(fname + ":1: simulation.contact: \"surface\" needs [[colliders]] or simulation.ground (nothing to touch)");
  if (top.has("interpolation")) parse_interpolation(top.sub("interpolation"), sc.interpolation);
  if (top.has("output")) parse_output(top.sub("output"), sc.output);
  top.finish();
  if (sc.mode == Mode::Drag && surface)
    throw Error(fname + ":1: simulation.contact: only simulate scenes (mode = \"" + std::string(mode_name(Mode::Simulate)) +
                "\") have contact");
  if (sc.mode == Mode::Drag && sc.drags.empty())
    throw Error(fname + ":1: drags: a drag scene needs at least one [[drags]] entry");
  if (sc.mode == Mode::Simulate && !sc.drags.empty())
    throw Error(fname + ":1: drags: only drag scenes (mode = \"" + mode_name(Mode::Drag) +
                     "\") take [[drags]]");
  // the drag driver has no forces: pokes and constraints would be ignored
  for (const std::string key : {"pokes", "constraints"})
    if (sc.mode == Mode::Drag && top.has(key))
      top.fail(key, "only simulate scenes (mode = \"" + std::string(mode_name(Mode::Simulate)) + "\") take [[" +
                        key + "]]; a drag scene moves its control mesh by [[drags]] alone");
  return sc;
}

std::vector<int> select_nodes(const Selection& s, const Eigen::Ref<const Eigen::MatrixXd>& U) {
  std::vector<char> on(static_cast<size_t>(U.rows()), 0);
  const int d = static_cast<int>(U.cols());
  for (int i : s.indices) {
    if (i >= U.rows())
      throw Error(s.where + ": select.indices: node " + std::to_string(i) +
                       " out of range (control mesh has " + std::to_string(U.rows()) + ")");
    on[static_cast<size_t>(i)] = 1;
  }
  const Eigen::VectorXd bb_lo = U.colwise().minCoeff().transpose();
  const Eigen::VectorXd bb_hi = U.colwise().maxCoeff().transpose();
  for (Eigen::Index i = 0; i < U.rows(); ++i) {
    if (s.box_relative) {
      const auto& [a, b] = *s.box_relative;
      bool in = true;
      for (int c = 0; c < d; ++c) {
        const double ext = bb_hi[c] - bb_lo[c], tol = 1e-9 * (1 + ext);
        in = in && U(i, c) >= bb_lo[c] + a[c] * ext - tol && U(i, c) <= bb_lo[c] + b[c] * ext + tol;
      }
      if (in) on[static_cast<size_t>(i)] = 1;
    }
    if (s.box) {
      const auto& [lo, hi] = *s.box;
      bool in = true;
      for (int c = 0; c < d; ++c) in = in && U(i, c) >= lo[c] && U(i, c) <= hi[c];
      if (in) on[static_cast<size_t>(i)] = 1;
    }
    if (s.half_space) {
      const auto& [q, n] = *s.half_space;
      double side = 0;
      for (int c = 0; c < d; ++c) side += (U(i, c) - q[c]) * n[c];
      if (side >= 0) on[static_cast<size_t>(i)] = 1;
    }
  }
  std::vector<int> out;
  for (size_t i = 0; i < on.size(); ++i)
    if (on[i]) out.push_back(static_cast<int>(i));
  if (out.empty()) throw Error(s.where + ": select: selects no control node");
  return out;
}

}  // namespace mbi::scenes
