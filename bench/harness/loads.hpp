#pragma once
// What else runs while the harness measures: nothing, a thread of this process or another process
// keeping one core busy with arithmetic (not memory), or the pools a Python user's process brings:
// numpy's (BLAS calls on OpenBLAS's threads, here through the system's libblas.so.3 as numpy
// calls it) and PyTorch's (an OpenMP parallel loop of the user's own, on the compiler's OpenMP
// runtime). The numpy- and PyTorch-like loads run in bursts (a few ms of parallel work, then a
// pause), as a script between two calls into mbi does.
#include <string>

namespace harness {

enum class Load { None, Thread, Process, Blas, OpenMP };

const char* name(Load l);
/// Whether this harness can produce the load (Blas: libblas.so.3 found; OpenMP: built with it).
bool available(Load l);

/// Keeps the load running from construction to destruction.
class LoadGuard {
 public:
  explicit LoadGuard(Load l);
  ~LoadGuard();
  LoadGuard(const LoadGuard&) = delete;
  LoadGuard& operator=(const LoadGuard&) = delete;

 private:
  struct Impl;
  Impl* impl_;
};

/// Arithmetic on one core until `stop` becomes true (also the child process's whole life).
void spin(const volatile bool* stop);

}  // namespace harness
