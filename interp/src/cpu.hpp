#pragma once
// Run-time CPU features of mbi::interp (internal): the AVX2/FMA kernels (evaluation, dense
// operator, factor sweeps) are picked with have_avx2_fma(), the AVX-512 evaluation kernels with
// have_avx512(); other CPUs run portable loops.
#if (defined(__x86_64__) || defined(__i386__)) && (defined(__GNUC__) || defined(__clang__))
#define MBI_INTERP_X86 1

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
