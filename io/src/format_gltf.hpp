#pragma once
// glTF 2.0 (.gltf, .glb): what a read asset keeps so that a writer can give it back, and the
// functions the format table calls. Reading: format_gltf_read.cpp (tinygltf); writing:
// format_gltf_write.cpp (our own JSON and GLB layout, see docs/cli.md "glTF").
#include "io_common.hpp"

#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace mbi::io {
struct SurfaceAttributes;
namespace detail {

struct SurfaceOutput;
using Polygons = std::vector<std::vector<int>>;

/// One mesh primitive as placed in the scene (a mesh used by two nodes gives two parts): a run
/// of the SurfaceMesh's vertices and of its triangles, with what it holds besides positions.
struct GltfPart {
  std::string name;  ///< the node's name, or "node N"
  long long first_vertex = 0, vertices = 0;
  long long first_face = 0, faces = 0;  ///< rows of SurfaceMesh::F
  int material = -1;                    ///< index into GltfAsset::materials; -1: none
  std::vector<float> uv0, uv1;          ///< TEXCOORD_0/1: vertices x 2, or empty
  std::vector<float> color;             ///< COLOR_0 as RGBA: vertices x 4, or empty
};

/// Everything besides geometry that is written back: the parts and the file's materials with
/// the textures, samplers and images they name (JSON arrays as text, as in the file; images
/// stored in the binary buffer are kept as bytes and written into the output's buffer).
struct GltfAsset {
  std::vector<GltfPart> parts;
  std::string materials = "[]", textures = "[]", samplers = "[]", images = "[]";
  std::vector<std::string> image_mime;                ///< per image, for bufferView images
  std::vector<std::vector<unsigned char>> image_bytes;  ///< per image: bytes, or empty (a uri)
  std::vector<std::string> extensions_used, extensions_required;  ///< those the materials use
  /// Per written vertex, the mesh vertex it copies (an OBJ's vertices split where the corners
  /// that share one differ in UV); empty: the mesh's vertices as they are.
  std::vector<int> source;
  /// With `source`: the triangles in written vertices, part after part.
  Polygons triangles;
  /// What did not map (an OBJ's MTL keys without a PBR counterpart), for the user.
  std::vector<std::string> notes;
};

SurfaceMesh parse_gltf(std::string_view data, const std::filesystem::path& file);
/// One static frame (see GltfWriter in io.hpp).
void write_gltf(std::FILE* f, const SurfaceOutput& out);
/// Whether `a` fits `faces` (triangles): read from a glTF file, every face inside one part's
/// vertices; read from an OBJ or PLY file, converts_to_gltf.
bool gltf_attributes_fit(const SurfaceAttributes& a, const Polygons& faces);
/// Whether `a` read from an OBJ (faces fan-triangulated into `triangles`) or a PLY file gives a
/// glTF asset (gltf_asset_of).
bool converts_to_gltf(const SurfaceAttributes& a, const Polygons& triangles);
/// The glTF asset of attributes that fit (gltf_attributes_fit) `triangles` of a mesh of
/// `vertices` vertices: a glTF's own; an OBJ's UVs, groups and MTL materials (format_gltf_convert.cpp,
/// textures named by URIs relative to `output`'s folder); a PLY's vertex colours. Null otherwise.
std::shared_ptr<const GltfAsset> gltf_asset_of(const SurfaceAttributes& a, const Polygons& triangles, long long vertices,
                                               const std::filesystem::path& output);

}  // namespace detail
}  // namespace mbi::io
