// MDD point caches (Blender, Houdini, 3ds Max, LightWave): read and written (see MddWriter).
// Big endian throughout: int32 numFrames, int32 numPoints, float32 times[numFrames], then
// float32 x, y, z per point per frame.
#include "cache.hpp"

#include <mbi/io/atomic_file.hpp>

#include <bit>
#include <cerrno>
#include <cfloat>
#include <cmath>
#include <cstring>

#include <unistd.h>

namespace mbi::io {

using detail::fail;
using std::filesystem::path;

namespace {

template <typename T>
std::string be_bytes(T x) {
  std::string b;
  detail::append_bytes(b, x, true);
  return b;
}

template <typename T>
T get_be(std::string_view data, std::size_t at) {
  return detail::load_bytes<T>(data.data() + at, std::endian::native == std::endian::little);
}

// The header and times of a file of `frames` frames.
std::string mdd_header(int frames, int points, const std::vector<float>& times) {
  std::string h = be_bytes<std::int32_t>(frames) + be_bytes<std::int32_t>(points);
  for (int k = 0; k < frames; ++k) h += be_bytes<float>(times[static_cast<std::size_t>(k)]);
  return h;
}

}  // namespace

MddWriter::MddWriter(const path& file, int num_points, std::vector<float> times)
    : file_(file), num_points_(num_points), times_(std::move(times)) {
  if (num_points < 0) fail(file, 0, "negative number of points");
  if (times_.size() > static_cast<std::size_t>(kMaxCount)) fail(file, 0, "too many frames");
  for (float t : times_)
    if (!std::isfinite(t)) fail(file, 0, "frame times must be finite");
  out_ = std::make_unique<AtomicFile>(file);
  out_->write(mdd_header(static_cast<int>(times_.size()), num_points, times_));
}

MddWriter::~MddWriter() = default;

void MddWriter::append(const Eigen::Ref<const Eigen::MatrixXd>& P) {
  if (P.rows() != num_points_ || (P.cols() != 3 && P.cols() != 2))
    fail(file_, 0, "frame " + std::to_string(samples_) + ": expected " + std::to_string(num_points_) +
                       " x 3 positions, got " + std::to_string(P.rows()) + " x " + std::to_string(P.cols()));
  std::vector<float> xyz(3 * static_cast<std::size_t>(num_points_), 0.0f);
  for (Eigen::Index i = 0; i < P.rows(); ++i)
    for (Eigen::Index c = 0; c < P.cols(); ++c) {
      if (!std::isfinite(P(i, c)) || std::abs(P(i, c)) > FLT_MAX)
        fail(file_, 0, "frame " + std::to_string(samples_) + " point " + std::to_string(i) +
                           ": coordinate not finite as float32");
      xyz[static_cast<std::size_t>(3 * i + c)] = static_cast<float>(P(i, c));
    }
  append(xyz.data());
}

void MddWriter::append(const float* xyz) {
  if (!out_) fail(file_, 0, "append after finish()");
  if (static_cast<std::size_t>(samples_) >= times_.size())
    fail(file_, 0, "frame " + std::to_string(samples_) + ": more frames than the " + std::to_string(times_.size()) + " announced");
  const std::size_t n = 3 * static_cast<std::size_t>(num_points_);
  const std::size_t bad = detail::first_non_finite(xyz, n);
  if (bad < n)
    fail(file_, 0, "frame " + std::to_string(samples_) + " point " + std::to_string(bad / 3) + ": non-finite coordinate");
  buffer_.resize(4 * n);
  for (std::size_t i = 0; i < n; ++i) {
    std::uint32_t u = std::bit_cast<std::uint32_t>(xyz[i]);
    if constexpr (std::endian::native == std::endian::little) u = __builtin_bswap32(u);
    std::memcpy(buffer_.data() + 4 * i, &u, 4);
  }
  // all of the frame or none: a full disk fails this frame, which is cut off
  const long end = static_cast<long>(8 + 4 * times_.size() + 12 * static_cast<std::size_t>(num_points_) * samples_);
  try {
    out_->write(buffer_.data(), buffer_.size());
    out_->flush();
  } catch (const Error&) {
    out_->truncate(end);
    throw;
  }
  ++samples_;
}

void MddWriter::finish() {
  if (!out_) fail(file_, 0, "finish() called twice");
  if (static_cast<std::size_t>(samples_) == times_.size()) {
    out_->commit();
    out_.reset();
    return;
  }
  // Fewer frames than announced (a bad frame, an interruption, a full disk): the times block is
  // shorter, so the frames written move up, in place (a full disk has no room for a copy).
  out_->flush();
  std::FILE* io = std::fopen(out_->temporary().c_str(), "r+b");
  if (!io) fail(file_, 0, std::string("cannot reopen the file being written (") + std::strerror(errno) + ")");
  struct Closer {
    std::FILE* f;
    ~Closer() {
      if (f) std::fclose(f);
    }
  } closer{io};
  const std::size_t frame = 12 * static_cast<std::size_t>(num_points_);
  const long from = static_cast<long>(8 + 4 * times_.size()), to = static_cast<long>(8 + 4 * static_cast<std::size_t>(samples_));
  buffer_.resize(frame);
  for (int k = 0; k < samples_; ++k) {  // frame k's new place ends before frame k + 1's old one
    const long at = static_cast<long>(frame) * k;
    if (std::fseek(io, from + at, SEEK_SET) != 0 || std::fread(buffer_.data(), 1, frame, io) != frame ||
        std::fseek(io, to + at, SEEK_SET) != 0 || std::fwrite(buffer_.data(), 1, frame, io) != frame)
      fail(file_, 0, "cannot move frame " + std::to_string(k) + " up (" + std::strerror(errno) + ")");
  }
  const std::string head = mdd_header(samples_, num_points_, times_);
  if (std::fseek(io, 0, SEEK_SET) != 0 || std::fwrite(head.data(), 1, head.size(), io) != head.size() || std::fflush(io) != 0 ||
      ::ftruncate(::fileno(io), to + static_cast<long>(frame) * samples_) != 0)
    fail(file_, 0, std::string("cannot shorten the file to the frames written (") + std::strerror(errno) + ")");
  std::fclose(io);
  closer.f = nullptr;
  out_->commit();
  out_.reset();
}

detail::CacheLayout detail::mdd_layout(const HeadReader& head, unsigned long long size, const path& file,
                                       bool with_times) {
  const std::string h8 = head(8);
  if (h8.size() < 8) fail(file, 0, "too short for an MDD header (8 bytes)");
  const auto frames = get_be<std::int32_t>(h8, 0);
  const auto points = get_be<std::int32_t>(h8, 4);
  if (frames < 0 || points < 0)
    fail(file, 0, "header says " + std::to_string(frames) + " frames of " + std::to_string(points) +
                      " points (negative: not an MDD file, or a little-endian one)");
  if (points == 0 && frames > 0) fail(file, 0, "header says " + std::to_string(frames) + " frames of 0 points");
  const unsigned long long nf = static_cast<unsigned long long>(frames), np = static_cast<unsigned long long>(points);
  const unsigned long long times_end = 8 + 4 * nf;
  const unsigned long long need = times_end + 12 * np * nf;
  // Blender's exporter writes the rest pose before the frames it counts
  const bool rest_frame = size == need + 12 * np && np > 0;
  if (size != need && !rest_frame)
    fail(file, 0, "header says " + std::to_string(frames) + " frames of " + std::to_string(points) +
                      " points (" + std::to_string(need) + " bytes) but the file has " + std::to_string(size) +
                      (need > size ? " (truncated?)" : ""));
  CacheLayout L;
  L.points = points;
  L.frames = frames;
  L.big_endian = true;
  L.data_offset = times_end + (rest_frame ? 12 * np : 0);
  L.times_offset = 8;
  if (!with_times) return L;
  const std::string h = head(static_cast<std::size_t>(times_end));
  L.times.resize(nf);
  for (std::size_t k = 0; k < nf; ++k) {
    L.times[k] = get_be<float>(h, 8 + 4 * k);
    if (!std::isfinite(L.times[k])) fail(file, 0, "time of frame " + std::to_string(k) + ": not finite");
  }
  return L;
}

PointCache read_mdd(const path& file) { return parse_mdd(detail::slurp(file), file); }

PointCache parse_mdd(std::string_view data, const path& file) {
  const detail::HeadReader head = [&](std::size_t n) { return std::string(data.substr(0, n)); };
  return detail::parse_cache(data, detail::mdd_layout(head, data.size(), file), file);
}

}  // namespace mbi::io
