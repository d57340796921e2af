#pragma once
// Run-time CPU features of mbi::interp (internal): the AVX2/FMA kernels (evaluation, dense
// operator, factor sweeps) are picked with have_avx2_fma(); other CPUs run portable loops.
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

}  // namespace mbi::interp::detail
#endif
