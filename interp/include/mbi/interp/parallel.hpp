#pragma once
// A parallel loop on the library's pool (threads.hpp) for layers above interp.
//
//   mbi::interp::parallel_for(points, 1024, [&](long long begin, long long end) { ... });
#include <functional>

namespace mbi::interp {

/// f(begin, end) for the blocks [k block, (k + 1) block) of [0, count) (the last one shorter),
/// each block on one thread, on up to `threads` threads (0: threads()); returns when every block
/// is done and rethrows the first exception. The blocks are the same for every thread count, so
/// results written per item or per block, then combined in order, do not depend on it.
void parallel_for(long long count, long long block, const std::function<void(long long, long long)>& f,
                  int threads = 0);

}  // namespace mbi::interp
