#include <mbi/io/atomic_file.hpp>
#include <mbi/io/image.hpp>

#include <stb_image.h>
#include <stb_image_write.h>

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

Image read_png(const std::filesystem::path& file) {
  int w = 0, h = 0, n = 0;
  unsigned char* data = stbi_load(file.string().c_str(), &w, &h, &n, 3);
  if (!data)
    throw IoError(file.string() + ": cannot read image (" + stbi_failure_reason() + ")");
  Image img;
  img.width = w;
  img.height = h;
  img.rgb.assign(data, data + static_cast<size_t>(w) * h * 3);
  stbi_image_free(data);
  return img;
}

void write_png(const std::filesystem::path& file, const Image& img) {
  if (img.width <= 0 || img.height <= 0 || img.rgb.size() != static_cast<size_t>(img.width) * img.height * 3)
    throw IoError(file.string() + ": cannot write an empty or inconsistent image");
  write_file_atomic(file, [&](AtomicFile& out) {
    auto sink = [](void* context, void* data, int size) {
      auto* f = static_cast<AtomicFile*>(context);
      f->write(data, static_cast<size_t>(size));
    };
    if (!stbi_write_png_to_func(sink, &out, img.width, img.height, 3, img.rgb.data(), img.width * 3))
      throw IoError(file.string() + ": cannot encode PNG");
  });
}

}  // namespace mbi::io
