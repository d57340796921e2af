#pragma once
// Run-time CPU features of mbi::interp (internal). MBI_INTERP_X86 is the one guard of the x86
// code: where it is defined, functions compiled for AVX2/FMA or AVX-512 with
// __attribute__((target(...))) (never per-file flags: Eigen templates compiled wider would leave
// copies the linker may keep for every CPU) are picked at run time with have_avx2_fma() and
// have_avx512(); other CPUs run portable loops, as does a build configured with
// MBI_WITH_X86_KERNELS=OFF (MBI_INTERP_PORTABLE).
#if (defined(__x86_64__) || defined(__i386__)) && (defined(__GNUC__) || defined(__clang__)) && \
    !defined(MBI_INTERP_PORTABLE)
#define MBI_INTERP_X86 1
#include <immintrin.h>

namespace mbi::interp::detail {

/// AVX2 and FMA are present (asked once).
inline bool have_avx2_fma() {
  static const bool ok = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  }();
  return ok;
}

/// AVX-512 F, DQ and VL, with AVX2 and FMA (the 512-bit evaluation kernels; asked once).
inline bool have_avx512() {
  static const bool ok = [] {
    __builtin_cpu_init();
    return have_avx2_fma() && __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
           __builtin_cpu_supports("avx512vl");
  }();
  return ok;
}

}  // namespace mbi::interp::detail
#endif
