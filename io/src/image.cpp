#include <mbi/io/atomic_file.hpp>
#include <mbi/io/image.hpp>
#include <mbi/io/parse.hpp>

#include <stb_image.h>
#include <stb_image_write.h>

#include <cstdint>
#include <cstring>
#include <limits>
#include <string>

namespace mbi::io {

Image read_png(const std::filesystem::path& file) { return parse_png(read_bytes(file), file); }

Image parse_png(std::string_view data, const std::filesystem::path& file) {
  // stb_image reads a dozen formats; only PNG is meant, so the decoder never sees anything else.
  static const unsigned char signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (data.size() < 8 || std::memcmp(data.data(), signature, 8) != 0)
    throw Error(file.string() + ": not a PNG file (no PNG signature)");
  if (data.size() > static_cast<std::size_t>(std::numeric_limits<int>::max()))
    throw Error(file.string() + ": PNG file too large");
  // The chunks are walked first: each must fit in the file. Empty IDAT chunks (legal, but stb
  // then copies 0 bytes to a null buffer: undefined behaviour, found by fuzz_png) are dropped,
  // which changes nothing of the image.
  std::string png(data.substr(0, 8));
  bool dropped = false;
  for (std::size_t at = 8; at < data.size();) {
    if (data.size() - at < 12)
      throw Error(file.string() + ": PNG truncated (chunk at byte " + std::to_string(at) + ")");
    const auto* b = reinterpret_cast<const unsigned char*>(data.data() + at);
    const std::uint32_t length = (std::uint32_t{b[0]} << 24) | (std::uint32_t{b[1]} << 16) |
                                 (std::uint32_t{b[2]} << 8) | b[3];
    if (length > data.size() - at - 12)
      throw Error(file.string() + ": PNG chunk at byte " + std::to_string(at) + " of " +
                    std::to_string(length) + " bytes runs past the end of the file");
    const std::size_t whole = 12 + static_cast<std::size_t>(length);
    if (length == 0 && data.compare(at + 4, 4, "IDAT") == 0) dropped = true;
    else png.append(data.substr(at, whole));
    if (data.compare(at + 4, 4, "IEND") == 0) break;  // anything after IEND is ignored
    at += whole;
  }
  const std::string_view kept = dropped ? std::string_view(png) : data;
  const auto* bytes = reinterpret_cast<const stbi_uc*>(kept.data());
  const int len = static_cast<int>(kept.size());
  int w = 0, h = 0, n = 0;
  if (!stbi_info_from_memory(bytes, len, &w, &h, &n))
    throw Error(file.string() + ": cannot read image (" + stbi_failure_reason() + ")");
  if (w <= 0 || h <= 0 || w > kMaxImageSide || h > kMaxImageSide)
    throw Error(file.string() + ": image of " + std::to_string(w) + " x " + std::to_string(h) +
                  " pixels; at most " + std::to_string(kMaxImageSide) + " x " +
                  std::to_string(kMaxImageSide) + " are accepted");
  unsigned char* pixels = stbi_load_from_memory(bytes, len, &w, &h, &n, 3);
  if (!pixels)
    throw Error(file.string() + ": cannot read image (" + stbi_failure_reason() + ")");
  Image img;
  img.width = w;
  img.height = h;
  img.rgb.assign(pixels, pixels + static_cast<size_t>(w) * h * 3);
  stbi_image_free(pixels);
  return img;
}

void write_png(const std::filesystem::path& file, const Image& img) {
  if (img.width <= 0 || img.height <= 0 || img.rgb.size() != static_cast<size_t>(img.width) * img.height * 3)
    throw Error(file.string() + ": cannot write an empty or inconsistent image");
  write_file_atomic(file, [&](AtomicFile& out) {
    auto sink = [](void* context, void* data, int size) {
      auto* f = static_cast<AtomicFile*>(context);
      f->write(data, static_cast<size_t>(size));
    };
    if (!stbi_write_png_to_func(sink, &out, img.width, img.height, 3, img.rgb.data(), img.width * 3))
      throw Error(file.string() + ": cannot encode PNG");
  });
}

}  // namespace mbi::io
