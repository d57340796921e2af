// interp::parallel_for (mbi/interp/parallel.hpp) on the library's parallel loops.
#include <mbi/interp/parallel.hpp>

#include "runtime/threads.hpp"

#include <algorithm>

namespace mbi::interp {

void parallel_for(long long count, long long block, const std::function<void(long long, long long)>& f, int threads) {
  if (count <= 0) return;
  block = std::max(block, 1LL);
  detail::parallel_blocks(count, block, detail::thread_count(count, block, threads), [&](long long b, long long e) {
    for (long long s = b; s < e; s += block) f(s, std::min(s + block, e));  // one call per block
  });
}

}  // namespace mbi::interp
