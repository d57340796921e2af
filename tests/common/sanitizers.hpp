#pragma once
// Whether this build runs under AddressSanitizer (the debug preset): the slowest accuracy tests
// take fewer points there, the same code paths at a tenth of the work (ASan makes each step many
// times slower; the release pass runs the full sizes).
namespace mbi::test {

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif

/// n in a plain build, about n / 10 under the sanitizers (the same remainder modulo 16, so that
/// the kernels' tails still run).
inline int sized(int n) { return kSanitized ? n / 160 * 16 + n % 16 : n; }

}  // namespace mbi::test
