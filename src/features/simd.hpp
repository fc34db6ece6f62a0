#pragma once
// Internal: the vector paths of the feature kernels. The build uses no -march flag; AVX2 and AVX-512
// code is compiled per function (target attributes) and chosen at run time, SSE2 is the x86-64 base.

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
#define RGBL_HAVE_AVX2_PATH 1
#endif

namespace rgbl::detail {

// The widest vector path a kernel may take (it takes the widest the CPU has, up to this).
enum class SimdWidth { sse2, avx2, avx512 };

// Whether this CPU runs the AVX2 paths, and the AVX-512BW ones.
bool cpu_has_avx2();
bool cpu_has_avx512bw();

}  // namespace rgbl::detail
