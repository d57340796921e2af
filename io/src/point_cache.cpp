// Point caches read a frame at a time (PointCacheReader), and whole (parse_cache), for PC2 and
// MDD alike: only their headers differ (cache.hpp).
#include "cache.hpp"

#include <sys/stat.h>

#include <cerrno>
#include <cmath>
#include <cstring>

namespace mbi::io {

using detail::fail;
using std::filesystem::path;

namespace detail {

void decode_cache_frame(const char* bytes, int points, bool big_endian, Eigen::MatrixXd& out,
                        const path& file, int frame) {
  out.resize(points, 3);
  const bool swap = big_endian != (std::endian::native == std::endian::big);
  for (int i = 0; i < points; ++i)
    for (int c = 0; c < 3; ++c) {
      const double x = load_bytes<float>(bytes + 12 * static_cast<std::size_t>(i) + 4 * c, swap);
      if (!std::isfinite(x) || std::abs(x) > kMaxCoordinate)
        fail(file, 0, "frame " + std::to_string(frame) + ": point " + std::to_string(i) + ": non-finite coordinate");
      out(i, c) = x;
    }
}

PointCache parse_cache(std::string_view data, const CacheLayout& layout, const path& file) {
  PointCache pc;
  pc.start_frame = layout.start_frame;
  pc.sample_rate = layout.sample_rate;
  pc.times = layout.times;
  const std::size_t frame_bytes = 12 * static_cast<std::size_t>(layout.points);
  for (int k = 0; k < layout.frames; ++k) {
    Eigen::MatrixXd P;
    decode_cache_frame(data.data() + layout.data_offset + frame_bytes * static_cast<std::size_t>(k),
                       layout.points, layout.big_endian, P, file, k);
    pc.frames.push_back(std::move(P));
  }
  return pc;
}

}  // namespace detail

PointCacheReader::PointCacheReader(const path& file) : file_(file) {
  const std::string ext = lower_extension(file);
  if (ext != ".pc2" && ext != ".mdd") fail(file, 0, "not a point cache (expected .pc2 or .mdd)");
  detail::require_regular_file(file);
  in_ = std::fopen(file.c_str(), "rb");
  if (!in_) fail(file, 0, std::string("cannot open for reading (") + std::strerror(errno) + ")");
  struct stat st {};
  if (::fstat(fileno(in_), &st) != 0 || !S_ISREG(st.st_mode)) {
    std::fclose(in_);
    fail(file, 0, "not a regular file");
  }
  const auto size = static_cast<unsigned long long>(st.st_size);
  const detail::HeadReader head = [this](std::size_t n) {
    std::string b(n, '\0');
    std::rewind(in_);
    b.resize(std::fread(b.data(), 1, n, in_));
    return b;
  };
  detail::CacheLayout L;
  try {
    L = ext == ".pc2" ? detail::pc2_layout(head, size, file) : detail::mdd_layout(head, size, file, false);
  } catch (...) {
    std::fclose(in_);
    throw;
  }
  points_ = L.points;
  frames_ = L.frames;
  big_endian_ = L.big_endian;
  data_offset_ = L.data_offset;
  start_frame_ = L.start_frame;
  sample_rate_ = L.sample_rate;
  times_offset_ = L.times_offset;
}

const std::vector<float>& PointCacheReader::times() {
  if (times_read_ || times_offset_ == 0) return times_;
  // float32 times cannot increase over more frames evenly spaced; more would only fill memory
  constexpr int kMaxTimes = 1 << 24;
  if (frames_ > kMaxTimes)
    fail(file_, 0, "the times of " + std::to_string(frames_) + " frames are more than mbi reads (" +
                       std::to_string(kMaxTimes) + ")");
  std::string b(4 * static_cast<std::size_t>(frames_), '\0');
  if (std::fseek(in_, static_cast<long>(times_offset_), SEEK_SET) != 0 || std::fread(b.data(), 1, b.size(), in_) != b.size())
    fail(file_, 0, "frame times: file truncated (it changed since it was opened)");
  times_.resize(static_cast<std::size_t>(frames_));
  for (std::size_t k = 0; k < times_.size(); ++k) {
    times_[k] = detail::load_bytes<float>(b.data() + 4 * k, std::endian::native == std::endian::little);
    if (!std::isfinite(times_[k])) fail(file_, 0, "time of frame " + std::to_string(k) + ": not finite");
  }
  times_read_ = true;
  return times_;
}

PointCacheReader::~PointCacheReader() {
  if (in_) std::fclose(in_);
}

Eigen::MatrixXd PointCacheReader::frame(int k) {
  if (k < 0 || k >= frames_) fail(file_, 0, "frame " + std::to_string(k) + " of " + std::to_string(frames_) + " asked for");
  const std::size_t bytes = 12 * static_cast<std::size_t>(points_);
  buffer_.resize(bytes);
  const unsigned long long at = data_offset_ + bytes * static_cast<unsigned long long>(k);
  if (std::fseek(in_, static_cast<long>(at), SEEK_SET) != 0 || std::fread(buffer_.data(), 1, bytes, in_) != bytes)
    fail(file_, 0, "frame " + std::to_string(k) + ": file truncated (it changed since it was opened)");
  Eigen::MatrixXd P;
  detail::decode_cache_frame(buffer_.data(), points_, big_endian_, P, file_, k);
  return P;
}

}  // namespace mbi::io
