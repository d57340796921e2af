// A frame loop allocates nothing large and faults no page after its first call: Deformer::deform,
// vjp and interp::evaluate with caller memory, for BI, Phong and modified-BI, counted by a malloc
// hook (Eigen allocates with malloc, std::vector through operator new, which calls malloc), and
// the results are the same bits as the allocating calls'. Its own binary: the hook replaces the
// process's malloc.
#include <catch2/catch.hpp>

#include <mbi/interp.hpp>
#include <mbi/pipeline/deformer.hpp>
#include <mbi/pipeline/driver.hpp>
#include <mbi/pipeline/frame_pipeline.hpp>

#include "common/grid_meshes.hpp"

#include <sys/resource.h>

#include <atomic>
#include <cerrno>
#include <cstddef>
#include <random>
#include <thread>

#if defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(memory_sanitizer) || __has_feature(thread_sanitizer)
#define MBI_SANITIZED_MALLOC 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__) || defined(MBI_SANITIZED_MALLOC)
#define MBI_COUNT_ALLOCATIONS 0  // the sanitizer owns malloc
#else
#define MBI_COUNT_ALLOCATIONS 1
#endif

namespace {

constexpr std::size_t kLarge = 4096;  // bytes: an allocation above this counts
std::atomic<bool> counting{false};
std::atomic<long> large_allocations{0};

[[maybe_unused]] void note(std::size_t bytes) {
  if (bytes > kLarge && counting.load(std::memory_order_relaxed))
    large_allocations.fetch_add(1, std::memory_order_relaxed);
}

}  // namespace

#if MBI_COUNT_ALLOCATIONS
extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void* __libc_memalign(std::size_t, std::size_t);

void* malloc(std::size_t n) {
  note(n);
  return __libc_malloc(n);
}
void* calloc(std::size_t k, std::size_t n) {
  note(k * n);
  return __libc_calloc(k, n);
}
void* realloc(void* p, std::size_t n) {
  note(n);
  return __libc_realloc(p, n);
}
void* memalign(std::size_t alignment, std::size_t n) {
  note(n);
  return __libc_memalign(alignment, n);
}
void* aligned_alloc(std::size_t alignment, std::size_t n) { return memalign(alignment, n); }
int posix_memalign(void** p, std::size_t alignment, std::size_t n) {
  *p = memalign(alignment, n);
  return *p ? 0 : ENOMEM;
}
}
#endif

using namespace mbi;
using pipeline::Deformer;
using pipeline::Method;

namespace {

struct Counts {
  long allocations = 0;  // above kLarge bytes
  long faults = 0;       // minor page faults
};

long minor_faults() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_minflt;
}

// What `calls` runs of f allocate and fault, after one run that may set up its scratch.
template <class F>
Counts count(int calls, F&& f) {
  f();
  large_allocations = 0;
  const long faults = minor_faults();
  counting = true;
  for (int k = 0; k < calls; ++k) f();
  counting = false;
  return {large_allocations.load(), minor_faults() - faults};
}

Eigen::MatrixXd random(Eigen::Index r, Eigen::Index c, unsigned seed, double lo, double hi) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(lo, hi);
  Eigen::MatrixXd A(r, c);
  for (Eigen::Index i = 0; i < r; ++i)
    for (Eigen::Index j = 0; j < c; ++j) A(i, j) = uni(rng);
  return A;
}

bool same_bits(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return a.rows() == b.rows() && a.cols() == b.cols() && (a.array() == b.array()).all();
}

// The allocating calls, one after the other: what the pipeline computed before it kept scratch.
Eigen::MatrixXd deform_allocating(const Deformer& D, const Eigen::MatrixXd& X) {
  const Eigen::MatrixXd& U = D.rest_positions();
  const Eigen::MatrixXi& T = D.elements_matrix();
  interp::BezierPoints B;
  switch (D.method()) {
    case Method::BI: B = interp::bezier_bi(X, T); break;
    case Method::Phong: B = interp::bezier_points(U, T, X, D.phong().M(X)); break;
    case Method::ModifiedBI: B = interp::bezier_points(U, T, X, D.solver().solve(X)); break;
  }
  Eigen::MatrixXd positions;
  interp::evaluate<double>(B, D.embedding(), positions, D.options().threads);
  return positions;
}

Eigen::MatrixXd vjp_allocating(const Deformer& D, const Eigen::MatrixXd& G) {
  const interp::BezierPoints GB = interp::evaluate_transpose(D.embedding(), G, D.elements(), D.options().threads);
  interp::BezierTranspose t = interp::bezier_transpose(D.rest_positions(), D.elements_matrix(), GB);
  if (D.method() == Method::Phong) t.X += D.phong().M_transpose(t.M);
  if (D.method() == Method::ModifiedBI) t.X += D.solver().solve_transpose(t.M);
  return t.X;
}

const Method kMethods[] = {Method::BI, Method::Phong, Method::ModifiedBI};

struct Setup {
  test::Mesh mesh = test::box_tet_mesh(7, 7, 6);  // 1,764 tetrahedra, as the Python benchmarks
  Eigen::MatrixXd P = random(1000, 3, 1, 0.05, 0.95);
  Eigen::MatrixXd X = mesh.U + 0.02 * random(mesh.U.rows(), 3, 2, -1, 1);
  Eigen::MatrixXd G = random(1000, 3, 3, -1, 1);
};

}  // namespace

TEST_CASE("allocations: deform, vjp and evaluate with caller memory allocate nothing large after the first call",
          "[allocations]") {
  if (!MBI_COUNT_ALLOCATIONS) {
    WARN("not counted: the sanitizer replaces malloc");
    return;
  }
  const Setup s;
  for (Method method : kMethods) {
    for (int threads : {1, 0}) {
      CAPTURE(pipeline::method_name(method), threads);
      const Deformer D(s.mesh.U, s.mesh.T, s.P, {.method = method, .threads = threads});
      Eigen::MatrixXd positions(1000, 3), dX(D.vertices(), 3);
      const Counts deform = count(20, [&] { D.deform(s.X, positions); });
      CHECK(deform.allocations == 0);
      CHECK(deform.faults < 20);  // none expected; a few for the kernel's own bookkeeping
      const Counts vjp = count(20, [&] { D.vjp_batch(s.G, dX); });
      CHECK(vjp.allocations == 0);
      CHECK(vjp.faults < 20);
      const interp::BezierPoints B = D.bezier(s.X);
      const Counts evaluate = count(20, [&] { interp::evaluate<double>(B, D.embedding(), positions, threads); });
      CHECK(evaluate.allocations == 0);
      // the counter sees the allocating calls
      CHECK(count(5, [&] { (void)D.deform(s.X); }).allocations >= 5);
    }
  }
}

TEST_CASE("allocations: the calls into caller memory give the allocating calls' bits", "[allocations]") {
  const Setup s;
  for (Method method : kMethods) {
    CAPTURE(pipeline::method_name(method));
    const Deformer D(s.mesh.U, s.mesh.T, s.P, {.method = method});
    Eigen::MatrixXd positions(1000, 3), dX(D.vertices(), 3);
    for (int frame = 0; frame < 3; ++frame) {  // the second and later frames reuse the scratch
      const Eigen::MatrixXd X = s.X + 0.01 * frame * random(s.X.rows(), 3, 10 + frame, -1, 1);
      D.deform(X, positions);
      CHECK(same_bits(positions, deform_allocating(D, X)));
      D.vjp_batch(s.G * (1 + frame), dX);
      CHECK(same_bits(dX, vjp_allocating(D, s.G * (1 + frame))));
    }
  }
}

TEST_CASE("allocations: one Deformer on several threads at once gives each call its own scratch", "[allocations]") {
  const Setup s;
  for (Method method : kMethods) {
    CAPTURE(pipeline::method_name(method));
    const Deformer D(s.mesh.U, s.mesh.T, s.P, {.method = method, .threads = 1});
    std::vector<Eigen::MatrixXd> poses, expected, got(4, Eigen::MatrixXd(1000, 3));
    for (unsigned k = 0; k < 4; ++k) {
      poses.push_back(s.X + 0.05 * random(s.X.rows(), 3, 20 + k, -1, 1));
      expected.push_back(deform_allocating(D, poses.back()));
    }
    std::vector<std::thread> threads;
    for (size_t k = 0; k < 4; ++k)
      threads.emplace_back([&, k] {
        for (int r = 0; r < 50; ++r) D.deform(poses[k], got[k]);
      });
    for (std::thread& t : threads) t.join();
    for (size_t k = 0; k < 4; ++k) CHECK(same_bits(got[k], expected[k]));
  }
}

namespace {

// Allocations above kLarge bytes of `steps` steps (after 3) of a simulated pipeline over p points.
long pipeline_step_allocations(const Setup& s, Method method, long long p, int steps) {
  sim::Simulator simulator(s.mesh.U, s.mesh.T, sim::Material{1e5, 0.3, 1000}, sim::Parameters{});
  std::vector<int> left;
  for (int i = 0; i < s.mesh.U.rows(); ++i)
    if (s.mesh.U(i, 0) < 1e-9) left.push_back(i);
  simulator.fix(left);
  const Eigen::MatrixXd P = random(p, 3, 5, 0.05, 0.95);
  pipeline::PipelineOptions options;
  options.method = method;
  pipeline::FramePipeline pipe(s.mesh.U, s.mesh.T, interp::embed(s.mesh.U, s.mesh.T, P),
                               std::make_unique<pipeline::SimulatorDriver>(std::move(simulator)), options);
  for (int k = 0; k < 3; ++k) REQUIRE(pipe.step().ok);
  return count(steps, [&] { REQUIRE(pipe.step().ok); }).allocations;
}

}  // namespace

TEST_CASE("allocations: a pipeline's step allocates no more for 100 times the dense points", "[allocations]") {
  if (!MBI_COUNT_ALLOCATIONS) {
    WARN("not counted: the sanitizer replaces malloc");
    return;
  }
  const Setup s;
  for (Method method : kMethods) {
    CAPTURE(pipeline::method_name(method));
    const long few = pipeline_step_allocations(s, method, 1000, 5);
    const long many = pipeline_step_allocations(s, method, 100000, 5);
    CHECK(many == few);
  }
}
