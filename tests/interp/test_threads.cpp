// The library's threads (mbi/interp/threads.hpp and the internal pool, interp/src/runtime/threads.hpp):
// the count set is the most that run, results do not depend on it, several caller threads share
// the one pool (its threads never exceed the count), and the parallel loops' contracts (every
// block once, nested calls, exceptions, steps that depend on each other).
#include <catch2/catch.hpp>

#include "common/grid_meshes.hpp"
#include "common/sanitizers.hpp"
#include "runtime/threads.hpp"

#include <mbi/interp.hpp>
#include <mbi/interp/threads.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <fstream>
#include <mutex>
#include <random>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

using namespace mbi::interp;
namespace detail = mbi::interp::detail;

namespace {

// restores the default count when a test ends, whatever it set
struct ThreadCount {
  explicit ThreadCount(int n) { set_threads(n); }
  ~ThreadCount() { set_threads(0); }
};

// the distinct threads that ran the blocks of one parallel loop of 64 blocks of ~200 us each
// (time for a pool thread to arrive, even on a busy machine: up to 10 tries until one does)
std::set<std::thread::id> threads_used(int threads) {
  std::mutex m;
  std::set<std::thread::id> ids;
  for (int attempt = 0; attempt < 10 && ids.size() < 2; ++attempt)
    detail::parallel_blocks(64, 1, threads, [&](long long, long long) {
      const auto t0 = std::chrono::steady_clock::now();
      while (std::chrono::steady_clock::now() - t0 < std::chrono::microseconds(200)) {
      }
      std::lock_guard<std::mutex> lock(m);
      ids.insert(std::this_thread::get_id());
    });
  return ids;
}

int process_threads() {
  std::ifstream f("/proc/self/status");
  for (std::string line; std::getline(f, line);)
    if (line.rfind("Threads:", 0) == 0) return std::stoi(line.substr(8));
  return -1;  // not Linux: not checked
}

// Everything a frame computes, at 1,331 control vertices (a factor large enough for the threaded
// sweeps) and 100K points (10K under the sanitizers), on the library's current thread count.
struct Frame {
  Embedding emb;
  Eigen::MatrixXd pd;
  Eigen::MatrixXf pf;
  RowMatrixXf fast;
  VertexMatrices M;
};

Frame frame() {
  const mbi::test::Mesh C = mbi::test::box_tet_mesh(10, 10, 10, Eigen::Vector3d(10, 10, 10));
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> uni(0.01, 9.99);
  Eigen::MatrixXd P(mbi::test::sized(100003), 3);  // not a multiple of any block: every tail runs
  for (Eigen::Index i = 0; i < P.rows(); ++i) P.row(i) << uni(rng), uni(rng), uni(rng);
  Frame f;
  f.emb = embed(C.U, C.T, P);
  const ModifiedBI solver(C.U, C.T);
  const Eigen::MatrixXd X = mbi::test::twist_bend(C.U, 1.0, 0.2);
  f.M = solver.solve(X);
  const BezierPoints B = solver.bezier(X, f.M);
  evaluate<double>(B, f.emb, f.pd);
  evaluate<float>(B, f.emb, f.pf);
  FastEvaluator(f.emb).evaluate(B, f.fast);
  return f;
}

}  // namespace

TEST_CASE("threads: the count set is the count in force and the most that run", "[threads]") {
  if (!threads_available()) {
    ThreadCount t(4);
    CHECK(threads() == 1);
    CHECK(threads_used(4).size() == 1);
    return;
  }
  const int cores = threads();
  CHECK(cores >= 1);
  for (int n : {1, 2, 3}) {
    ThreadCount t(n);
    CHECK(threads() == n);
    const auto ids = threads_used(n);
    CHECK(static_cast<int>(ids.size()) <= n);
    if (n > 1) CHECK(ids.size() > 1);  // the pool comes
    // a per-call count above the library's is held to it
    CHECK(detail::thread_count(1 << 20, 1, 8) == n);
  }
  set_threads(0);
  CHECK(threads() == cores);
}

TEST_CASE("threads: results are the same on 1, 2, 3 and 4 threads", "[threads]") {
  Frame one;
  {
    ThreadCount t(1);
    one = frame();
  }
  for (int n : {2, 3, 4}) {
    ThreadCount t(n);
    CAPTURE(n);
    const Frame f = frame();
    CHECK(f.emb.element == one.emb.element);
    CHECK(f.emb.bary == one.emb.bary);
    CHECK(f.M == one.M);  // the sparse sweeps' schedule does not depend on the thread count
    CHECK(f.pd == one.pd);
    CHECK(f.pf == one.pf);
    CHECK(f.fast == one.fast);
  }
}

TEST_CASE("threads: several caller threads at once share the one pool", "[threads]") {
  ThreadCount t(2);
  const Frame ref = frame();
  const int before = process_threads();
  std::atomic<int> most{0}, wrong{0};
  std::vector<std::thread> callers;
  for (int c = 0; c < 4; ++c)
    callers.emplace_back([&] {
      for (int k = 0; k < 2; ++k) {
        const Frame f = frame();
        if (!(f.M == ref.M && f.pd == ref.pd && f.pf == ref.pf && f.fast == ref.fast)) ++wrong;
        most = std::max(most.load(), process_threads());
      }
    });
  for (auto& th : callers) th.join();
  CHECK(wrong == 0);
  if (before > 0) {
    // the callers and what was there before (the pool's one thread, BLAS's): no team per caller
    CAPTURE(before, most.load());
    CHECK(most <= before + 4);
  }
}

TEST_CASE("threads: every block runs once, nested loops run on their thread, exceptions reach the caller", "[threads]") {
  ThreadCount t(3);
  std::vector<std::atomic<int>> hits(10007);
  detail::parallel_blocks(static_cast<long long>(hits.size()), 13, 3, [&](long long b, long long e) {
    detail::parallel_blocks(e - b, 2, 3, [&](long long b2, long long e2) {  // nested: on this thread
      for (long long i = b + b2; i < b + e2; ++i) ++hits[static_cast<size_t>(i)];
    });
  });
  CHECK(std::all_of(hits.begin(), hits.end(), [](const std::atomic<int>& h) { return h == 1; }));
  for (int thrower : {0, 1}) {
    const std::thread::id caller = std::this_thread::get_id();
    auto body = [&](long long, long long) {
      std::this_thread::sleep_for(std::chrono::microseconds(100));
      if ((std::this_thread::get_id() == caller) == (thrower == 0)) throw std::runtime_error("block failed");
    };
    if (thrower == 0) CHECK_THROWS_WITH(detail::parallel_blocks(64, 1, 3, body), "block failed");
    else {
      // a pool thread's exception, when a pool thread ran a block
      try {
        detail::parallel_blocks(64, 1, 3, body);
      } catch (const std::runtime_error& e) {
        CHECK(std::string(e.what()) == "block failed");
      }
    }
  }
  // the pool works after the exceptions
  CHECK(threads_used(3).size() >= 1);
}

TEST_CASE("threads: steps see everything the step before wrote", "[threads]") {
  // 200 steps, each reading the array the step before wrote (a neighbour's entry too)
  auto run = [](int n) {
    ThreadCount t(n);
    std::vector<long long> a(5000), b(5000);
    for (size_t i = 0; i < a.size(); ++i) a[i] = static_cast<long long>(i);
    detail::Steps steps;
    const std::thread::id caller = std::this_thread::get_id();
    detail::run_shared(n, [&] {
      if (std::this_thread::get_id() != caller) return steps.join();
      for (int k = 0; k < 200; ++k) {
        const std::vector<long long>& from = k % 2 ? b : a;
        std::vector<long long>& to = k % 2 ? a : b;
        steps.run(static_cast<long long>(a.size()), 97, [&](long long lo, long long hi) {
          for (long long i = lo; i < hi; ++i)
            to[static_cast<size_t>(i)] = (from[static_cast<size_t>(i)] + 3 * from[static_cast<size_t>((i + 1) % 5000)] + k) % 1000003;
        });
      }
      steps.close();
    });
    return a;
  };
  const std::vector<long long> one = run(1);
  for (int n : {2, 3, 4}) {
    CAPTURE(n);
    CHECK(run(n) == one);
  }
}
