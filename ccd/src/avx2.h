#pragma once
// Internal to ccd/: the AVX2 helpers shared by the kernels (batch.cpp: four tests at a time;
// coplanarity.cpp: one query's cubic; separation.cpp: one query's boxes). Each kernel is a
// function with __attribute__((target("avx2"))), run only where avx2_enabled(); the helpers
// inline into it. Every one reproduces a scalar operation bit for bit.

// The x86 kernels are compiled where the compiler targets x86 with GCC's or clang's intrinsics,
// unless the build asks for the portable kernels alone (CMake: DRAPE_PORTABLE_KERNELS=ON, which
// tools/test-portable.sh builds and tests); without them every answer comes from the portable
// code, bit for bit the same.
#if !defined(DRAPE_PORTABLE_KERNELS_ONLY) && (defined(__x86_64__) || defined(__i386__)) && \
    (defined(__GNUC__) || defined(__clang__))
#define DRAPE_X86_KERNELS 1
#else
#define DRAPE_X86_KERNELS 0
#endif

#if DRAPE_X86_KERNELS
#include <immintrin.h>
#endif

#include "drape/ccd/coplanarity.h"
#include "drape/ccd/query.h"

#define DRAPE_AVX2 __attribute__((target("avx2"), always_inline)) inline

namespace drape::ccd::detail {

/// Whether this machine has AVX2, asked once at start-up. avx2.cpp.
extern const bool cpu_has_avx2;
/// Tests only: the portable code even where the AVX2 kernels could run (run_batch's gather and
/// compute_cubics, query_cubic's coplanarity_cubic, apart_over's boxes); both must give the
/// same bits and decisions. avx2.cpp.
extern bool portable_kernels;

/// Whether the AVX2 kernels run (called per query: a load and a test); never without them.
inline bool avx2_enabled() { return DRAPE_X86_KERNELS && cpu_has_avx2 && !portable_kernels; }

/// Whether this machine has AVX-512 F and DQ, asked once at start-up (avx2.cpp); and, for
/// tests only, the AVX2 batch kernel even where the AVX-512 one could run (the same bits).
extern const bool cpu_has_avx512;
extern bool avx2_only;

/// Whether the batch's cubic kernel runs eight tests at a time (batch.cpp).
inline bool avx512_enabled() { return avx2_enabled() && cpu_has_avx512 && !avx2_only; }

#if DRAPE_X86_KERNELS
/// std::max(a, b) and std::min(a, b) lane by lane, NaN and signed zeros included: b where
/// a < b (b < a), else a. maxpd(x, y) is x > y ? x : y and minpd(x, y) is x < y ? x : y, so
/// with the operands swapped they are exactly these.
DRAPE_AVX2 __m256d max4(__m256d a, __m256d b) { return _mm256_max_pd(b, a); }
DRAPE_AVX2 __m256d min4(__m256d a, __m256d b) { return _mm256_min_pd(b, a); }
DRAPE_AVX2 __m256d abs4(__m256d a) { return _mm256_andnot_pd(_mm256_set1_pd(-0.0), a); }

/// (x, y, z, 0): x and y in one 128-bit load, z with a zero above it (a masked 256-bit load is
/// several times slower on the machines we measured, AMD Zen 4).
DRAPE_AVX2 __m256d load_point(const Vec3& p) {
  return _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(p.data())), _mm_load_sd(p.data() + 2), 1);
}

/// (x, y, z, whatever follows p) in one load: only for a point followed by another double of
/// the same object, where the kernel ignores lane 3.
static_assert(sizeof(Vec3) == 3 * sizeof(double) && sizeof(Query) == 8 * sizeof(Vec3),
              "load_start and load_end read a query's points as 8 consecutive packed Vec3");
DRAPE_AVX2 __m256d load_point_followed(const Vec3& p) { return _mm256_loadu_pd(p.data()); }

/// Point i of a query at the start or the end of the step, for kernels that ignore lane 3: the
/// last point has nothing after it in the query.
DRAPE_AVX2 __m256d load_start(const Query& q, int i) { return load_point_followed(q.start[i]); }
DRAPE_AVX2 __m256d load_end(const Query& q, int i) { return i < 3 ? load_point_followed(q.end[i]) : load_point(q.end[i]); }

/// filter_culls(cubic) from b = (b0, b1, b2, b3) in a register and the error: every comparison
/// and every min and max of the scalar code (cubic_poorly_resolved, same_strict_sign,
/// signs_cull), in its order, so the same answer for every input, NaN included.
DRAPE_AVX2 bool filter_culls_avx2(__m256d b, Scalar error) {
  const __m128d b01 = _mm256_castpd256_pd128(b), b23 = _mm256_extractf128_pd(b, 1);
  const __m128d abs01 = _mm_andnot_pd(_mm_set1_pd(-0.0), b01), abs23 = _mm_andnot_pd(_mm_set1_pd(-0.0), b23);
  // max_abs: std::max({|b0|, |b1|, |b2|, |b3|}), left to right; maxsd(x, m) is std::max(m, x).
  __m128d largest = _mm_max_sd(_mm_unpackhi_pd(abs01, abs01), abs01);
  largest = _mm_max_sd(abs23, largest);
  largest = _mm_max_sd(_mm_unpackhi_pd(abs23, abs23), largest);
  const bool poorly_resolved = _mm_cvtsd_f64(largest) <= POORLY_RESOLVED_RATIO * error;
  // same_strict_sign: std::min and std::max of (b0, b1) and (b2, b3), then of the two.
  const __m128d evens = _mm_unpacklo_pd(b01, b23), odds = _mm_unpackhi_pd(b01, b23);  // (b0, b2), (b1, b3)
  const __m128d pair_min = _mm_min_pd(odds, evens), pair_max = _mm_max_pd(odds, evens);
  const Scalar lo = _mm_cvtsd_f64(_mm_min_sd(_mm_unpackhi_pd(pair_min, pair_min), pair_min));
  const Scalar hi = _mm_cvtsd_f64(_mm_max_sd(_mm_unpackhi_pd(pair_max, pair_max), pair_max));
  // std::min(|b0|, |b3|).
  const Scalar ends = _mm_cvtsd_f64(_mm_min_sd(_mm_unpackhi_pd(abs23, abs23), abs01));
  return (!poorly_resolved) & ((lo > 0) | (hi < 0)) & (ends > error);
}

#endif  // DRAPE_X86_KERNELS

}  // namespace drape::ccd::detail
