// Private: run-time dispatch to code compiled for a wider instruction set, on every compiler.
//
// Where the compiler can compile one function for AVX2 inside a baseline build and ask the CPU
// at run time (GCC and Clang on x86), RIDGELINE_HAS_AVX2_DISPATCH is 1, RIDGELINE_TARGET_AVX2
// marks such a function and cpu_has_avx2() says whether it may run. Elsewhere (MSVC, other
// CPUs, builds with RIDGELINE_PORTABLE) there is no dispatch: RIDGELINE_HAS_AVX2_DISPATCH is 0
// and callers take their scalar path, which gives the same results (front.cpp).
#pragma once

#if !defined(RIDGELINE_PORTABLE) && (defined(__GNUC__) || defined(__clang__)) && \
    (defined(__x86_64__) || defined(__i386__))
#define RIDGELINE_HAS_AVX2_DISPATCH 1
#define RIDGELINE_TARGET_AVX2 __attribute__((target("avx2")))
#include <immintrin.h>

namespace ridgeline::detail {
/// True when the CPU runs AVX2 instructions (asked once).
inline bool cpu_has_avx2() noexcept {
  static const bool yes = __builtin_cpu_supports("avx2");
  return yes;
}
}  // namespace ridgeline::detail

#else
#define RIDGELINE_HAS_AVX2_DISPATCH 0
#define RIDGELINE_TARGET_AVX2
namespace ridgeline::detail {
inline bool cpu_has_avx2() noexcept { return false; }
}  // namespace ridgeline::detail
#endif
