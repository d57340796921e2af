// PC2 point caches (Blender "Mesh Cache" modifier): read and written (see Pc2Writer).
#include "cache.hpp"

#include <mbi/io/atomic_file.hpp>

#include <bit>
#include <cfloat>
#include <cmath>
#include <cstring>

namespace mbi::io {

using detail::fail;
using std::filesystem::path;

namespace {
template <typename T>
void put_le(AtomicFile& f, T x) {
  std::string b;
  detail::append_bytes(b, x, false);
  f.write(b.data(), b.size());
}
template <typename T>
T get_le(std::string_view data, std::size_t at) {
  return detail::load_le<T>(data.data() + at);
}
constexpr char kMagic[12] = {'P', 'O', 'I', 'N', 'T', 'C', 'A', 'C', 'H', 'E', '2', '\0'};
}  // namespace

Pc2Writer::Pc2Writer(const path& file, int num_points, float start_frame, float sample_rate)
    : file_(file), num_points_(num_points) {
  if (num_points < 0) fail(file, 0, "negative number of points");
  if (!std::isfinite(start_frame) || !std::isfinite(sample_rate))
    fail(file, 0, "start frame and sample rate must be finite");
  out_ = std::make_unique<AtomicFile>(file);
  out_->write(kMagic, 12);
  put_le<std::int32_t>(*out_, 1);
  put_le<std::int32_t>(*out_, num_points);
  put_le<float>(*out_, start_frame);
  put_le<float>(*out_, sample_rate);
  put_le<std::int32_t>(*out_, 0);
}

Pc2Writer::~Pc2Writer() = default;

void Pc2Writer::append(const Eigen::Ref<const Eigen::MatrixXd>& P) {
  if (!out_) fail(file_, 0, "append after finish()");
  if (P.rows() != num_points_ || (P.cols() != 3 && P.cols() != 2))
    fail(file_, 0, "sample " + std::to_string(samples_) + ": expected " +
                       std::to_string(num_points_) + " x 3 positions, got " +
                       std::to_string(P.rows()) + " x " + std::to_string(P.cols()));
  for (Eigen::Index i = 0; i < P.rows(); ++i)
    for (Eigen::Index c = 0; c < P.cols(); ++c)
      if (!std::isfinite(P(i, c)) || std::abs(P(i, c)) > FLT_MAX)
        fail(file_, 0, "sample " + std::to_string(samples_) + " point " + std::to_string(i) +
                           ": coordinate not finite as float32");
  std::vector<float> buf(static_cast<std::size_t>(P.rows()) * 3, 0.0f);
  for (Eigen::Index i = 0; i < P.rows(); ++i)
    for (Eigen::Index c = 0; c < P.cols(); ++c)
      buf[static_cast<std::size_t>(3 * i + c)] = static_cast<float>(P(i, c));
  // All of the sample or none: flushed now, so that a full disk fails this sample, which is
  // then cut off; the file holds exactly the samples counted.
  const long end = 32 + 12 * static_cast<long>(num_points_) * samples_;
  try {
    if constexpr (std::endian::native == std::endian::big) {
      for (float x : buf) put_le<float>(*out_, x);
    } else {
      out_->write(buf.data(), buf.size() * sizeof(float));
    }
    out_->flush();
  } catch (const Error&) {
    out_->truncate(end);
    throw;
  }
  ++samples_;
}

void Pc2Writer::append(const float* xyz) {
  if (!out_) fail(file_, 0, "append after finish()");
  const std::size_t n = 3 * static_cast<std::size_t>(num_points_);
  const std::size_t bad = detail::first_non_finite(xyz, n);
  if (bad < n)
    fail(file_, 0, "sample " + std::to_string(samples_) + " point " + std::to_string(bad / 3) + ": non-finite coordinate");
  // all of the sample or none, as above
  const long end = 32 + 12 * static_cast<long>(num_points_) * samples_;
  try {
    if constexpr (std::endian::native == std::endian::big) {
      for (std::size_t i = 0; i < n; ++i) put_le<float>(*out_, xyz[i]);
    } else {
      out_->write(xyz, n * sizeof(float));
    }
    out_->flush();
  } catch (const Error&) {
    out_->truncate(end);
    throw;
  }
  ++samples_;
}

void Pc2Writer::finish() {
  if (!out_) fail(file_, 0, "finish() called twice");
  out_->seek(28);
  put_le<std::int32_t>(*out_, samples_);
  out_->commit();
  out_.reset();
}

PointCache read_pc2(const path& file) { return parse_pc2(detail::slurp(file), file); }

PointCache parse_pc2(std::string_view data, const path& file) {
  const detail::HeadReader head = [&](std::size_t n) { return std::string(data.substr(0, n)); };
  return detail::parse_cache(data, detail::pc2_layout(head, data.size(), file), file);
}

detail::CacheLayout detail::pc2_layout(const HeadReader& head, unsigned long long size, const path& file) {
  const std::string h = head(32);
  if (h.size() < 32) fail(file, 0, "too short for a PC2 header (32 bytes)");
  if (std::memcmp(h.data(), kMagic, 12) != 0) fail(file, 0, "not a PC2 file (magic)");
  const auto version = get_le<std::int32_t>(h, 12);
  if (version != 1) fail(file, 0, "version " + std::to_string(version) + " (expected 1)");
  const auto np = get_le<std::int32_t>(h, 16);
  const auto ns = get_le<std::int32_t>(h, 28);
  if (np < 0 || ns < 0) fail(file, 0, "negative numPoints or numSamples");
  if (np == 0 && ns > 0)  // would loop over samples that take no bytes
    fail(file, 0, "header says " + std::to_string(ns) + " samples of 0 points");
  const unsigned long long need = 32ull + 12ull * static_cast<unsigned long long>(np) *
                                              static_cast<unsigned long long>(ns);
  if (need != size)
    fail(file, 0, "header says " + std::to_string(np) + " points x " + std::to_string(ns) +
                      " samples (" + std::to_string(need) + " bytes) but the file has " +
                      std::to_string(size) + (need > size ? " (truncated?)" : ""));
  CacheLayout L;
  L.points = np;
  L.frames = ns;
  L.data_offset = 32;
  L.start_frame = get_le<float>(h, 20);
  L.sample_rate = get_le<float>(h, 24);
  if (!std::isfinite(L.start_frame) || !std::isfinite(L.sample_rate))
    fail(file, 0, "start frame and sample rate must be finite");
  return L;
}

}  // namespace mbi::io
