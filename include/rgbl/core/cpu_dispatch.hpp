#pragma once
// Function multi-versioning for the hot kernels: the library is built for the baseline x86-64 target
// (no -march anywhere), and these attributes add AVX2 (x86-64-v3) / AVX-512 (x86-64-v4) builds of a
// function, picked once at load time by the CPU. GCC on x86-64 only; elsewhere the portable code is
// compiled once. Not under ThreadSanitizer: GCC instruments the ifunc resolvers, which the dynamic
// loader runs before the TSan runtime is initialised, so binaries crashed at start-up.
// RGBL_X86_DISPATCH is defined where `__attribute__((target(...)))` and `__builtin_cpu_supports` can
// be used for hand-written dispatch. RGBL_NO_AVX512 (the CMake option) caps all of it at AVX2.

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(__SANITIZE_THREAD__)
#define RGBL_X86_DISPATCH 1
#define RGBL_CLONES_AVX2 __attribute__((target_clones("arch=x86-64-v3", "default")))
#if defined(RGBL_NO_AVX512)
#define RGBL_CLONES_AVX512 RGBL_CLONES_AVX2
#else
#define RGBL_CLONES_AVX512 __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#endif
#else
#define RGBL_CLONES_AVX2
#define RGBL_CLONES_AVX512
#endif
