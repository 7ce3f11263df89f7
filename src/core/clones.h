// Private: PBA_CLONES, function multi-versioning for the hot kernels.
//
// A function marked PBA_CLONES is compiled for AVX2 and for the baseline, and the loader
// picks one at start-up (GCC target_clones). -ffp-contract=off keeps both free of fused
// multiply-adds, so both give the same bits. Not under the sanitizers: the ifunc resolver
// runs during relocation, before the sanitizer runtime is up, and crashes the program
// (seen with TSan). Empty on other compilers and targets.
#pragma once

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && !defined(__SANITIZE_ADDRESS__) && \
    !defined(__SANITIZE_THREAD__)
#define PBA_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define PBA_CLONES
#endif
