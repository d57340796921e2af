#pragma once
// Scene files (TOML): what to load, how to simulate or drag it, how to interpolate, what to write.
// The format is documented key by key in docs/scene-format.md. load_scene() checks every key:
// unknown keys, wrong types and out-of-range values throw Error "<file>:<line>: <key>: ...".
// After parsing, a scene holds enums and typed values only: nothing downstream compares strings.
#include <mbi/base/names.hpp>
#include <mbi/error.hpp>
#include <mbi/generate/cage.hpp>
#include <mbi/interp/control.hpp>
#include <mbi/pipeline/contact_setup.hpp>
#include <mbi/pipeline/method.hpp>
#include <mbi/sim/simulator.hpp>

#include <Eigen/Core>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace mbi::scenes {

/// A scene file that cannot be used: "<file>:<line>: <key>: <what is wrong>".
class Error : public mbi::Error {
 public:
  using mbi::Error::Error;
};

/// How the control mesh moves.
enum class Mode {
  Simulate,  ///< co-rotational FEM (3D)
  Drag,      ///< handles dragged without physics (paper Eq. 10/11), 2D or 3D
};
enum class DenseBuiltin { None, PaperBar, Cylinder, BumpySphere, ImageGrid };
enum class ControlBuiltin { None, PaperBar, Box, Grid2D };
enum class MeshFormat { Obj, Ply, Glb, None };
/// Where the dense points are evaluated and pictures drawn: the GPU (OpenGL transform feedback)
/// or the CPU. Auto uses the GPU when an OpenGL context can be made and says so when it cannot.
enum class GpuUse { Auto, On, Off };

/// The names of the enums, as scene files, the command line and messages spell them (the
/// methods' names are pipeline::kMethodNames, the meshers' generate::kMesherNames). The "none"
/// values of DenseBuiltin and ControlBuiltin have no name: a scene never writes them.
inline constexpr auto kModeNames =
    name_table<Mode>({{Mode::Simulate, "simulate"}, {Mode::Drag, "drag"}});
inline constexpr auto kDenseBuiltinNames = name_table<DenseBuiltin>(
    {{DenseBuiltin::PaperBar, "paper-bar"},
     {DenseBuiltin::Cylinder, "cylinder"},
     {DenseBuiltin::BumpySphere, "bumpy-sphere"},
     {DenseBuiltin::ImageGrid, "image-grid"}});
inline constexpr auto kControlBuiltinNames = name_table<ControlBuiltin>(
    {{ControlBuiltin::PaperBar, "paper-bar"},
     {ControlBuiltin::Box, "box"},
     {ControlBuiltin::Grid2D, "grid-2d"}});
inline constexpr auto kMeshFormatNames = name_table<MeshFormat>(
    {{MeshFormat::Obj, "obj"}, {MeshFormat::Ply, "ply"}, {MeshFormat::Glb, "glb"}, {MeshFormat::None, "none"}});
inline constexpr auto kGpuUseNames =
    name_table<GpuUse>({{GpuUse::Auto, "auto"}, {GpuUse::On, "on"}, {GpuUse::Off, "off"}});
inline constexpr auto kColliderShapeNames = name_table<pipeline::ColliderShape>(
    {{pipeline::ColliderShape::Plane, "plane"},
     {pipeline::ColliderShape::Sphere, "sphere"},
     {pipeline::ColliderShape::Box, "box"},
     {pipeline::ColliderShape::Capsule, "capsule"},
     {pipeline::ColliderShape::Mesh, "mesh"}});
inline constexpr auto kHandleModeNames = name_table<interp::HandleMode>(
    {{interp::HandleMode::Hard, "hard"}, {interp::HandleMode::Soft, "soft"}});

/// The tables' names of single values ("" for the builtins' None).
inline const char* mode_name(Mode m) { return kModeNames.name(m); }
inline const char* builtin_name(DenseBuiltin b) { return kDenseBuiltinNames.name(b); }
inline const char* builtin_name(ControlBuiltin b) { return kControlBuiltinNames.name(b); }
inline const char* format_name(MeshFormat f) { return kMeshFormatNames.name(f); }
inline const char* gpu_name(GpuUse g) { return kGpuUseNames.name(g); }

/// Dense model: a file (path relative to the scene file) or a built-in procedural mesh.
struct DenseSpec {
  std::filesystem::path path;  ///< empty when builtin is set
  DenseBuiltin builtin = DenseBuiltin::None;
  int subdivide = 0;           ///< Loop subdivision steps (OpenMesh), 3D surfaces only
  std::filesystem::path image; ///< 2D: PNG texture (relative to the scene file); "" = checker
  int grid = 128;              ///< 2D image grid: cells along the longer side
};

/// Control mesh: a file, a built-in, or generated around the dense model.
struct ControlSpec {
  std::filesystem::path path;  ///< TetGen .node/.ele (or base) or Gmsh .msh
  ControlBuiltin builtin = ControlBuiltin::None;
  int generate_vertices = 0;   ///< > 0: generate a control mesh of about this many vertices
  generate::Mesher mesher = generate::Mesher::Voxel;  ///< how a control mesh is generated
  Eigen::Vector3i cells{2, 2, 8};  ///< for builtin "box" / "grid-2d" (z ignored in 2D)
};

/// sim::Material with the scene file's defaults: E = 1e6 Pa, nu = 0.45, rho = 1000 kg/m^3.
inline sim::Material scene_material() { return {.youngs_modulus = 1e6, .poisson_ratio = 0.45, .density = 1000}; }

/// sim::Parameters with the scene file's defaults: one step of 1/30 s a frame, no gravity.
inline sim::Parameters scene_parameters() {
  sim::Parameters p;
  p.dt = 1.0 / 30.0;
  p.gravity.setZero();
  return p;
}

/// Node selection: an axis-aligned box, a half-space, or explicit indices (any combination is a
/// union).
struct Selection {
  std::optional<std::pair<Eigen::Vector3d, Eigen::Vector3d>> box;        ///< min, max
  std::optional<std::pair<Eigen::Vector3d, Eigen::Vector3d>> half_space; ///< point, normal: n.(x-p) >= 0
  /// Box in fractions of the control mesh's bounding box (0 = min, 1 = max per axis), so that a
  /// scene works with any model given by --mesh.
  std::optional<std::pair<Eigen::Vector3d, Eigen::Vector3d>> box_relative;
  std::vector<int> indices;
  std::string where;  ///< "<file>:<line>" for error messages
};

/// Time stepping: the simulator's parameters themselves, and the length of a run. The keys of
/// [simulation] fill them: dt, substeps, newton_iterations, gravity; damping_mass and
/// damping_stiffness are mass_damping and stiffness_damping; ground = h is a ground plane y = h
/// (contact = control: the simulator's, on the control nodes; contact = surface: a plane
/// collider, the last of Scene::colliders).
struct SimulationSpec {
  sim::Parameters parameters = scene_parameters();
  int frames = 120;
  pipeline::ContactMode contact = pipeline::ContactMode::Control;
  /// contact = surface: N/m per point (unset: pipeline::default_contact_stiffness), and the dense
  /// vertices that touch (unset: all)
  std::optional<double> contact_stiffness;
  std::optional<Selection> contact_select;
  /// contact = surface: the guarded depth (m, > 0) and friction's eps_v (m/s);
  /// unset: SurfaceContact's defaults (method.md facts 16 and 17)
  std::optional<double> contact_max_depth, contact_friction_velocity;
  /// m/s; unset: 0 (every Newton iteration runs) with contact = control, 1e-5 of the dense
  /// model's diagonal per substep with contact = surface (surface_newton_tolerance)
  std::optional<double> newton_tolerance;
};

/// newton_iterations when a surface-contact scene does not give it: Newton to its tolerance.
inline constexpr int kSurfaceNewtonIterations = 20;
/// The Newton tolerance (m/s) of a surface-contact scene that does not give one: the last update
/// moves no node by more than 1e-5 of the dense model's diagonal (m) in a substep of h (s).
inline double surface_newton_tolerance(double diagonal, double h) { return 1e-5 * diagonal / h; }

struct ConstraintSpec {
  enum class Kind { Fixed, Kinematic } kind = Kind::Fixed;
  Selection select;
  /// Kinematic only: the keys of `motion` fill it (twist_center, twist_axis and twist_rate are
  /// center, axis and angular_velocity). The scene file's defaults: about z, no stop (1e30 s).
  sim::RigidMotion motion{.axis = Eigen::Vector3d::UnitZ(), .stop = 1e30};
};
inline constexpr auto kConstraintKindNames = name_table<ConstraintSpec::Kind>(
    {{ConstraintSpec::Kind::Fixed, "fixed"}, {ConstraintSpec::Kind::Kinematic, "kinematic"}});

/// A scripted poke: a constant force (N) or a spring (N/m) toward a target, on frames
/// [first, last], at a material point: `point` in rest coordinates, or `at` in fractions of the
/// dense model's bounding box (the dense vertex nearest to it is poked).
struct PokeSpec {
  int first = 0, last = 0;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  bool relative = false;  ///< point holds the `at` fractions
  bool target_relative = false;  ///< target is an offset from the poked point (m)
  /// `offset_relative`: the offset is in units of the dense model's size (its bounding-box
  /// diagonal), so a scene pokes a 15 cm model and a 6 m one alike
  bool offset_in_sizes = false;
  std::optional<Eigen::Vector3d> force;
  std::optional<Eigen::Vector3d> target;
  double stiffness = 0.0;
};

/// A dragged control vertex (no physics; paper Eq. 10/11): keyframes (frame, displacement from
/// the vertex's rest position) linearly interpolated, held before the first and after the last.
struct DragSpec {
  int vertex = -1;                      ///< control vertex index, or -1 with `near` / `select`
  std::optional<Eigen::Vector3d> near;  ///< pick the control vertex nearest to this point
  std::optional<Selection> select;      ///< every selected control vertex, same displacement
  std::vector<std::pair<double, Eigen::Vector3d>> keys;
};

struct InterpolationSpec {
  pipeline::Method method = pipeline::Method::ModifiedBI;
  /// alpha (0 = default: 0.1 in 3D, 0.2 in 2D) and pin_boundary; the rest at their defaults
  interp::Options options;
  bool compare_pinned = false;         ///< 2D drag scenes: also write the pinned variant
  interp::HandleMode handles = interp::HandleMode::Hard;  ///< drag scenes: Eq. 10 or Eq. 11
  GpuUse gpu = GpuUse::Auto;
};

struct OutputSpec {
  int every = 10;                  ///< write meshes every N frames (and the last)
  MeshFormat mesh_format = MeshFormat::Obj;
  bool pc2 = true;
  bool control_vtk = true;
  bool metrics = true;
  bool image = true;               ///< PNG pictures of written frames
  bool creases = false;            ///< 3D pictures coloured by the gradient jump (creases.hpp)
  Eigen::Vector3d up{0.0, 1.0, 0.0};  ///< 3D pictures: the direction shown upwards
};

/// A [[colliders]] entry with shape = "mesh": the file of its closed triangle mesh and the
/// options of its level set. Scene::colliders[index] is that collider, placed and moving as the
/// entry says; read_collider_meshes gives it the level set built from the file.
struct ColliderMesh {
  std::size_t index = 0;        ///< into Scene::colliders
  std::filesystem::path path;   ///< as written: relative paths start at the scene file's folder
  pipeline::MeshLevelSetOptions options;
  std::string where_path;       ///< "<file>:<line>" of the entry's path, for messages
  std::string where_voxel_size; ///< of its voxel_size (of path when not given)
};

struct Scene {
  std::filesystem::path file;  ///< the scene file itself
  std::string name;
  Mode mode = Mode::Simulate;
  DenseSpec dense;
  /// [[dense]] entries after the first: more dense models (files) driven by the same control
  /// mesh, each written on its own ([dense] alone leaves this empty).
  std::vector<DenseSpec> more_dense;
  ControlSpec control;
  sim::Material material = scene_material();
  SimulationSpec simulation;
  std::vector<ConstraintSpec> constraints;
  std::vector<PokeSpec> pokes;
  std::vector<DragSpec> drags;
  /// [[colliders]] (contact = surface), then the ground plane when simulation.ground is given
  std::vector<pipeline::Collider> colliders;
  /// the colliders with shape = "mesh" (their level sets built by read_collider_meshes)
  std::vector<ColliderMesh> collider_meshes;
  InterpolationSpec interpolation;
  OutputSpec output;
};

/// Deepest nesting of arrays and inline tables a scene file may have (a scene needs 3), and the
/// most parts a dotted key may have. Deeper files are refused, naming the line, before the TOML
/// parser (recursive) runs.
inline constexpr int kMaxSceneNesting = 16;

/// Reads and checks a scene file (a regular file: a directory, FIFO or device is refused), and
/// builds the level sets of its mesh colliders from the files they name (read_collider_meshes).
/// Throws Error naming file, line and key.
Scene load_scene(const std::filesystem::path& file);
/// The scene of a text; `file` names it in messages and is where relative paths of the scene
/// start from. Nothing is read from disk: mesh colliders are placed but have no level set until
/// read_collider_meshes (make_pipeline reads those still missing).
Scene parse_scene(std::string_view text, const std::filesystem::path& file);

/// The level set of a mesh collider, built from its file (pipeline::MeshLevelSet: well under a
/// second at the default voxel size). Throws Error "<file>:<line>: colliders[i].<key>: ..." for
/// a file that cannot be read, a mesh that is not closed, a voxel size too small for the mesh;
/// in a build without model files (the page) the refusal of model_files.hpp.
std::shared_ptr<const pipeline::MeshLevelSet> read_collider_mesh(const Scene& scene, const ColliderMesh& mesh);
/// Gives every mesh collider of the scene that has none its level set (read_collider_mesh).
void read_collider_meshes(Scene& scene);

/// A path of the scene (dense.path, control.path, ...): relative paths start at the scene file's
/// folder.
std::filesystem::path resolve_path(const Scene& scene, const std::filesystem::path& p);

/// Nodes of U (n x d) selected by s (sorted, unique). Throws Error if an index is out of
/// range or nothing is selected.
std::vector<int> select_nodes(const Selection& s, const Eigen::Ref<const Eigen::MatrixXd>& U);

/// A number in the messages and names of scenes: three significant digits.
inline std::string format_num(double x) {
  char b[64];
  std::snprintf(b, sizeof b, "%.3g", x);
  return b;
}

}  // namespace mbi::scenes
