#pragma once
// What the point-cache formats (format_pc2.cpp, format_mdd.cpp) share with their readers
// (PointCacheReader in point_cache.cpp, parse_pc2, parse_mdd): where the frames are in a file,
// and one frame decoded.
#include "io_common.hpp"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace mbi::io::detail {

/// Where a point cache's frames lie: frame k is 12 points bytes (float32 x, y, z per point) at
/// data_offset + 12 points k.
struct CacheLayout {
  int points = 0, frames = 0;
  bool big_endian = false;
  unsigned long long data_offset = 0;
  float start_frame = 0.0f, sample_rate = 1.0f;  // PC2
  std::vector<float> times;                       // MDD (unless left unread)
  unsigned long long times_offset = 0;            // MDD: where its times are
};

/// The first n bytes of a file (fewer when it is shorter).
using HeadReader = std::function<std::string(std::size_t n)>;

/// A PC2 file's layout from its first bytes and its size; throws Error naming what is wrong.
CacheLayout pc2_layout(const HeadReader& head, unsigned long long size, const std::filesystem::path& file);
/// An MDD file's layout (a Blender export's extra rest frame skipped).
/// `with_times`: the times are read too (else only their place is given).
CacheLayout mdd_layout(const HeadReader& head, unsigned long long size, const std::filesystem::path& file,
                       bool with_times = true);

/// One frame of `points` float32 triples at `bytes` (big or little endian) into out (points x 3);
/// throws Error "<file>: frame k: point i: non-finite coordinate" (and for magnitudes above
/// kMaxCoordinate, which float32 cannot reach).
void decode_cache_frame(const char* bytes, int points, bool big_endian, Eigen::MatrixXd& out,
                        const std::filesystem::path& file, int frame);

/// The index of the first of n floats that is not finite, n when all are (a vectorised pass:
/// a frame of a million points is checked at memory speed before it is written).
inline std::size_t first_non_finite(const float* x, std::size_t n) {
  std::uint32_t any = 0;
  for (std::size_t i = 0; i < n; ++i) {
    std::uint32_t u;
    std::memcpy(&u, x + i, 4);
    any |= static_cast<std::uint32_t>((u & 0x7f800000u) == 0x7f800000u);
  }
  if (!any) return n;
  std::size_t i = 0;
  while (std::isfinite(x[i])) ++i;
  return i;
}

/// Every frame of a cache in memory (parse_pc2, parse_mdd).
PointCache parse_cache(std::string_view data, const CacheLayout& layout, const std::filesystem::path& file);

}  // namespace mbi::io::detail
