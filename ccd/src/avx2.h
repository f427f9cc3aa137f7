#pragma once
// Internal to ccd/: the AVX2 helpers shared by the kernels (batch.cpp: four tests at a time;
// coplanarity.cpp: one query's cubic; separation.cpp: one query's boxes). Each kernel is a
// function with __attribute__((target("avx2"))), run only where avx2_enabled(); the helpers
// inline into it. Every one reproduces a scalar operation bit for bit.

#include <immintrin.h>

#include "drape/ccd/query.h"

#define DRAPE_AVX2 __attribute__((target("avx2"), always_inline)) inline

namespace drape::ccd::detail {

/// Whether this machine has AVX2, asked once at start-up. avx2.cpp.
extern const bool cpu_has_avx2;
/// Tests only: the portable code even where the AVX2 kernels could run (run_batch's gather and
/// compute_cubics, query_cubic's coplanarity_cubic, apart_over's boxes); both must give the
/// same bits and decisions. avx2.cpp.
extern bool portable_kernels;

/// Whether the AVX2 kernels run (called per query: a load and a test).
inline bool avx2_enabled() { return cpu_has_avx2 && !portable_kernels; }

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

}  // namespace drape::ccd::detail
