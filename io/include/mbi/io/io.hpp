#pragma once
// File formats of mbi, each in its own file of src/ (format_*.cpp), chosen by extension through
// one table (src/formats.cpp; file_format below):
//   dense surfaces  OBJ, OFF (ASCII), PLY (ASCII, binary of either endianness), STL (ASCII,
//                   binary), glTF 2.0 (.gltf, .glb): read and written
//   point lists     .txt, .xyz: read and written
//   control meshes  TetGen .node/.ele: read and written, .face: written; Gmsh .msh 2.2, 4.0 and
//                   4.1, ASCII or binary: read; legacy VTK .vtk 2.0-5.1, ASCII or BINARY: read,
//                   ASCII: written; VTK XML .vtu (ASCII, base64, raw appended, zlib): read
//   animation       OBJ/PLY frame sequences, glTF animations: written; PC2 and MDD point caches: read and
//                   written; ParaView .pvd collections: read; control trajectories (Trajectory)
// PNG images are read and written by image.hpp.
//
// Conventions: positions are n x d Eigen::MatrixXd (d = 2 or 3), elements m x (d+1) 0-based
// Eigen::MatrixXi, as in mbi::interp. Units are whatever the file uses (no scaling).
//
// Errors: every function throws Error. The message starts with "<file>:<line>: " when a line
// of a text file is at fault, "<file>: " otherwise, and names the field (header count, vertex,
// face, element, index) at fault. Counts in headers are checked against the size of the file
// before anything is allocated for them. Non-finite coordinates are rejected.
//
// Writers never leave a half-written file: they write through AtomicFile (atomic_file.hpp), a
// temporary file in the same folder renamed over the target at the end. Text writers print
// reals with %.17g, so reading a written file gives back the same doubles bit for bit.
#include <mbi/error.hpp>

#include <Eigen/Core>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace mbi::io {

/// Every error of the IO functions (message: "<file>[:<line>]: <what is wrong>").
class Error : public mbi::Error {
 public:
  using mbi::Error::Error;
};

class AtomicFile;

// ----------------------------------------------------------------------------------------------
// Formats by extension
// ----------------------------------------------------------------------------------------------

/// What a file of a format holds.
enum class FileKind {
  surface,  ///< a dense surface: read_surface, write_surface
  control,  ///< a control mesh, or positions of its nodes: read_control_mesh, read_positions
  points,   ///< a point list: read_points, write_points
  cache,    ///< an animation cache: read_pc2, Pc2Writer, read_mdd, MddWriter
  collection,  ///< a list of files over time: read_pvd
};

/// One format of the table.
struct FileFormat {
  const char* extension;  ///< lower case, with its dot: ".obj"
  const char* name;       ///< for people: "Wavefront OBJ"
  FileKind kind;
};

/// The format of `file`'s extension (any case); nullptr for an extension not in the table.
const FileFormat* file_format(const std::filesystem::path& file);
/// The extensions of one kind in table order, for messages: ".obj, .off, .ply or .stl".
std::string extensions_of(FileKind kind);
/// True for the extensions read_surface reads (.obj, .off, .ply, .stl, any case).
bool is_surface_file(const std::filesystem::path& file);

/// The file's extension in lower case, with its dot (".obj"; "" when there is none): how every
/// reader and writer picks a format.
std::string lower_extension(const std::filesystem::path& file);

// ----------------------------------------------------------------------------------------------
// Dense surfaces
// ----------------------------------------------------------------------------------------------

/// Everything a surface file holds besides positions, faces and normals, kept so that a writer
/// of the same format can write it back (defined in the implementation; see read_surface).
struct SurfaceAttributes;

/// A surface mesh as stored in a file. Vertex order and count are exactly the file's: vertices
/// that no face uses, duplicated positions, holes, several components and non-manifold faces
/// are all kept as they are.
struct SurfaceMesh {
  Eigen::MatrixXd V;  ///< n x 3 vertex positions (file order)
  Eigen::MatrixXi F;  ///< t x 3 triangles, 0-based; polygons are fan-triangulated (v0, vk, vk+1)
  /// Faces as written in the file (0-based, any size >= 3). Writers use these when non-empty
  /// (so polygons are written back unchanged), otherwise F.
  std::vector<std::vector<int>> polygons;
  /// n x 3 unit vertex normals, or empty (0 x 0) when the file has none. OBJ: a vertex takes
  /// the `vn` of the first face corner that names it (corners of one vertex with different
  /// normals, i.e. hard edges, are merged that way); vertices that no corner gives a normal get
  /// the area-weighted normal of their faces. PLY: properties nx, ny, nz. Writers write these
  /// (OBJ: one `vn` per vertex, referenced by every face corner; PLY: nx, ny, nz); they depend
  /// on positions, so a deformed mesh should carry deformed normals (or none).
  Eigen::MatrixXd N;
  /// What the file held besides that (null for meshes not read from a file): its format and
  /// encoding, and OBJ: texture coordinates `vt` and the corners' vt indices, `g`, `o`,
  /// `usemtl`, `mtllib`, `s` and other records in file order, extra numbers of `v` lines
  /// (vertex colours); PLY: every property and element, header comments, endianness; STL: the
  /// 80-byte header and the attribute word of each triangle, or the solid's name. Comments of
  /// OBJ files are not kept. A writer of the same format writes all of it back (positions and
  /// normals replaced) as long as the vertex count and the faces' sizes still match the file's;
  /// otherwise, or for another format, only positions, faces and normals are written.
  std::shared_ptr<const SurfaceAttributes> attributes;
};

/// Reads .obj, .off, .ply (ASCII or binary, little or big endian) or .stl (ASCII or binary),
/// chosen by extension (case-insensitive). OBJ: "v" and "f" lines (v, v/t, v//n, v/t/n, negative
/// relative indices), "vn" for N; other records are kept in `attributes`. OFF: ASCII, positions
/// and faces. PLY: vertex x,y,z of any scalar type, face "vertex_indices"/"vertex_index" list,
/// nx,ny,nz for N; every property and element is kept in `attributes`. STL has no shared
/// vertices: the corners of its triangles are merged when bitwise equal, in order of first
/// appearance (STL stores float32).
SurfaceMesh read_surface(const std::filesystem::path& file);

/// Area-weighted unit vertex normals (n x 3) of the triangles F (t x 3, 0-based) of V (n x 3);
/// finite for any finite coordinates (a far-out vertex gets the sum of its faces' unit normals),
/// (0, 0, 1) for a vertex without area. The readers complete missing normals with the same.
Eigen::MatrixXd vertex_normals(const Eigen::Ref<const Eigen::MatrixXd>& V, const Eigen::Ref<const Eigen::MatrixXi>& F);

/// ascii / binary: as named (binary: PLY keeps the endianness of a binary file it was read
/// from, little endian otherwise). as_read: the encoding of the file the mesh was read from
/// when it has the output's format, ASCII otherwise.
enum class Encoding { ascii, binary, as_read };

/// Writes `mesh` to .obj, .off, .ply or .stl (by extension), with its normals N when present
/// and its `attributes` when they came from a file of the same format (see SurfaceMesh). PLY
/// written fresh: float64 coordinates and normals, int32 indices; with attributes every
/// property keeps its type. Binary STL: float32, the format's only precision. OBJ and OFF are
/// always ASCII. STL writes the triangles F (polygons cannot be stored). A mesh without faces
/// writes its vertices only (OBJ: `v` lines). Throws Error on out-of-range indices or
/// non-finite positions (nothing written).
void write_surface(const std::filesystem::path& file, const SurfaceMesh& mesh,
                   Encoding encoding = Encoding::as_read);
/// Same, from plain arrays: V n x 3, F t x 3 (0-based).
void write_surface(const std::filesystem::path& file, const Eigen::Ref<const Eigen::MatrixXd>& V,
                   const Eigen::Ref<const Eigen::MatrixXi>& F, Encoding encoding = Encoding::ascii);

// ----------------------------------------------------------------------------------------------
// Point lists (.txt, .xyz): one point per line, d numbers separated by blanks or commas; blank
// lines and '#' comments are allowed. Every line must have the same count d.
// ----------------------------------------------------------------------------------------------

/// n x d. An empty file gives a 0 x 0 matrix.
Eigen::MatrixXd read_points(const std::filesystem::path& file);
/// One row per line, %.17g.
void write_points(const std::filesystem::path& file, const Eigen::Ref<const Eigen::MatrixXd>& P);

// ----------------------------------------------------------------------------------------------
// Control meshes
// ----------------------------------------------------------------------------------------------

/// A control mesh as read from TetGen or Gmsh files.
struct ControlMesh {
  Eigen::MatrixXd U;             ///< n x d rest positions, d = 2 or 3
  Eigen::MatrixXi T;             ///< m x (d+1) elements (triangles / tetrahedra), 0-based
  /// What the reader changed or left out that a user should be told (e.g. higher-order
  /// elements used by their corners), one line each, starting with the file name.
  std::vector<std::string> notes;
  int dim() const { return static_cast<int>(U.cols()); }
};

/// Reads a control mesh from TetGen files, a Gmsh, a legacy VTK or a VTK XML file, chosen by
/// extension: ".msh" -> Gmsh, ".vtk" -> VTK, ".vtu" -> VTK XML, anything else (".node", ".ele", ".face", none, "box.1") ->
/// TetGen base name (.face itself is not read).
ControlMesh read_control_mesh(const std::filesystem::path& file);
/// The files read_control_mesh(file) reads: BASE.node and BASE.ele for TetGen, else `file`.
std::vector<std::filesystem::path> control_mesh_files(const std::filesystem::path& file);
/// Positions of every node of a control mesh file, in file order, as deformed positions for the
/// mesh read_control_mesh reads: ".node" -> read_node (n x d), ".msh" -> read_gmsh_nodes,
/// ".vtk" -> read_vtk_points, ".vtu" -> read_vtu_points (n x 3); any other file is a point list
/// (read_points).
Eigen::MatrixXd read_positions(const std::filesystem::path& file);

/// TetGen: `path` is the base name or any of BASE.node / BASE.ele / BASE.face. Reads BASE.node
/// and BASE.ele only: the boundary follows from the elements, so a BASE.face (or .edge, .neigh)
/// beside them, stale or not, is never read. Point numbering may start at 0 or 1 (the first
/// point's number decides; numbers must then be consecutive); attributes and boundary markers
/// are read past. 2D: .node with dimension 2 and .ele with 3 (or 6) nodes per triangle.
/// 10-node tetrahedra keep their 4 corners.
ControlMesh read_tetgen(const std::filesystem::path& path);
/// Positions only, from a .node file (e.g. deformed positions X): n x d.
Eigen::MatrixXd read_node(const std::filesystem::path& file);
/// Writes BASE.node and BASE.ele (0-based numbering, no attributes, no markers), and BASE.face
/// when `faces` has rows (3D only). `base` may also end in .node/.ele.
void write_tetgen(const std::filesystem::path& base, const Eigen::Ref<const Eigen::MatrixXd>& U,
                  const Eigen::Ref<const Eigen::MatrixXi>& T,
                  const Eigen::Ref<const Eigen::MatrixXi>& faces = Eigen::MatrixXi(0, 3));
/// Writes one .node file (0-based): n x d positions.
void write_node(const std::filesystem::path& file, const Eigen::Ref<const Eigen::MatrixXd>& X);

/// Gmsh .msh, format 2.2, 4.0 or 4.1, ASCII or binary (either endianness). Nodes: every node of
/// the file in file order, also those no element uses (so that deformed positions given per
/// file node, e.g. read_gmsh_nodes, map 1:1), like TetGen's .node. Tetrahedra of any order
/// (types 4, 11, 29-31) make a 3D mesh, used by their 4 corners; without tetrahedra, triangles
/// of any order (2, 9, 20-25) make a 2D mesh (all nodes must then have the same z, which is
/// dropped). Higher-order elements are reported in `notes`. Other element types and sections
/// (physical names, entities, parametric coordinates of -save_parametric) are skipped; when no
/// usable element is found the message lists what was.
ControlMesh read_gmsh(const std::filesystem::path& file);
/// Every node of a .msh file in file order, n x 3 (deformed positions for a mesh read by
/// read_gmsh).
Eigen::MatrixXd read_gmsh_nodes(const std::filesystem::path& file);

/// Legacy VTK unstructured grid (format 2.0-5.1, ASCII or BINARY), as written by write_vtk,
/// meshio or VTK: every point in file order; tetrahedra (cell type 10, quadratic 24 by its
/// corners, reported in `notes`) make a 3D mesh, else triangles (5, 22) a 2D one (z constant,
/// dropped). Other cells and all point/cell data are skipped.
ControlMesh read_vtk_mesh(const std::filesystem::path& file);
/// The POINTS of a legacy VTK file, n x 3 (deformed positions for a mesh read by read_vtk_mesh).
Eigen::MatrixXd read_vtk_points(const std::filesystem::path& file);

/// VTK XML unstructured grid (.vtu), as written by VTK, ParaView, meshio, FEniCS or deal.II: one
/// Piece; DataArrays in any of the format's encodings (format="ascii", "binary" (inline base64),
/// "appended" with AppendedData encoding="raw" or "base64"), either byte_order, header_type
/// UInt32 or UInt64, uncompressed or compressor="vtkZLibDataCompressor" (other compressors are
/// named and refused). Cells as read_vtk_mesh (connectivity, offsets, types); PointData and
/// CellData are skipped. Messages name the line of the XML element at fault.
ControlMesh read_vtu_mesh(const std::filesystem::path& file);
/// The Points of a .vtu file, n x 3 (deformed positions for a mesh read by read_vtu_mesh).
Eigen::MatrixXd read_vtu_points(const std::filesystem::path& file);

/// A point data array of a VTK file: its name and values, n x components (points x components).
struct PointField {
  std::string name;
  Eigen::MatrixXd values;
};
/// The points of a VTK file with its point data.
struct PointData {
  Eigen::MatrixXd P;                ///< n x 3, as read_vtu_points / read_vtk_points
  std::vector<PointField> fields;  ///< in file order
};
/// The Points and every point data array of a .vtu (PointData, in every encoding read_vtu_mesh
/// reads) or a legacy .vtk (POINT_DATA: SCALARS, VECTORS, NORMALS, TENSORS, TEXTURE_COORDINATES,
/// COLOR_SCALARS and FIELD arrays of n tuples, ASCII or BINARY, up to a METADATA block). Error
/// naming the file for any other extension.
PointData read_point_data(const std::filesystem::path& file);
/// read_positions(file) plus the point field `displacement` of a .vtu or .vtk file (FEniCS's and
/// deal.II's rest mesh with a displacement): n x 3, the field of n tuples of 3 components (or 2:
/// z unchanged). Error naming the file and the field when the file has no such field, its size
/// is not n x 2 or n x 3, a value is not finite, or the file is not a .vtu or .vtk.
Eigen::MatrixXd read_positions(const std::filesystem::path& file, const std::string& displacement);

/// Legacy VTK unstructured grid (ASCII, for ParaView): tetrahedra (cell type 10) or triangles
/// (type 5, z = 0). Optional per-point vectors (n x d, e.g. displacements) named `point_data`.
void write_vtk(const std::filesystem::path& file, const Eigen::Ref<const Eigen::MatrixXd>& U,
               const Eigen::Ref<const Eigen::MatrixXi>& T,
               const Eigen::Ref<const Eigen::MatrixXd>& point_vectors = Eigen::MatrixXd(0, 3),
               const std::string& point_data = "displacement");

// ----------------------------------------------------------------------------------------------
// Animation output
// ----------------------------------------------------------------------------------------------

/// "<base>_<frame, zero-padded to `digits`><ext>", e.g. frame_path("out/bunny", 7, ".obj") ->
/// "out/bunny_0007.obj". Throws Error on a negative frame.
std::filesystem::path frame_path(const std::filesystem::path& base, int frame,
                                 const std::string& ext, int digits = 4);
/// Writes one frame of a sequence: the positions V (n x 3) and normals N (n x 3, or empty: no
/// normals) with the faces and attributes of `topology` (see write_surface) to
/// frame_path(base, frame, ext); ext is ".obj" or ".ply". Returns the path written.
std::filesystem::path write_frame(const std::filesystem::path& base, int frame,
                                  const std::string& ext, const SurfaceMesh& topology,
                                  const Eigen::Ref<const Eigen::MatrixXd>& V,
                                  Encoding encoding = Encoding::as_read,
                                  const Eigen::Ref<const Eigen::MatrixXd>& N = Eigen::MatrixXd());

/// glTF 2.0 animation (.glb, or .gltf with the buffer inside as base64) of a deformed surface:
/// one node per frame, each with a mesh of every part (a mesh read from a glTF keeps its parts,
/// materials, UVs and colours; one read from an OBJ has a part per group and material, its UVs,
/// its vertices split where corners differ in UV (every frame's positions copied to the split),
/// and its MTL materials as PBR materials where they map (Kd, map_Kd as a URI relative to the
/// output, d/Tr as BLEND); a PLY keeps its vertex colours; any other mesh is one part), shown in turn by step-keyed node
/// scale, which Blender's and three.js's importers play back. Positions and normals are stored
/// as float32 (a relative error of at most 2^-24 a coordinate), indices, UVs and colours once
/// for all frames. The frames are kept in memory (12 bytes a vertex, 24 with normals) and
/// written by finish(); a file past 4 GB (the .glb limit) is refused at the frame that would
/// pass it. Destroyed before finish(), nothing is written.
class GltfWriter {
 public:
  /// `topology`: the faces and attributes of the frames to come (positions unused).
  GltfWriter(const std::filesystem::path& file, const SurfaceMesh& topology);
  ~GltfWriter();
  GltfWriter(const GltfWriter&) = delete;
  GltfWriter& operator=(const GltfWriter&) = delete;

  /// One frame at `time` (s, after the previous frame's): V n x 3, N n x 3 or empty (no
  /// normals; the same for every frame). Throws Error (nothing kept of this frame).
  void append(double time, const Eigen::Ref<const Eigen::MatrixXd>& V,
              const Eigen::Ref<const Eigen::MatrixXd>& N = Eigen::MatrixXd());
  /// Writes the frames appended so far, atomically.
  void finish();
  int samples() const;
  /// What of the input's attributes did not map to glTF (an OBJ's MTL keys without a PBR
  /// counterpart, a missing material library or texture), one line each, for the user.
  const std::vector<std::string>& notes() const;

 private:
  struct State;
  std::filesystem::path file_;
  std::unique_ptr<State> state_;
};

/// PC2 point cache (Blender "Mesh Cache" modifier): header "POINTCACHE2\0", int32 version 1,
/// int32 numPoints, float32 startFrame, float32 sampleRate, int32 numSamples, then float32 x,y,z
/// per point per sample, all little endian. Frames are appended as they come to a temporary
/// file; finish() fixes numSamples and renames it to the target. If the writer is destroyed
/// before finish() (e.g. by an exception), the temporary file is removed and the target is left
/// untouched.
class Pc2Writer {
 public:
  Pc2Writer(const std::filesystem::path& file, int num_points, float start_frame = 0.0f,
            float sample_rate = 1.0f);
  ~Pc2Writer();
  Pc2Writer(const Pc2Writer&) = delete;
  Pc2Writer& operator=(const Pc2Writer&) = delete;

  /// Appends one sample: P is numPoints x 3 (or x 2: z = 0), finite. All of it or, on a write
  /// error (Error: a full disk), none: the file keeps exactly samples() samples.
  void append(const Eigen::Ref<const Eigen::MatrixXd>& P);
  /// The same from numPoints x 3 finite floats, row after row (interleaved x y z).
  void append(const float* xyz);
  /// Writes numSamples into the header, flushes, and moves the file into place.
  void finish();
  int samples() const { return samples_; }

 private:
  std::filesystem::path file_;
  std::unique_ptr<AtomicFile> out_;
  int num_points_ = 0;
  int samples_ = 0;
};

/// A PC2 or MDD file read back (float32 values widened to double; non-finite values refused).
struct PointCache {
  float start_frame = 0.0f;  ///< PC2
  float sample_rate = 1.0f;  ///< PC2
  std::vector<float> times;  ///< MDD: each frame's time (s); empty for PC2
  std::vector<Eigen::MatrixXd> frames;  ///< numSamples matrices of numPoints x 3
};
PointCache read_pc2(const std::filesystem::path& file);

/// MDD point cache (Blender's MDD import/export and Mesh Cache modifier, Houdini, 3ds Max,
/// LightWave): int32 numFrames, int32 numPoints, float32 time (s) of each frame, then float32
/// x,y,z per point per frame, all big endian. Frames are appended to a temporary file as they
/// come; finish() moves it into place. Destroyed before finish(), it removes the temporary.
class MddWriter {
 public:
  /// `times`: the time of each frame to come (their count is the most frames append() takes).
  MddWriter(const std::filesystem::path& file, int num_points, std::vector<float> times);
  ~MddWriter();
  MddWriter(const MddWriter&) = delete;
  MddWriter& operator=(const MddWriter&) = delete;

  /// Appends one frame: P is numPoints x 3 (or x 2: z = 0), finite as float32.
  void append(const Eigen::Ref<const Eigen::MatrixXd>& P);
  /// The same from numPoints x 3 floats, row after row (interleaved x y z, host byte order).
  void append(const float* xyz);
  /// Writes a file of the frames appended so far (fewer than announced: the header and times
  /// say so) and moves it into place.
  void finish();
  int samples() const { return samples_; }

 private:
  std::filesystem::path file_;
  std::unique_ptr<AtomicFile> out_;
  int num_points_ = 0;
  int samples_ = 0;
  std::vector<float> times_;
  std::vector<char> buffer_;  // one frame, big endian
};

/// Reads an MDD file. A file holding one frame more than its header counts (Blender's exporter
/// writes the rest pose first) has that first frame skipped.
PointCache read_mdd(const std::filesystem::path& file);

/// A PC2 or MDD point cache (by extension) read one frame at a time, so that memory holds one
/// frame whatever the length. The header is checked against the file's size when opened.
class PointCacheReader {
 public:
  explicit PointCacheReader(const std::filesystem::path& file);
  ~PointCacheReader();
  PointCacheReader(const PointCacheReader&) = delete;
  PointCacheReader& operator=(const PointCacheReader&) = delete;

  int points() const { return points_; }
  int frames() const { return frames_; }
  const std::filesystem::path& file() const { return file_; }
  /// PC2: the header's start frame and sample rate; MDD: 0 and 1.
  float start_frame() const { return start_frame_; }
  float sample_rate() const { return sample_rate_; }
  /// MDD: each frame's time (s), read on the first call (Error naming the file past 2^24
  /// frames); PC2: empty.
  const std::vector<float>& times();
  bool has_times() const { return times_offset_ > 0; }
  /// Frame k (0-based), points() x 3. Throws Error "<file>: frame k: point i: ..." on a
  /// non-finite coordinate or a file that changed under us.
  Eigen::MatrixXd frame(int k);

 private:
  std::filesystem::path file_;
  std::FILE* in_ = nullptr;
  int points_ = 0, frames_ = 0;
  bool big_endian_ = false;
  unsigned long long data_offset_ = 0;
  float start_frame_ = 0.0f, sample_rate_ = 1.0f;
  unsigned long long times_offset_ = 0;  // MDD: where the times are
  std::vector<float> times_;
  bool times_read_ = false;
  std::string buffer_;
};

/// One dataset of a ParaView collection.
struct PvdEntry {
  double time = 0;             ///< its timestep
  std::filesystem::path file;  ///< relative names resolved against the .pvd's folder
  int line = 0;                ///< its line in the .pvd
};
/// ParaView collection (.pvd: VTKFile type="Collection", DataSet elements with timestep and
/// file), sorted by timestep (stably). Several parts or datasets with one timestep are refused.
/// The files are not opened.
std::vector<PvdEntry> read_pvd(const std::filesystem::path& file);

// ----------------------------------------------------------------------------------------------
// Control trajectories
// ----------------------------------------------------------------------------------------------

/// The file of number k of a printf pattern ("out/m_%04d.obj" -> "out/m_0007.obj"): one %d or
/// %0Nd (N <= 12) in the file name, %% for a percent sign. Throws Error on any other pattern.
std::filesystem::path numbered_file(const std::string& pattern, int k);
/// Whether `name` is a printf pattern: it has a %d or %0Nd; a '%' otherwise ("100%.obj") is
/// part of a plain name.
bool is_numbered_name(const std::string& name);

/// The positions of a control mesh's nodes over time, read one frame at a time, from
///  - a PC2 or MDD point cache (one row per node),
///  - a ParaView collection (.pvd) of .vtu or .vtk files,
///  - numbered files read by read_positions (.node, .vtk, .vtu, .msh, plain text) named by a
///    printf pattern, "x_%04d.vtk" (%d or %0Nd once, %% for a percent sign; numbering starts at
///    0, or at 1 when there is no 0, and goes on up to the first number missing), or by a glob,
///    "x_*.vtk" (* ? [...] in the file name; sorted by name with runs of digits compared as
///    numbers: x_2 before x_10).
/// The list of frames is made when opened; every file named is checked to exist then, so that a
/// missing one is reported before any work.
class Trajectory {
 public:
  /// `displacement`: a point field of every frame added to its positions (read_positions);
  /// frames of a point cache or of text files have none (Error naming the file and the field).
  explicit Trajectory(const std::string& spec, const std::string& displacement = "");
  ~Trajectory();
  Trajectory(Trajectory&&) noexcept;
  Trajectory& operator=(Trajectory&&) noexcept;

  /// Whether `spec` names a trajectory rather than one file of positions: a .pc2, .mdd or .pvd
  /// extension, a printf pattern or glob characters.
  static bool names_trajectory(const std::string& spec);
  int frames() const;
  /// Frame k's positions as the file holds them (n x 3, or n x d for .node and text).
  Eigen::MatrixXd read(int k);
  /// The file of frame k; empty for a point cache.
  std::filesystem::path file(int k) const;
  /// Where frame k comes from, for messages: "x_0007.vtk" or "traj.pc2: frame 7".
  std::string where(int k) const;
  /// Frame times (s) from an MDD or a .pvd; empty otherwise. An MDD's are read on the first
  /// call (Error naming the file past 2^24 frames: memory for them is not taken up front).
  const std::vector<double>& times() const;
  /// Whether it has frame times (an MDD or a .pvd), without reading them.
  bool has_times() const;
  /// The trajectory as given.
  const std::string& spec() const;
  /// A PC2's start frame and sample rate (frames), when read from one.
  std::optional<std::pair<float, float>> pc2_timing() const;
  /// Every file it reads (to keep them from being outputs).
  std::vector<std::filesystem::path> files() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace mbi::io
