#pragma once
// 8-bit RGB images and PNG files (stb): textures of 2D scenes and rendered pictures.
#include <mbi/io/io.hpp>

#include <Eigen/Core>

#include <cstdint>
#include <filesystem>
#include <vector>

namespace mbi::io {

/// 8-bit RGB image, row 0 at the top.
struct Image {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;  ///< width * height * 3
  Image() = default;
  Image(int w, int h, Eigen::Vector3i background = {255, 255, 255});
  std::uint8_t* at(int x, int y) { return rgb.data() + (static_cast<size_t>(y) * width + x) * 3; }
  const std::uint8_t* at(int x, int y) const {
    return rgb.data() + (static_cast<size_t>(y) * width + x) * 3;
  }
};

/// Reads a PNG (any channel count; converted to RGB). Throws Error naming the file.
Image read_png(const std::filesystem::path& file);
/// Writes a PNG atomically (AtomicFile: nothing under the final name on failure).
void write_png(const std::filesystem::path& file, const Image& img);

}  // namespace mbi::io
