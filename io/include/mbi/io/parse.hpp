#pragma once
// Limits of the readers, and the readers of io.hpp / image.hpp on bytes in memory.
//
// Every read_* function of io.hpp is a thin wrapper: it reads the file (regular files only,
// see read_bytes) and calls the parse_* function below with the bytes and the file's name,
// which is used for the format (by extension) and in messages only. The parse_* functions are
// what the fuzz targets (tests/fuzz/) call: they never touch the file system.
//
// What every reader guarantees, whatever the bytes (docs/hardening.md):
//  - it returns a valid mesh or throws Error ("<name>[:<line>]: <what>"), nothing else: no
//    crash, no hang, no read outside the data, no undefined behaviour;
//  - counts in headers are checked against the bytes (or lines) that remain AND against
//    kMaxCount before anything is allocated or looped over for them (an element of a binary
//    PLY with no properties counts one byte per item);
//  - coordinates are finite and at most kMaxCoordinate in magnitude, indices are in range;
//  - text formats accept a UTF-8 byte-order mark, CRLF or CR-LF-mixed line ends, tabs, a
//    missing final newline and lines of any length; memory and time are linear in the size.
#include <mbi/io/image.hpp>
#include <mbi/io/io.hpp>

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

namespace mbi::io {

/// Largest file a reader accepts: 4 GiB.
inline constexpr std::uintmax_t kMaxFileBytes = std::uintmax_t{4} << 30;
/// Largest count of anything (vertices, faces, elements, points, list items) a header may
/// declare: 2^31 - 1, as indices are int. A count must also fit in the bytes that follow it.
inline constexpr long long kMaxCount = 2147483647LL;
/// Largest magnitude of a coordinate: 1e300. Larger finite values (1e308, next to the largest
/// double, where any sum or product overflows) are refused with the file and line, like NaN
/// and inf. Models far out but below this (1e154 and up, where squared distances overflow) are
/// read; the geometry code refuses what it cannot measure, naming the cause.
inline constexpr double kMaxCoordinate = 1e300;
/// Largest width or height of a PNG read: 16384 (as for pictures written).
inline constexpr int kMaxImageSide = 16384;

/// The bytes of a regular file. A directory, FIFO, device (/dev/zero), socket or a file larger
/// than kMaxFileBytes is refused, naming what it is, without blocking (O_NONBLOCK).
std::string read_bytes(const std::filesystem::path& file);

/// read_surface on bytes; the format is that of `name`'s extension.
SurfaceMesh parse_surface(std::string_view data, const std::filesystem::path& name);
/// read_points on bytes.
Eigen::MatrixXd parse_points(std::string_view data, const std::filesystem::path& name);
/// read_node on bytes.
Eigen::MatrixXd parse_node(std::string_view data, const std::filesystem::path& name);
/// read_tetgen on the bytes of BASE.node and BASE.ele (`base`: names in messages).
ControlMesh parse_tetgen(std::string_view node, std::string_view ele,
                         const std::filesystem::path& base);
/// read_gmsh / read_gmsh_nodes on bytes.
ControlMesh parse_gmsh(std::string_view data, const std::filesystem::path& name);
Eigen::MatrixXd parse_gmsh_nodes(std::string_view data, const std::filesystem::path& name);
/// read_vtk_mesh / read_vtk_points on bytes.
ControlMesh parse_vtk_mesh(std::string_view data, const std::filesystem::path& name);
Eigen::MatrixXd parse_vtk_points(std::string_view data, const std::filesystem::path& name);
/// read_vtu_mesh / read_vtu_points on bytes.
ControlMesh parse_vtu_mesh(std::string_view data, const std::filesystem::path& name);
Eigen::MatrixXd parse_vtu_points(std::string_view data, const std::filesystem::path& name);
/// read_pc2 / read_mdd on bytes.
PointCache parse_pc2(std::string_view data, const std::filesystem::path& name);
PointCache parse_mdd(std::string_view data, const std::filesystem::path& name);
/// read_pvd on bytes (relative file names resolved against `name`'s folder).
std::vector<PvdEntry> parse_pvd(std::string_view data, const std::filesystem::path& name);
/// read_png on bytes: PNG only (the 8-byte signature is checked before the decoder runs), at
/// most kMaxImageSide wide and high (checked from the header, before decoding).
Image parse_png(std::string_view data, const std::filesystem::path& name);

}  // namespace mbi::io
