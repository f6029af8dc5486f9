#pragma once
// 2/sqrt(x) for 8 floats, the same bits on every x86-64 CPU.
//
// _mm256_rsqrt_ps is an approximation whose bits differ between CPU vendors (Intel and AMD
// give different 12-bit estimates); one Newton step does not make them agree, so a kernel
// built on it gives caches that differ by machine (the golden caches baked on an Intel VM
// differed from an AMD VM's from the first step). Square root and division are IEEE-754
// correctly rounded, so this version is reproducible everywhere.
#if defined(__AVX2__) && defined(__FMA__)
#include <immintrin.h>

namespace magbake::magnetics {

/// 2 / sqrt(x), lane by lane (x > 0; x = 0 gives +inf). Correctly rounded square root and
/// quotient: one rounding each, no CPU-dependent estimate.
inline __m256 two_over_sqrt(__m256 x) { return _mm256_div_ps(_mm256_set1_ps(2.0f), _mm256_sqrt_ps(x)); }

}  // namespace magbake::magnetics
#endif
