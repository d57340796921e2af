// An Image's pixels, apart from PNG (image.cpp): what needs no stb (the browser build's mbi::io).
#include <mbi/io/image.hpp>

#include <cstdint>
#include <stdexcept>
#include <string>

namespace mbi::io {

Image::Image(int w, int h, Eigen::Vector3i background) : width(w), height(h) {
  if (w <= 0 || h <= 0 || w > 16384 || h > 16384)
    throw std::invalid_argument("Image: size " + std::to_string(w) + " x " + std::to_string(h) +
                                " out of range");
  rgb.resize(static_cast<size_t>(w) * h * 3);
  for (size_t i = 0; i < rgb.size(); i += 3)
    for (int c = 0; c < 3; ++c) rgb[i + static_cast<size_t>(c)] = static_cast<std::uint8_t>(background[c]);
}

}  // namespace mbi::io
