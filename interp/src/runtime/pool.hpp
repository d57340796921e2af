#pragma once
// The process's one pool of threads (internal; built with MBI_WITH_THREADS). See threads.hpp for
// how work is shared; this file only hands bodies to threads and waits for them.
//
// A call takes the pool threads that are free (a second caller meanwhile gets the rest, or none,
// and runs alone: pools never multiply), posts its body to each and runs it itself. When its own
// body returns, it takes back every post a thread has not picked up yet, so a thread that has not
// been scheduled since is never waited for, and waits only for those that picked it up. A thread
// without work waits on the CPU for kSpin (a frame's next call usually comes sooner, and then
// finds it running), then sleeps in the kernel until posted to.
#include "runtime/threads.hpp"

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

namespace mbi::interp::detail {

class Pool {
 public:
  static Pool& get();
  /// The CPUs this process may run on (its affinity mask), at least 1.
  static int cores();
  /// Runs body on the caller and on up to threads - 1 free pool threads (see run_shared).
  void run(int threads, FunctionRef<void()> body);

 private:
  struct Job;
  struct Worker;
  Pool() = default;
  int acquire(int n, Worker** out);
  void release(Worker* const* w, int n);
  void work(Worker& w);

  std::mutex m_;
  std::vector<std::unique_ptr<Worker>> workers_;  // started on demand, kept
  std::vector<Worker*> idle_;
  bool stopping_ = false;
};

}  // namespace mbi::interp::detail
