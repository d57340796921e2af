// Loads beside the measured work (see loads.hpp).
#include "loads.hpp"

#include <dlfcn.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <thread>
#include <vector>

namespace harness {
namespace {

using Dgemm = void (*)(const char*, const char*, const int*, const int*, const int*, const double*,
                       const double*, const int*, const double*, const int*, const double*, double*,
                       const int*);

Dgemm dgemm() {
  static const Dgemm f = [] {
    void* s = dlsym(RTLD_DEFAULT, "dgemm_");  // already loaded when mbi runs CHOLMOD on it
    if (!s) {
      void* h = dlopen("libblas.so.3", RTLD_NOW | RTLD_GLOBAL);
      if (h) s = dlsym(h, "dgemm_");
    }
    return reinterpret_cast<Dgemm>(s);
  }();
  return f;
}

// One burst of numpy-like work: a 256 x 256 matrix product (OpenBLAS splits it over its threads).
void blas_burst(std::vector<double>& a, std::vector<double>& c) {
  const int n = 256;
  const double one = 1.0, zero = 0.0;
  dgemm()("N", "N", &n, &n, &n, &one, a.data(), &n, a.data(), &n, &zero, c.data(), &n);
}

// One burst of PyTorch-like work: an OpenMP parallel loop of about a millisecond.
double omp_burst(std::vector<double>& v) {
  double s = 0;
#ifdef HARNESS_OPENMP
#pragma omp parallel for reduction(+ : s)
#endif
  for (long i = 0; i < static_cast<long>(v.size()); ++i) {
    v[i] = std::sqrt(v[i] + 1.0);
    s += v[i];
  }
  return s;
}

volatile double g_sink;  // keeps the arithmetic

}  // namespace

void spin(const volatile bool* stop) {
  double x = 1.0;
  while (!*stop) {
    for (int i = 0; i < 1 << 20; ++i) x = x * 1.0000001 + 1e-9;
    if (x > 1e6) x = 1.0;
  }
  g_sink = x;
}

const char* name(Load l) {
  switch (l) {
    case Load::None: return "quiet";
    case Load::Thread: return "thread";
    case Load::Process: return "process";
    case Load::Blas: return "numpy-like";
    case Load::OpenMP: return "torch-like";
  }
  return "?";
}

bool available(Load l) {
  if (l == Load::Blas) return dgemm() != nullptr;
#ifndef HARNESS_OPENMP
  if (l == Load::OpenMP) return false;
#endif
  return true;
}

struct LoadGuard::Impl {
  explicit Impl(Load l) : load(l) {}
  Load load;
  volatile bool stop = false;
  std::thread th;
  pid_t child = -1;
};

LoadGuard::LoadGuard(Load l) : impl_(new Impl(l)) {
  Impl& I = *impl_;
  switch (l) {
    case Load::None: break;
    case Load::Thread: I.th = std::thread([&I] { spin(&I.stop); }); break;
    case Load::Process:
      I.child = fork();
      if (I.child == 0) {  // the child only computes until it is killed
        static const volatile bool never = false;
        spin(&never);
        _exit(0);
      }
      break;
    case Load::Blas:
    case Load::OpenMP:
      I.th = std::thread([&I, l] {
        std::vector<double> a(256 * 256, 0.5), c(256 * 256);
        std::vector<double> v(1 << 20, 1.0);
        while (!I.stop) {
          if (l == Load::Blas) blas_burst(a, c);
          else omp_burst(v);
          std::this_thread::sleep_for(std::chrono::milliseconds(5));
        }
      });
      break;
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(20));  // let it start
}

LoadGuard::~LoadGuard() {
  Impl& I = *impl_;
  I.stop = true;
  if (I.th.joinable()) I.th.join();
  if (I.child > 0) {
    kill(I.child, SIGKILL);
    waitpid(I.child, nullptr, 0);
  }
  delete impl_;
}

}  // namespace harness
