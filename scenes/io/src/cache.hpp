#pragma once
// What the point-cache formats (format_pc2.cpp, format_mdd.cpp) share with their readers
// (PointCacheReader in point_cache.cpp, parse_pc2, parse_mdd): where the frames are in a file,
// and one frame decoded.
#include "io_common.hpp"

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
  std::vector<float> times;                       // MDD
};

/// The first n bytes of a file (fewer when it is shorter).
using HeadReader = std::function<std::string(std::size_t n)>;

/// A PC2 file's layout from its first bytes and its size; throws IoError naming what is wrong.
CacheLayout pc2_layout(const HeadReader& head, unsigned long long size, const std::filesystem::path& file);
/// An MDD file's layout (a Blender export's extra rest frame skipped).
CacheLayout mdd_layout(const HeadReader& head, unsigned long long size, const std::filesystem::path& file);

/// One frame of `points` float32 triples at `bytes` (big or little endian) into out (points x 3);
/// throws IoError "<file>: frame k: point i: non-finite coordinate" (and for magnitudes above
/// kMaxCoordinate, which float32 cannot reach).
void decode_cache_frame(const char* bytes, int points, bool big_endian, Eigen::MatrixXd& out,
                        const std::filesystem::path& file, int frame);

/// Every frame of a cache in memory (parse_pc2, parse_mdd).
PointCache parse_cache(std::string_view data, const CacheLayout& layout, const std::filesystem::path& file);

}  // namespace mbi::io::detail
