// Private to the library: rows of four doubles turned into columns on AVX2, for the contact
// bookkeeping that gathers a record a lane into lanes (the reuse test, rigid/contact_pairs.cpp;
// the blocks' fill, rigid/contact_solver.cpp). Copies and shuffles only: no value changes.
// Include it only in files whose wide functions are compiled with per-function targets.
#pragma once

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>

#include "pba/core.h"

#define PBA_ROWS_AVX2 1

namespace pba::detail {

/// Four rows of four doubles to four columns (column i's lane k is row k's i-th).
[[gnu::always_inline]] __attribute__((target("avx2"))) inline void columns4(__m256d r0, __m256d r1, __m256d r2,
                                                                           __m256d r3, __m256d out[4]) {
  const __m256d t0 = _mm256_unpacklo_pd(r0, r1), t1 = _mm256_unpackhi_pd(r0, r1);
  const __m256d t2 = _mm256_unpacklo_pd(r2, r3), t3 = _mm256_unpackhi_pd(r2, r3);
  out[0] = _mm256_permute2f128_pd(t0, t2, 0x20), out[1] = _mm256_permute2f128_pd(t1, t3, 0x20);
  out[2] = _mm256_permute2f128_pd(t0, t2, 0x31), out[3] = _mm256_permute2f128_pd(t1, t3, 0x31);
}
/// A Vec3 as a row (its fourth lane 0).
[[gnu::always_inline]] __attribute__((target("avx2"))) inline __m256d row3(const Vec3& v) {
  return _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(&v.x)), _mm_load_sd(&v.z), 1);
}

}  // namespace pba::detail
#else
#define PBA_ROWS_AVX2 0
#endif
