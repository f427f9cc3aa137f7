#include "drape/ccd/batch.h"

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

#include "drape/ccd/coplanarity.h"
#include "avx2.h"
#include "problem.h"

namespace drape::ccd {

namespace {
// Tests per TBB task: a few microseconds of work, enough to amortise the scheduling.
constexpr std::size_t GRAIN = 256;
}  // namespace

void BatchCounters::add(const Result& result) {
  ++tests;
  culled += result.path == Path::Culled || result.path == Path::Separated;
  separated += result.path == Path::Separated;
  degenerate += result.path == Path::Degenerate;
  root_solves += result.root_solves;
  hits += result.hit;
}

BatchCounters& BatchCounters::operator+=(const BatchCounters& other) {
  tests += other.tests;
  culled += other.culled;
  separated += other.separated;
  root_solves += other.root_solves;
  hits += other.hits;
  degenerate += other.degenerate;
  return *this;
}

VertexFaceQuery gather(const BatchInput& input, const VertexFacePair& pair) {
  VertexFaceQuery q;
  const std::array<std::int32_t, 4> index{pair.vertex, pair.face[0], pair.face[1], pair.face[2]};
  for (int i = 0; i < 4; ++i) {
    q.start[i] = input.start[index[i]];
    q.end[i] = input.end[index[i]];
  }
  return q;
}

EdgeEdgeQuery gather(const BatchInput& input, const EdgeEdgePair& pair) {
  EdgeEdgeQuery q;
  const std::array<std::int32_t, 4> index{pair.edge_a[0], pair.edge_a[1], pair.edge_b[0], pair.edge_b[1]};
  for (int i = 0; i < 4; ++i) {
    q.start[i] = input.start[index[i]];
    q.end[i] = input.end[index[i]];
  }
  return q;
}

namespace {

// Tests whose cubics are computed together: the coordinates of a chunk are gathered into one
// array per coordinate so that the arithmetic runs on several tests at once (SIMD).
constexpr std::size_t CHUNK = 64;

struct ChunkCubics {
  // The differences x2 - x1, x3 - x1, x4 - x1 (A, B, C) at t = 0 and t = 1, per coordinate.
  alignas(64) Scalar a0[3][CHUNK], a1[3][CHUNK], b0[3][CHUNK], b1[3][CHUNK], c0[3][CHUNK], c1[3][CHUNK];
  alignas(64) Scalar coefficient[4][CHUNK], error[CHUNK], extent[CHUNK];
  static_assert(CHUNK == 64, "one bit per test of a chunk in a 64-bit mask");
  std::uint64_t culled = 0;  // bit i: filter_culls of test i's cubic
  // Bit i: the conservative method's first question: resolved, and every coefficient beyond
  // its error plus the thickness's share of the cubic with one sign (certainly_nonzero on the
  // whole step). Only computed where asked for: by the AVX2 path's APART kernels, at any
  // thickness; by the portable path always, but for zero thickness only (the error alone).
  std::uint64_t certainly_apart = 0;
};

// The tests [0, n) of a chunk as bits.
std::uint64_t chunk_bits(std::size_t n) { return n >= CHUNK ? ~std::uint64_t(0) : (std::uint64_t(1) << n) - 1; }

std::array<std::int32_t, 4> points(const VertexFacePair& p) { return {p.vertex, p.face[0], p.face[1], p.face[2]}; }
std::array<std::int32_t, 4> points(const EdgeEdgePair& p) { return {p.edge_a[0], p.edge_a[1], p.edge_b[0], p.edge_b[1]}; }

// coplanarity_cubic_in<Scalar> for n tests at once, operation for operation (the results are the
// same bits; the batch test compares them with the one-query entry points). The portable path:
// machines with AVX2 run gather_cubics_avx2 below instead, so this needs no AVX2 clone.
void compute_cubics(ChunkCubics& c, std::size_t n) {
  constexpr Scalar unit_roundoff = std::numeric_limits<Scalar>::epsilon() / 2;
  c.culled = c.certainly_apart = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const auto cross = [&](const Scalar (*u)[CHUNK], const Scalar (*v)[CHUNK], Scalar out[3]) {
      out[0] = u[1][i] * v[2][i] - u[2][i] * v[1][i];
      out[1] = u[2][i] * v[0][i] - u[0][i] * v[2][i];
      out[2] = u[0][i] * v[1][i] - u[1][i] * v[0][i];
    };
    const auto dot = [&](const Scalar (*u)[CHUNK], const Scalar w[3]) { return u[0][i] * w[0] + u[1][i] * w[1] + u[2][i] * w[2]; };
    Scalar b0c0[3], b1c0[3], b0c1[3], b1c1[3];
    cross(c.b0, c.c0, b0c0);
    cross(c.b1, c.c0, b1c0);
    cross(c.b0, c.c1, b0c1);
    cross(c.b1, c.c1, b1c1);
    c.coefficient[0][i] = dot(c.a0, b0c0);
    c.coefficient[1][i] = (dot(c.a1, b0c0) + dot(c.a0, b1c0) + dot(c.a0, b0c1)) / Scalar(3);
    c.coefficient[2][i] = (dot(c.a1, b1c0) + dot(c.a1, b0c1) + dot(c.a0, b1c1)) / Scalar(3);
    c.coefficient[3][i] = dot(c.a1, b1c1);
    const auto l1 = [&](const Scalar (*s)[CHUNK], const Scalar (*e)[CHUNK]) {
      return std::max(std::abs(s[0][i]) + std::abs(s[1][i]) + std::abs(s[2][i]),
                      std::abs(e[0][i]) + std::abs(e[1][i]) + std::abs(e[2][i]));
    };
    const Scalar a = l1(c.a0, c.a1), b = l1(c.b0, c.b1), cc = l1(c.c0, c.c1);
    c.error[i] = Scalar(COPLANARITY_ERROR_FACTOR) * unit_roundoff * a * b * cc;
    c.extent[i] = std::max(std::max(a, b), cc);
    // filter_culls, written out on the arrays.
    const Scalar k0 = c.coefficient[0][i], k1 = c.coefficient[1][i], k2 = c.coefficient[2][i], k3 = c.coefficient[3][i];
    const Scalar largest = std::max(std::max(std::abs(k0), std::abs(k1)), std::max(std::abs(k2), std::abs(k3)));
    const Scalar lo = std::min(std::min(k0, k1), std::min(k2, k3)), hi = std::max(std::max(k0, k1), std::max(k2, k3));
    const bool resolved = !(largest <= POORLY_RESOLVED_RATIO * c.error[i]);
    const bool one_sign = (lo > 0) | (hi < 0);
    const bool ends_clear = std::min(std::abs(k0), std::abs(k3)) > c.error[i];
    c.culled |= std::uint64_t(resolved & one_sign & ends_clear) << i;
    const Scalar e = c.error[i];
    const bool all_above = (k0 > e) & (k1 > e) & (k2 > e) & (k3 > e), all_below = (k0 < -e) & (k1 < -e) & (k2 < -e) & (k3 < -e);
    c.certainly_apart |= std::uint64_t(resolved & (all_above | all_below)) << i;
  }
}

// The scalar gather into c's coordinate arrays, then compute_cubics.
template <class Pair>
void gather_cubics(const BatchInput& input, const Pair* pairs, std::size_t n, const std::array<int, 4>& order,
                   ChunkCubics& c) {
  for (std::size_t i = 0; i < n; ++i) {
    const auto index = points(pairs[i]);
    const Vec3 &s1 = input.start[index[order[0]]], &e1 = input.end[index[order[0]]];
    const Vec3 &s2 = input.start[index[order[1]]], &e2 = input.end[index[order[1]]];
    const Vec3 &s3 = input.start[index[order[2]]], &e3 = input.end[index[order[2]]];
    const Vec3 &s4 = input.start[index[order[3]]], &e4 = input.end[index[order[3]]];
    for (int k = 0; k < 3; ++k) {
      c.a0[k][i] = s2[k] - s1[k];
      c.a1[k][i] = e2[k] - e1[k];
      c.b0[k][i] = s3[k] - s1[k];
      c.b1[k][i] = e3[k] - e1[k];
      c.c0[k][i] = s4[k] - s1[k];
      c.c1[k][i] = e4[k] - e1[k];
    }
  }
  compute_cubics(c, n);
}

// Which of conservative's first question the kernel asks: none, at zero thickness (the error
// alone), or with the thickness's share of the cubic (a separate kernel: the share's norms keep
// more registers alive).
enum class Apart { No, AtZeroThickness, WithThickness };

// A test the chunk's decisions left (not culled by the filter, not certainly apart for
// conservative), with its cubic: run a few chunks' worth at a time.
struct Left {
  std::size_t index;
  CoplanarityCubic cubic;
};
constexpr int LEFT_MAX = 64;

#if DRAPE_X86_KERNELS
// The same with AVX2 intrinsics, fused with the gather: four tests at a time, their points
// loaded straight into registers (x and y as one 128-bit load, then transposed), nothing
// stored but the results. Every operation is the scalar code's, in its order (no FMA; min and
// max as std::min and std::max, NaN included), so the bits are the same. About half the
// instructions of the gather and compute_cubics above, which are the whole cost of a culled test.
using detail::abs4;
using detail::max4;
using detail::min4;

struct Lanes3 {
  __m256d x, y, z;
};

// Point `point` (of the pair's points in query order) of four tests, one coordinate per
// register; the indices read straight from the pairs. Each point's (x, y) and (y, z) as two
// 128-bit loads, the tests' pairs interleaved (as many instructions as gathering z by scalar
// loads, but fewer registers: callgrind counted about 1 % fewer for the kernel).
template <class Pair>
DRAPE_AVX2 Lanes3 load4_point(const Vec3* base, const Pair* const (&pair)[4], int point) {
  const double *p0 = base[points(*pair[0])[point]].data(), *p1 = base[points(*pair[1])[point]].data(),
               *p2 = base[points(*pair[2])[point]].data(), *p3 = base[points(*pair[3])[point]].data();
  const __m256d xy02 = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(p0)), _mm_loadu_pd(p2), 1);
  const __m256d xy13 = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(p1)), _mm_loadu_pd(p3), 1);
  const __m256d yz02 = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(p0 + 1)), _mm_loadu_pd(p2 + 1), 1);
  const __m256d yz13 = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(p1 + 1)), _mm_loadu_pd(p3 + 1), 1);
  return {_mm256_unpacklo_pd(xy02, xy13), _mm256_unpacklo_pd(yz02, yz13), _mm256_unpackhi_pd(yz02, yz13)};
}

// Point k in coplanarity order.
template <QueryKind kind, int k, class Pair>
DRAPE_AVX2 Lanes3 load4(const Vec3* base, const Pair* const (&pair)[4]) {
  return load4_point(base, pair, coplanarity_order(kind)[k]);
}

DRAPE_AVX2 Lanes3 sub4(const Lanes3& a, const Lanes3& b) {
  return {_mm256_sub_pd(a.x, b.x), _mm256_sub_pd(a.y, b.y), _mm256_sub_pd(a.z, b.z)};
}

DRAPE_AVX2 Lanes3 cross4(const Lanes3& u, const Lanes3& v) {
  return {_mm256_sub_pd(_mm256_mul_pd(u.y, v.z), _mm256_mul_pd(u.z, v.y)),
          _mm256_sub_pd(_mm256_mul_pd(u.z, v.x), _mm256_mul_pd(u.x, v.z)),
          _mm256_sub_pd(_mm256_mul_pd(u.x, v.y), _mm256_mul_pd(u.y, v.x))};
}

DRAPE_AVX2 __m256d dot4(const Lanes3& u, const Lanes3& w) {
  return _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(u.x, w.x), _mm256_mul_pd(u.y, w.y)), _mm256_mul_pd(u.z, w.z));
}

DRAPE_AVX2 __m256d l1_4(const Lanes3& s, const Lanes3& e) {
  return max4(_mm256_add_pd(_mm256_add_pd(abs4(s.x), abs4(s.y)), abs4(s.z)),
              _mm256_add_pd(_mm256_add_pd(abs4(e.x), abs4(e.y)), abs4(e.z)));
}

DRAPE_AVX2 __m256d norm4(const Lanes3& u) {
  return _mm256_sqrt_pd(_mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(u.x, u.x), _mm256_mul_pd(u.y, u.y)),
                                      _mm256_mul_pd(u.z, u.z)));
}

DRAPE_AVX2 __m256d negate4(__m256d a) { return _mm256_xor_pd(a, _mm256_set1_pd(-0.0)); }

// certainly_nonzero(b, margin) lane by lane: every coefficient above margin, or every one below
// -margin.
DRAPE_AVX2 __m256d certainly_nonzero4(const __m256d (&b)[4], __m256d margin) {
  const __m256d minus = negate4(margin);
  const __m256d above =
      _mm256_and_pd(_mm256_and_pd(_mm256_cmp_pd(b[0], margin, _CMP_GT_OQ), _mm256_cmp_pd(b[1], margin, _CMP_GT_OQ)),
                    _mm256_and_pd(_mm256_cmp_pd(b[2], margin, _CMP_GT_OQ), _mm256_cmp_pd(b[3], margin, _CMP_GT_OQ)));
  const __m256d below =
      _mm256_and_pd(_mm256_and_pd(_mm256_cmp_pd(b[0], minus, _CMP_LT_OQ), _mm256_cmp_pd(b[1], minus, _CMP_LT_OQ)),
                    _mm256_and_pd(_mm256_cmp_pd(b[2], minus, _CMP_LT_OQ), _mm256_cmp_pd(b[3], minus, _CMP_LT_OQ)));
  return _mm256_or_pd(above, below);
}


// Tests i to i + 3 of a chunk, the pairs pair, into c's arrays at i and bits i to i + 3 of
// culled and (with APART) apart.
template <QueryKind kind, Apart APART, class Pair>
DRAPE_AVX2 void cubics4(const BatchInput& input, const Pair* const (&pair)[4], Scalar thickness, ChunkCubics& c,
                        std::size_t i, std::uint64_t& culled_bits, std::uint64_t& apart_bits) {
  constexpr Scalar unit_roundoff = std::numeric_limits<Scalar>::epsilon() / 2;
  const __m256d zero = _mm256_setzero_pd();
  const Vec3 *start = input.start.data(), *end = input.end.data();
  const Lanes3 s1 = load4<kind, 0>(start, pair), e1 = load4<kind, 0>(end, pair);
  const Lanes3 A0 = sub4(load4<kind, 1>(start, pair), s1), A1 = sub4(load4<kind, 1>(end, pair), e1);
  const Lanes3 s3 = load4<kind, 2>(start, pair), e3 = load4<kind, 2>(end, pair);
  const Lanes3 s4 = load4<kind, 3>(start, pair), e4 = load4<kind, 3>(end, pair);
  const Lanes3 B0 = sub4(s3, s1), B1 = sub4(e3, e1);
  const Lanes3 C0 = sub4(s4, s1), C1 = sub4(e4, e1);
  const Lanes3 b0c0 = cross4(B0, C0), b1c0 = cross4(B1, C0), b0c1 = cross4(B0, C1), b1c1 = cross4(B1, C1);
  const __m256d three = _mm256_set1_pd(3.0);
  const __m256d k0 = dot4(A0, b0c0);
  const __m256d k1 = _mm256_div_pd(_mm256_add_pd(_mm256_add_pd(dot4(A1, b0c0), dot4(A0, b1c0)), dot4(A0, b0c1)), three);
  const __m256d k2 = _mm256_div_pd(_mm256_add_pd(_mm256_add_pd(dot4(A1, b1c0), dot4(A1, b0c1)), dot4(A0, b1c1)), three);
  const __m256d k3 = dot4(A1, b1c1);
  const __m256d a = l1_4(A0, A1), b = l1_4(B0, B1), cc = l1_4(C0, C1);
  const __m256d e = _mm256_mul_pd(
      _mm256_mul_pd(_mm256_mul_pd(_mm256_set1_pd(Scalar(COPLANARITY_ERROR_FACTOR) * unit_roundoff), a), b), cc);
  _mm256_store_pd(&c.coefficient[0][i], k0);
  _mm256_store_pd(&c.coefficient[1][i], k1);
  _mm256_store_pd(&c.coefficient[2][i], k2);
  _mm256_store_pd(&c.coefficient[3][i], k3);
  _mm256_store_pd(&c.error[i], e);
  _mm256_store_pd(&c.extent[i], max4(max4(a, b), cc));
  const __m256d largest = max4(max4(abs4(k0), abs4(k1)), max4(abs4(k2), abs4(k3)));
  const __m256d lo = min4(min4(k0, k1), min4(k2, k3)), hi = max4(max4(k0, k1), max4(k2, k3));
  const __m256d resolved = _mm256_cmp_pd(largest, _mm256_mul_pd(_mm256_set1_pd(POORLY_RESOLVED_RATIO), e), _CMP_NLE_UQ);
  const __m256d one_sign = _mm256_or_pd(_mm256_cmp_pd(lo, zero, _CMP_GT_OQ), _mm256_cmp_pd(hi, zero, _CMP_LT_OQ));
  const __m256d ends_clear = _mm256_cmp_pd(min4(abs4(k0), abs4(k3)), e, _CMP_GT_OQ);
  culled_bits |= std::uint64_t(_mm256_movemask_pd(_mm256_and_pd(_mm256_and_pd(resolved, one_sign), ends_clear))) << i;
  if constexpr (APART != Apart::No) {
    // The margin: the error, plus with a thickness conservative.cpp's thickness_to_cubic
    // lane by lane (the longer of each of two edges at the two ends of the step: the vertex-
    // face test's triangle edges from its first vertex, A and B; the edge-edge test's edges,
    // A and x4 - x3 from the points themselves, as the scalar code subtracts them).
    __m256d m = e;
    if constexpr (APART == Apart::WithThickness) {
      const __m256d first = max4(norm4(A0), norm4(A1));
      const __m256d second = kind == QueryKind::VertexFace ? max4(norm4(B0), norm4(B1))
                                                           : max4(norm4(sub4(s4, s3)), norm4(sub4(e4, e3)));
      const __m256d share = _mm256_mul_pd(_mm256_mul_pd(_mm256_set1_pd(thickness), _mm256_mul_pd(first, second)),
                                          _mm256_set1_pd(1 + 16 * UNIT_ROUNDOFF));
      m = _mm256_add_pd(e, share);
    }
    apart_bits |= std::uint64_t(_mm256_movemask_pd(_mm256_and_pd(resolved, certainly_nonzero4({k0, k1, k2, k3}, m))))
                  << i;
  }
}

// Tests [0, n) of pairs, n <= CHUNK, into c (the arrays a0..c1 are not filled); with APART
// also c.certainly_apart (the conservative method's first question), else it stays 0.
template <QueryKind kind, Apart APART, class Pair>
__attribute__((target("avx2"))) void gather_cubics_avx2(const BatchInput& input, const Pair* pairs, std::size_t n,
                                                        Scalar thickness, ChunkCubics& c) {
  std::uint64_t culled_bits = 0, apart_bits = 0;
  std::size_t i = 0;
  for (; i + 4 <= n; i += 4) {
    const Pair* const pair[4] = {pairs + i, pairs + i + 1, pairs + i + 2, pairs + i + 3};
    cubics4<kind, APART>(input, pair, thickness, c, i, culled_bits, apart_bits);
  }
  if (i < n) {  // the tail repeats the last test; its bits are dropped below
    const Pair* const pair[4] = {pairs + i, pairs + std::min(i + 1, n - 1), pairs + std::min(i + 2, n - 1),
                                 pairs + n - 1};
    cubics4<kind, APART>(input, pair, thickness, c, i, culled_bits, apart_bits);
  }
  c.culled = culled_bits & chunk_bits(n);
  c.certainly_apart = apart_bits & chunk_bits(n);
}

// The same kernel eight tests at a time with AVX-512 (F and DQ; where the machine has them):
// the same operations in the same order as cubics4, so the same bits; a test per lane of a
// 512-bit register, so half the instructions for the arithmetic, and 32 registers, so no
// spills. Only the loads and the comparisons (masks instead of vectors) differ in form.
#define DRAPE_AVX512 __attribute__((target("avx512f,avx512dq"), always_inline)) inline
// GCC 12's AVX-512 intrinsics pass an uninitialised source that their full mask never reads,
// and -Wmaybe-uninitialized reports it (fixed in GCC 13; clang has no such warning).
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

struct Lanes8 {
  __m512d x, y, z;
};

DRAPE_AVX512 __m512d max8(__m512d a, __m512d b) { return _mm512_max_pd(b, a); }
DRAPE_AVX512 __m512d min8(__m512d a, __m512d b) { return _mm512_min_pd(b, a); }
DRAPE_AVX512 __m512d abs8(__m512d a) { return _mm512_andnot_pd(_mm512_set1_pd(-0.0), a); }

// Four 128-bit pairs of doubles from p0..p3 into one register.
DRAPE_AVX512 __m512d pairs4(const double* p0, const double* p1, const double* p2, const double* p3) {
  const __m512d lo = _mm512_insertf64x2(_mm512_castpd128_pd512(_mm_loadu_pd(p0)), _mm_loadu_pd(p1), 1);
  return _mm512_insertf64x2(_mm512_insertf64x2(lo, _mm_loadu_pd(p2), 2), _mm_loadu_pd(p3), 3);
}

// load4_point for eight tests: (x, y) and (y, z) of the even and the odd tests, interleaved.
template <class Pair>
DRAPE_AVX512 Lanes8 load8_point(const Vec3* base, const Pair* const (&pair)[8], int point) {
  const double* p[8];
  for (int j = 0; j < 8; ++j) p[j] = base[points(*pair[j])[point]].data();
  const __m512d xy_even = pairs4(p[0], p[2], p[4], p[6]), xy_odd = pairs4(p[1], p[3], p[5], p[7]);
  const __m512d yz_even = pairs4(p[0] + 1, p[2] + 1, p[4] + 1, p[6] + 1);
  const __m512d yz_odd = pairs4(p[1] + 1, p[3] + 1, p[5] + 1, p[7] + 1);
  return {_mm512_unpacklo_pd(xy_even, xy_odd), _mm512_unpacklo_pd(yz_even, yz_odd),
          _mm512_unpackhi_pd(yz_even, yz_odd)};
}

DRAPE_AVX512 Lanes8 sub8(const Lanes8& a, const Lanes8& b) {
  return {_mm512_sub_pd(a.x, b.x), _mm512_sub_pd(a.y, b.y), _mm512_sub_pd(a.z, b.z)};
}

DRAPE_AVX512 Lanes8 cross8(const Lanes8& u, const Lanes8& v) {
  return {_mm512_sub_pd(_mm512_mul_pd(u.y, v.z), _mm512_mul_pd(u.z, v.y)),
          _mm512_sub_pd(_mm512_mul_pd(u.z, v.x), _mm512_mul_pd(u.x, v.z)),
          _mm512_sub_pd(_mm512_mul_pd(u.x, v.y), _mm512_mul_pd(u.y, v.x))};
}

DRAPE_AVX512 __m512d dot8(const Lanes8& u, const Lanes8& w) {
  return _mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(u.x, w.x), _mm512_mul_pd(u.y, w.y)), _mm512_mul_pd(u.z, w.z));
}

DRAPE_AVX512 __m512d l1_8(const Lanes8& s, const Lanes8& e) {
  return max8(_mm512_add_pd(_mm512_add_pd(abs8(s.x), abs8(s.y)), abs8(s.z)),
              _mm512_add_pd(_mm512_add_pd(abs8(e.x), abs8(e.y)), abs8(e.z)));
}

DRAPE_AVX512 __m512d norm8(const Lanes8& u) {
  return _mm512_sqrt_pd(_mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(u.x, u.x), _mm512_mul_pd(u.y, u.y)),
                                      _mm512_mul_pd(u.z, u.z)));
}

// cubics4 for tests i to i + 7.
template <QueryKind kind, Apart APART, class Pair>
DRAPE_AVX512 void cubics8(const BatchInput& input, const Pair* const (&pair)[8], Scalar thickness, ChunkCubics& c,
                          std::size_t i, std::uint64_t& culled_bits, std::uint64_t& apart_bits) {
  constexpr Scalar unit_roundoff = std::numeric_limits<Scalar>::epsilon() / 2;
  constexpr std::array<int, 4> order = coplanarity_order(kind);
  const __m512d zero = _mm512_setzero_pd();
  const Vec3 *start = input.start.data(), *end = input.end.data();
  const Lanes8 s1 = load8_point(start, pair, order[0]), e1 = load8_point(end, pair, order[0]);
  const Lanes8 A0 = sub8(load8_point(start, pair, order[1]), s1), A1 = sub8(load8_point(end, pair, order[1]), e1);
  const Lanes8 s3 = load8_point(start, pair, order[2]), e3 = load8_point(end, pair, order[2]);
  const Lanes8 s4 = load8_point(start, pair, order[3]), e4 = load8_point(end, pair, order[3]);
  const Lanes8 B0 = sub8(s3, s1), B1 = sub8(e3, e1);
  const Lanes8 C0 = sub8(s4, s1), C1 = sub8(e4, e1);
  const Lanes8 b0c0 = cross8(B0, C0), b1c0 = cross8(B1, C0), b0c1 = cross8(B0, C1), b1c1 = cross8(B1, C1);
  const __m512d three = _mm512_set1_pd(3.0);
  const __m512d k0 = dot8(A0, b0c0);
  const __m512d k1 = _mm512_div_pd(_mm512_add_pd(_mm512_add_pd(dot8(A1, b0c0), dot8(A0, b1c0)), dot8(A0, b0c1)), three);
  const __m512d k2 = _mm512_div_pd(_mm512_add_pd(_mm512_add_pd(dot8(A1, b1c0), dot8(A1, b0c1)), dot8(A0, b1c1)), three);
  const __m512d k3 = dot8(A1, b1c1);
  const __m512d a = l1_8(A0, A1), b = l1_8(B0, B1), cc = l1_8(C0, C1);
  const __m512d e = _mm512_mul_pd(
      _mm512_mul_pd(_mm512_mul_pd(_mm512_set1_pd(Scalar(COPLANARITY_ERROR_FACTOR) * unit_roundoff), a), b), cc);
  _mm512_store_pd(&c.coefficient[0][i], k0);
  _mm512_store_pd(&c.coefficient[1][i], k1);
  _mm512_store_pd(&c.coefficient[2][i], k2);
  _mm512_store_pd(&c.coefficient[3][i], k3);
  _mm512_store_pd(&c.error[i], e);
  _mm512_store_pd(&c.extent[i], max8(max8(a, b), cc));
  const __m512d largest = max8(max8(abs8(k0), abs8(k1)), max8(abs8(k2), abs8(k3)));
  const __m512d lo = min8(min8(k0, k1), min8(k2, k3)), hi = max8(max8(k0, k1), max8(k2, k3));
  const __mmask8 resolved =
      _mm512_cmp_pd_mask(largest, _mm512_mul_pd(_mm512_set1_pd(POORLY_RESOLVED_RATIO), e), _CMP_NLE_UQ);
  const __mmask8 one_sign = _mm512_cmp_pd_mask(lo, zero, _CMP_GT_OQ) | _mm512_cmp_pd_mask(hi, zero, _CMP_LT_OQ);
  const __mmask8 ends_clear = _mm512_cmp_pd_mask(min8(abs8(k0), abs8(k3)), e, _CMP_GT_OQ);
  culled_bits |= std::uint64_t(resolved & one_sign & ends_clear) << i;
  if constexpr (APART != Apart::No) {
    __m512d m = e;
    if constexpr (APART == Apart::WithThickness) {
      const __m512d first = max8(norm8(A0), norm8(A1));
      const __m512d second = kind == QueryKind::VertexFace ? max8(norm8(B0), norm8(B1))
                                                           : max8(norm8(sub8(s4, s3)), norm8(sub8(e4, e3)));
      const __m512d share = _mm512_mul_pd(_mm512_mul_pd(_mm512_set1_pd(thickness), _mm512_mul_pd(first, second)),
                                          _mm512_set1_pd(1 + 16 * UNIT_ROUNDOFF));
      m = _mm512_add_pd(e, share);
    }
    const __m512d minus_m = _mm512_sub_pd(zero, m);
    const __mmask8 above = _mm512_cmp_pd_mask(k0, m, _CMP_GT_OQ) & _mm512_cmp_pd_mask(k1, m, _CMP_GT_OQ) &
                           _mm512_cmp_pd_mask(k2, m, _CMP_GT_OQ) & _mm512_cmp_pd_mask(k3, m, _CMP_GT_OQ);
    const __mmask8 below = _mm512_cmp_pd_mask(k0, minus_m, _CMP_LT_OQ) & _mm512_cmp_pd_mask(k1, minus_m, _CMP_LT_OQ) &
                           _mm512_cmp_pd_mask(k2, minus_m, _CMP_LT_OQ) & _mm512_cmp_pd_mask(k3, minus_m, _CMP_LT_OQ);
    apart_bits |= std::uint64_t(resolved & (above | below)) << i;
  }
}

// gather_cubics_avx2 eight tests at a time.
template <QueryKind kind, Apart APART, class Pair>
__attribute__((target("avx512f,avx512dq"))) void gather_cubics_avx512(const BatchInput& input, const Pair* pairs,
                                                                       std::size_t n, Scalar thickness,
                                                                       ChunkCubics& c) {
  std::uint64_t culled_bits = 0, apart_bits = 0;
  std::size_t i = 0;
  for (; i + 8 <= n; i += 8) {
    const Pair* const pair[8] = {pairs + i,     pairs + i + 1, pairs + i + 2, pairs + i + 3,
                                 pairs + i + 4, pairs + i + 5, pairs + i + 6, pairs + i + 7};
    cubics8<kind, APART>(input, pair, thickness, c, i, culled_bits, apart_bits);
  }
  if (i < n) {  // the tail repeats the last test; its bits are dropped below
    const Pair* const pair[8] = {pairs + i,
                                 pairs + std::min(i + 1, n - 1),
                                 pairs + std::min(i + 2, n - 1),
                                 pairs + std::min(i + 3, n - 1),
                                 pairs + std::min(i + 4, n - 1),
                                 pairs + std::min(i + 5, n - 1),
                                 pairs + std::min(i + 6, n - 1),
                                 pairs + n - 1};
    cubics8<kind, APART>(input, pair, thickness, c, i, culled_bits, apart_bits);
  }
  c.culled = culled_bits & chunk_bits(n);
  c.certainly_apart = apart_bits & chunk_bits(n);
}
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif


// Ranges [a_lo, a_hi] and [b_lo, b_hi] farther apart than need, lane by lane.
DRAPE_AVX2 __m256d apart4(__m256d a_lo, __m256d a_hi, __m256d b_lo, __m256d b_hi, __m256d need) {
  return _mm256_or_pd(_mm256_cmp_pd(_mm256_sub_pd(b_lo, a_hi), need, _CMP_GT_OQ),
                      _mm256_cmp_pd(_mm256_sub_pd(a_lo, b_hi), need, _CMP_GT_OQ));
}

// The box of point `point` of four tests over the whole step, and largest raised to its
// coordinates' magnitudes (as boxes_apart_avx2 in separation.cpp).
template <class Pair>
DRAPE_AVX2 void point_box4(const BatchInput& input, const Pair* const (&pair)[4], int point, Lanes3& lo, Lanes3& hi,
                           __m256d& largest) {
  const Lanes3 s = load4_point(input.start.data(), pair, point), e = load4_point(input.end.data(), pair, point);
  const Lanes3 x1 = {_mm256_add_pd(s.x, _mm256_sub_pd(e.x, s.x)), _mm256_add_pd(s.y, _mm256_sub_pd(e.y, s.y)),
                     _mm256_add_pd(s.z, _mm256_sub_pd(e.z, s.z))};
  lo = {min4(s.x, x1.x), min4(s.y, x1.y), min4(s.z, x1.z)};
  hi = {max4(s.x, x1.x), max4(s.y, x1.y), max4(s.z, x1.z)};
  largest = max4(largest, max4(max4(max4(abs4(s.x), abs4(e.x)), max4(abs4(s.y), abs4(e.y))), max4(abs4(s.z), abs4(e.z))));
}

// [box_lo, box_hi] widened to hold [lo, hi].
DRAPE_AVX2 void merge_box4(Lanes3& box_lo, Lanes3& box_hi, const Lanes3& lo, const Lanes3& hi) {
  box_lo = {min4(box_lo.x, lo.x), min4(box_lo.y, lo.y), min4(box_lo.z, lo.z)};
  box_hi = {max4(box_hi.x, hi.x), max4(box_hi.y, hi.y), max4(box_hi.z, hi.z)};
}

// Whether each of four tests goes on to the separation stage, from their cubics b and errors:
// detail::stage_runs (every coefficient finite) and the method's entry gives Stage, vincent's
// (detail::vincent_entry: resolved, and the signs vary or a root is possible at an end; signs
// vary exactly when a coefficient is above zero and another below, zeros skipped as
// sign_variations skips them) or conservative's at zero thickness (detail::conservative_entry:
// resolved, and not certainly nonzero). Only finite lanes need the others' bits: among finite
// coefficients the largest magnitude is the same in any order.
template <bool VINCENT>
DRAPE_AVX2 int reaches_stage4(const __m256d (&b)[4], __m256d error) {
  const __m256d zero = _mm256_setzero_pd(), infinity = _mm256_set1_pd(std::numeric_limits<Scalar>::infinity());
  const __m256d every = _mm256_castsi256_pd(_mm256_set1_epi64x(-1));
  __m256d magnitude[4], finite = every, largest = zero, above = zero, below = zero;
  for (int k = 0; k < 4; ++k) {
    magnitude[k] = abs4(b[k]);
    finite = _mm256_and_pd(finite, _mm256_cmp_pd(magnitude[k], infinity, _CMP_LT_OQ));
    largest = max4(largest, magnitude[k]);
    above = _mm256_or_pd(above, _mm256_cmp_pd(b[k], zero, _CMP_GT_OQ));
    below = _mm256_or_pd(below, _mm256_cmp_pd(b[k], zero, _CMP_LT_OQ));
  }
  const __m256d poorly_resolved =
      _mm256_cmp_pd(largest, _mm256_mul_pd(_mm256_set1_pd(POORLY_RESOLVED_RATIO), error), _CMP_LE_OQ);
  __m256d onward;
  if constexpr (VINCENT) {
    const __m256d at_an_end = _mm256_or_pd(_mm256_cmp_pd(magnitude[0], error, _CMP_LE_OQ),
                                           _mm256_cmp_pd(magnitude[3], error, _CMP_LE_OQ));
    onward = _mm256_or_pd(_mm256_and_pd(above, below), at_an_end);
  } else {
    // Not certainly_nonzero(b, error + 0).
    onward = _mm256_xor_pd(certainly_nonzero4(b, _mm256_add_pd(error, zero)), every);
  }
  return _mm256_movemask_pd(_mm256_and_pd(finite, _mm256_andnot_pd(poorly_resolved, onward)));
}

// The separation stage's first question (detail::coordinate_axes_apart over [0, 1] with the gap
// thickness + tolerance * extent: vincent's detail::contact_distance with the contact tolerance,
// conservative's thickness with 0), four tests at a time: bit j set when the boxes of the
// features of left[j] over the whole step are apart, and need[j] the gap plus the rounding
// margin. The one-query AVX2 box test with a test per lane instead of a coordinate per lane,
// the same decisions and need: the positions at t = 0 and t = 1 are start and start + motion
// (what start + t * motion gives there, but for the sign of a zero, which no decision reads),
// the same minima and maxima. Only read for tests that pass detail::stage_runs (finite
// coordinates). need has room for count rounded up to four. With it, stage: bit j set when
// left[j] goes on to the stage at all (reaches_stage4; vincent's entry, or conservative's).
template <QueryKind kind, bool VINCENT, class Pair>
__attribute__((target("avx2"))) std::uint64_t whole_step_apart_avx2(const BatchInput& input, const Pair* pairs,
                                                                    const Left* left, int count, Scalar thickness_gap,
                                                                    Scalar contact_tolerance, Scalar* need,
                                                                    std::uint64_t& stage) {
  constexpr int split = kind == QueryKind::VertexFace ? 1 : 2;  // points [0, split) are the first feature
  const __m256d thickness = _mm256_set1_pd(thickness_gap), tolerance = _mm256_set1_pd(contact_tolerance);
  const __m256d margin = _mm256_set1_pd(detail::PROJECTION_ERROR_FACTOR * UNIT_ROUNDOFF);
  std::uint64_t apart_bits = 0, stage_bits = 0;
  for (int j = 0; j < count; j += 4) {
    // Four tests (a tail repeats the last one; its bits are dropped below).
    const Left* const test[4] = {left + j, left + std::min(j + 1, count - 1), left + std::min(j + 2, count - 1),
                                 left + std::min(j + 3, count - 1)};
    __m256d b[4];
    for (int k = 0; k < 4; ++k)
      b[k] = _mm256_set_pd(test[3]->cubic.b[k], test[2]->cubic.b[k], test[1]->cubic.b[k], test[0]->cubic.b[k]);
    const __m256d error =
        _mm256_set_pd(test[3]->cubic.error, test[2]->cubic.error, test[1]->cubic.error, test[0]->cubic.error);
    stage_bits |= std::uint64_t(reaches_stage4<VINCENT>(b, error)) << j;
    const Pair* const pair[4] = {pairs + test[0]->index, pairs + test[1]->index, pairs + test[2]->index,
                                 pairs + test[3]->index};
    // Point 0 is always the first feature's, point 3 the second's; point 1 is the vertex-face
    // test's triangle's, the edge-edge test's first edge's.
    __m256d largest = _mm256_setzero_pd();
    Lanes3 a_lo, a_hi, b_lo, b_hi, lo, hi;
    point_box4(input, pair, 0, a_lo, a_hi, largest);
    point_box4(input, pair, 3, b_lo, b_hi, largest);
    point_box4(input, pair, 1, lo, hi, largest);
    merge_box4(split == 1 ? b_lo : a_lo, split == 1 ? b_hi : a_hi, lo, hi);
    point_box4(input, pair, 2, lo, hi, largest);
    merge_box4(b_lo, b_hi, lo, hi);
    const __m256d extent = _mm256_set_pd(test[3]->cubic.extent, test[2]->cubic.extent, test[1]->cubic.extent,
                                         test[0]->cubic.extent);
    const __m256d need4 =
        _mm256_add_pd(_mm256_add_pd(thickness, _mm256_mul_pd(tolerance, extent)), _mm256_mul_pd(margin, largest));
    _mm256_storeu_pd(need + j, need4);
    const __m256d apart = _mm256_or_pd(_mm256_or_pd(apart4(a_lo.x, a_hi.x, b_lo.x, b_hi.x, need4),
                                                    apart4(a_lo.y, a_hi.y, b_lo.y, b_hi.y, need4)),
                                       apart4(a_lo.z, a_hi.z, b_lo.z, b_hi.z, need4));
    apart_bits |= std::uint64_t(_mm256_movemask_pd(apart)) << j;
  }
  stage = stage_bits & chunk_bits(std::size_t(count));
  return apart_bits & chunk_bits(std::size_t(count));
}

// The rest of the separation stage after the whole step's boxes (detail::roots_apart_within,
// no cubic margin), four tests at a time, a test per lane, for the tests whose boxes were not
// apart: the tree of halvings, then the one run of kept sub-intervals through apart_over's axes
// (the coordinate boxes, the shape's axes at the run's midpoint). Which sub-intervals are kept
// and which axis separates are random from one cloth test to the next, so the scalar code's
// branches cost more than its arithmetic; here every lane computes everything, with the scalar
// code's operations in its order (separation.cpp), so the decisions are the same.

// The tree of halvings below b, DEPTH levels deep, as kept_leaves in separation.cpp: lane l of
// kept (a 64-bit integer per lane) gets bit first + i when its sub-interval i may hold a root.
template <int DEPTH>
DRAPE_AVX2 void kept_leaves4(const __m256d (&b)[4], __m256d margin, int first, __m256d& kept) {
  if constexpr (DEPTH == 0) {
    const __m256d bit = _mm256_castsi256_pd(_mm256_set1_epi64x(std::int64_t(1) << first));
    kept = _mm256_or_pd(kept, _mm256_andnot_pd(certainly_nonzero4(b, margin), bit));
  } else {
    const __m256d half = _mm256_set1_pd(0.5);
    const __m256d b01 = _mm256_mul_pd(half, _mm256_add_pd(b[0], b[1]));
    const __m256d b12 = _mm256_mul_pd(half, _mm256_add_pd(b[1], b[2]));
    const __m256d b23 = _mm256_mul_pd(half, _mm256_add_pd(b[2], b[3]));
    const __m256d b012 = _mm256_mul_pd(half, _mm256_add_pd(b01, b12));
    const __m256d b123 = _mm256_mul_pd(half, _mm256_add_pd(b12, b23));
    const __m256d mid = _mm256_mul_pd(half, _mm256_add_pd(b012, b123));
    kept_leaves4<DEPTH - 1>({b[0], b01, b012, mid}, margin, first, kept);
    kept_leaves4<DEPTH - 1>({mid, b123, b23, b[3]}, margin, first + (1 << (DEPTH - 1)), kept);
  }
}

// Whether the projections on axis w (a test per lane) of points [0, split) and [split, 4) over
// [lo, hi] (x0, x1) are farther apart than need scaled by w's 1-norm: apart_along.
DRAPE_AVX2 __m256d apart_along4(const Lanes3 (&x0)[4], const Lanes3 (&x1)[4], int split, const Lanes3& w,
                                __m256d need) {
  const __m256d infinity = _mm256_set1_pd(std::numeric_limits<Scalar>::infinity());
  __m256d a_lo = infinity, a_hi = negate4(infinity), b_lo = infinity, b_hi = negate4(infinity);
  for (int i = 0; i < 4; ++i) {
    const __m256d p0 = dot4(w, x0[i]), p1 = dot4(w, x1[i]);
    const __m256d lo = min4(p0, p1), hi = max4(p0, p1);
    __m256d& group_lo = i < split ? a_lo : b_lo;
    __m256d& group_hi = i < split ? a_hi : b_hi;
    group_lo = min4(group_lo, lo);
    group_hi = max4(group_hi, hi);
  }
  const __m256d scaled = _mm256_mul_pd(need, _mm256_add_pd(_mm256_add_pd(abs4(w.x), abs4(w.y)), abs4(w.z)));
  return apart4(a_lo, a_hi, b_lo, b_hi, scaled);
}

struct StageLanes {
  unsigned decided = 0;  // bit l: lane l's answer is known (no run, or one)
  unsigned apart = 0;    // bit l: the stage separates lane l's features
};

// Tests test[0..3] (tests may repeat), need[l] the gap plus the rounding margin of their whole
// step's boxes. A lane with two runs or more is left undecided, for roots_apart_within.
template <QueryKind kind, class Pair>
__attribute__((target("avx2"))) StageLanes stage_within_avx2(const BatchInput& input, const Pair* pairs,
                                                             const Left* const (&test)[4], const Scalar (&need)[4],
                                                             int depth) {
  depth = std::min(depth, detail::MAX_SEPARATION_DEPTH);
  __m256d b[4];
  for (int k = 0; k < 4; ++k)
    b[k] = _mm256_set_pd(test[3]->cubic.b[k], test[2]->cubic.b[k], test[1]->cubic.b[k], test[0]->cubic.b[k]);
  const __m256d error =
      _mm256_set_pd(test[3]->cubic.error, test[2]->cubic.error, test[1]->cubic.error, test[0]->cubic.error);
  // roots_apart_within's margin (max_abs: the largest of four finite magnitudes, in any order).
  const __m256d largest = max4(max4(max4(abs4(b[0]), abs4(b[1])), abs4(b[2])), abs4(b[3]));
  const __m256d margin = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(_mm256_set1_pd(2.0), error),
                                                     _mm256_mul_pd(_mm256_set1_pd(256 * UNIT_ROUNDOFF), largest)),
                                       _mm256_setzero_pd());
  assert(depth >= 1);  // stage_runs held
  __m256d kept_lanes = _mm256_setzero_pd();
  switch (depth) {
    case 1: kept_leaves4<1>(b, margin, 0, kept_lanes); break;
    case 2: kept_leaves4<2>(b, margin, 0, kept_lanes); break;
    case 3: kept_leaves4<3>(b, margin, 0, kept_lanes); break;
    case 4: kept_leaves4<4>(b, margin, 0, kept_lanes); break;
    case 5: kept_leaves4<5>(b, margin, 0, kept_lanes); break;
    default: kept_leaves4<6>(b, margin, 0, kept_lanes); break;
  }
  alignas(32) std::uint64_t kept_of[4];
  _mm256_store_si256(reinterpret_cast<__m256i*>(kept_of), _mm256_castpd_si256(kept_lanes));
  // Each lane's kept sub-intervals, and its run's time range (widened as apart_over widens it).
  const int leaves = 1 << depth;
  const std::uint64_t all = leaves == 64 ? ~std::uint64_t(0) : (std::uint64_t(1) << leaves) - 1;
  const Scalar width = Scalar(1) / Scalar(leaves);
  StageLanes out;
  unsigned runs = 0;  // lanes with one run to test
  alignas(32) Scalar lo[4] = {0, 0, 0, 0}, hi[4] = {1, 1, 1, 1};
  for (int l = 0; l < 4; ++l) {
    const std::uint64_t kept = kept_of[l];
    if (kept == 0 || kept == all) {  // no root anywhere: apart; roots anywhere: the whole step's boxes said no
      out.decided |= 1u << l;
      out.apart |= unsigned(kept == 0) << l;
      continue;
    }
    const int first = __builtin_ctzll(kept);
    const int past = first + __builtin_ctzll(~(kept >> first));
    if (past < 64 && (kept >> past) != 0) continue;  // another run after this one
    lo[l] = std::max(Scalar(0), first * width - detail::TIME_WIDENING);
    hi[l] = std::min(Scalar(1), past * width + detail::TIME_WIDENING);
    runs |= 1u << l;
  }
  if (runs == 0) return out;
  // The points at the run's ends, as apart_over computes them: start + t * motion.
  const Pair* const pair[4] = {pairs + test[0]->index, pairs + test[1]->index, pairs + test[2]->index,
                               pairs + test[3]->index};
  const __m256d at_lo = _mm256_load_pd(lo), at_hi = _mm256_load_pd(hi);
  Lanes3 x0[4], x1[4];
  for (int i = 0; i < 4; ++i) {
    const Lanes3 s = load4_point(input.start.data(), pair, i), e = load4_point(input.end.data(), pair, i);
    const Lanes3 motion = sub4(e, s);
    x0[i] = {_mm256_add_pd(s.x, _mm256_mul_pd(at_lo, motion.x)), _mm256_add_pd(s.y, _mm256_mul_pd(at_lo, motion.y)),
             _mm256_add_pd(s.z, _mm256_mul_pd(at_lo, motion.z))};
    x1[i] = {_mm256_add_pd(s.x, _mm256_mul_pd(at_hi, motion.x)), _mm256_add_pd(s.y, _mm256_mul_pd(at_hi, motion.y)),
             _mm256_add_pd(s.z, _mm256_mul_pd(at_hi, motion.z))};
  }
  const __m256d need4 = _mm256_loadu_pd(need);
  constexpr int split = kind == QueryKind::VertexFace ? 1 : 2;
  // The coordinate boxes (boxes_apart_avx2): point 0 is always the first feature's, point 3 the
  // second's.
  Lanes3 point_lo[4], point_hi[4];
  for (int i = 0; i < 4; ++i) {
    point_lo[i] = {min4(x0[i].x, x1[i].x), min4(x0[i].y, x1[i].y), min4(x0[i].z, x1[i].z)};
    point_hi[i] = {max4(x0[i].x, x1[i].x), max4(x0[i].y, x1[i].y), max4(x0[i].z, x1[i].z)};
  }
  Lanes3 a_lo = point_lo[0], a_hi = point_hi[0], b_lo = point_lo[3], b_hi = point_hi[3];
  for (int i = 1; i < 3; ++i) merge_box4(i < split ? a_lo : b_lo, i < split ? a_hi : b_hi, point_lo[i], point_hi[i]);
  __m256d apart = _mm256_or_pd(_mm256_or_pd(apart4(a_lo.x, a_hi.x, b_lo.x, b_hi.x, need4),
                                            apart4(a_lo.y, a_hi.y, b_lo.y, b_hi.y, need4)),
                               apart4(a_lo.z, a_hi.z, b_lo.z, b_hi.z, need4));
  // The shape's axes (shape_axes_apart), at the midpoints of the run.
  const __m256d half = _mm256_set1_pd(0.5);
  Lanes3 m[4];
  for (int i = 0; i < 4; ++i)
    m[i] = {_mm256_mul_pd(half, _mm256_add_pd(x0[i].x, x1[i].x)), _mm256_mul_pd(half, _mm256_add_pd(x0[i].y, x1[i].y)),
            _mm256_mul_pd(half, _mm256_add_pd(x0[i].z, x1[i].z))};
  if constexpr (kind == QueryKind::VertexFace) {
    // The in-plane normal of the triangle edge the vertex lies farthest outside of.
    const Lanes3 e[3] = {sub4(m[2], m[1]), sub4(m[3], m[2]), sub4(m[1], m[3])};
    const Lanes3 n = cross4(e[0], {negate4(e[2].x), negate4(e[2].y), negate4(e[2].z)});
    Lanes3 best = cross4(n, e[0]);
    __m256d best_value = _mm256_set1_pd(std::numeric_limits<Scalar>::infinity());
    for (int i = 0; i < 3; ++i) {
      const Lanes3 axis = i == 0 ? best : cross4(n, e[i]);
      const __m256d norm = _mm256_add_pd(_mm256_add_pd(abs4(axis.x), abs4(axis.y)), abs4(axis.z));
      const __m256d value = _mm256_div_pd(dot4(sub4(m[0], m[1 + i]), axis), norm);
      const __m256d lower = _mm256_cmp_pd(value, best_value, _CMP_LT_OQ);
      best_value = _mm256_blendv_pd(best_value, value, lower);
      best = {_mm256_blendv_pd(best.x, axis.x, lower), _mm256_blendv_pd(best.y, axis.y, lower),
              _mm256_blendv_pd(best.z, axis.z, lower)};
    }
    apart = _mm256_or_pd(apart, apart_along4(x0, x1, split, best, need4));
  } else {
    // The in-plane normals of the two edges.
    const Lanes3 a = sub4(m[1], m[0]), b = sub4(m[3], m[2]);
    const Lanes3 n = cross4(a, b);
    apart = _mm256_or_pd(apart, _mm256_or_pd(apart_along4(x0, x1, split, cross4(n, b), need4),
                                             apart_along4(x0, x1, split, cross4(n, a), need4)));
  }
  out.decided |= runs;
  out.apart |= runs & unsigned(_mm256_movemask_pd(apart));
  return out;
}

#endif  // DRAPE_X86_KERNELS

// The tests the chunks' decisions left, in order: the full method on the gathered query. For
// vincent, and conservative at zero thickness, the separation stage is asked here four tests at
// a time (the whole step's boxes, then the rest of it for the tests those do not separate), and
// the tests it separates need nothing else; the others take what it decided to the method.
template <QueryKind kind, class Pair>
void run_left(const BatchInput& input, std::span<const Pair> pairs, const Options& options, const Left* left,
              int count, BatchCounters& counters, std::vector<BatchHit>& hits) {
  const bool stage = options.separation_depth > 0 && detail::avx2_enabled();
  [[maybe_unused]] const bool vincent = options.method == Method::Vincent && stage;
  [[maybe_unused]] const bool conservative = options.method == Method::Conservative && options.thickness == 0 && stage;
  alignas(32) Scalar need[LEFT_MAX + 3];
  // Bits of left: the tests that go on to the separation stage (as vincent_method and
  // conservative_search decide it), and what the stage decided of them here.
  std::uint64_t within = 0, whole_step_apart = 0, decided = 0, apart = 0;
#if DRAPE_X86_KERNELS
  if (vincent || conservative) {
    whole_step_apart =
        vincent ? whole_step_apart_avx2<kind, true>(input, pairs.data(), left, count, options.thickness,
                                                    options.contact_tolerance, need, within)
                : whole_step_apart_avx2<kind, false>(input, pairs.data(), left, count, 0, 0, need, within);
    // The tests whose whole step's boxes were not apart: the rest of the stage four at a time.
    int asked[LEFT_MAX], asked_count = 0;
    for (std::uint64_t rest = within & ~whole_step_apart; rest != 0; rest &= rest - 1)
      asked[asked_count++] = __builtin_ctzll(rest);
    for (int g = 0; g < asked_count; g += 4) {
      int lane[4];
      for (int l = 0; l < 4; ++l) lane[l] = asked[std::min(g + l, asked_count - 1)];
      const Left* const test[4] = {left + lane[0], left + lane[1], left + lane[2], left + lane[3]};
      const Scalar lane_need[4] = {need[lane[0]], need[lane[1]], need[lane[2]], need[lane[3]]};
      const StageLanes s = stage_within_avx2<kind>(input, pairs.data(), test, lane_need, options.separation_depth);
      for (int l = 0; l < 4 && g + l < asked_count; ++l) {
        decided |= std::uint64_t((s.decided >> l) & 1) << lane[l];
        apart |= std::uint64_t((s.apart >> l) & 1) << lane[l];
      }
    }
  }
#endif  // DRAPE_X86_KERNELS
#ifndef NDEBUG
  for (int j = 0; j < count; ++j)
    assert(!(vincent || conservative) ||
           bool((within >> j) & 1) ==
               (detail::stage_runs(left[j].cubic, options.separation_depth) &&
                (vincent ? detail::vincent_entry(left[j].cubic) == detail::VincentEntry::Stage
                         : detail::conservative_entry(left[j].cubic, 0) == detail::ConservativeEntry::Stage)));
#endif
  // The tests the stage separated here, counted at once as roots_apart's answer (Separated).
  const std::uint64_t separated = within & (whole_step_apart | apart);
  const auto separated_count = static_cast<std::uint64_t>(__builtin_popcountll(separated));
  counters.tests += separated_count;
  counters.culled += separated_count;
  counters.separated += separated_count;
  // The others, in order, through the method with what the stage decided of them.
  for (std::uint64_t rest = chunk_bits(std::size_t(count)) & ~separated; rest != 0; rest &= rest - 1) {
    const int j = __builtin_ctzll(rest);
    const std::uint64_t bit = std::uint64_t(1) << j;
    detail::StageAsked asked;  // nothing
    if (within & bit)
      asked = (decided & bit) ? detail::StageAsked{detail::StageAsked::Part::All}
                              : detail::StageAsked{detail::StageAsked::Part::WholeStep, need[j]};
    const Result result =
        detail::run_unculled(kind, gather(input, pairs[left[j].index]), options, left[j].cubic, asked);
    counters.add(result);
    if (result.hit) hits.push_back({left[j].index, result});
  }
}

// The tests [begin, end) of one kind: cubics a chunk at a time; dnf and vincent decide the
// culled ones from the cubic alone, everything else runs the full method on the gathered query.
// Appends the hits to hits and returns the counters of the range.
template <QueryKind kind, class Pair>
BatchCounters run_range(const BatchInput& input, std::span<const Pair> pairs, const Options& options, std::size_t begin,
                        std::size_t end, std::vector<BatchHit>& hits) {
  BatchCounters counters;
  constexpr std::array<int, 4> order = coplanarity_order(kind);
  const bool filter = options.method == Method::Dnf || options.method == Method::Vincent;
  // The conservative method ends a test at its first question when the cubic is certainly
  // farther from zero over the whole step than the thickness lets it come: a miss, counted here
  // as the method counts it. The portable kernel asks it at zero thickness only.
  const bool conservative_first =
      options.method == Method::Conservative && (options.thickness == 0 || detail::avx2_enabled());
  [[maybe_unused]] const Apart apart = !conservative_first ? Apart::No
                     : options.thickness > 0 ? Apart::WithThickness
                                             : Apart::AtZeroThickness;
#if DRAPE_X86_KERNELS
  const bool eight = detail::avx512_enabled();
#endif
  ChunkCubics c;
  Left left[LEFT_MAX];
  int left_count = 0;
  for (std::size_t first = begin; first < end; first += CHUNK) {
    const std::size_t n = std::min(CHUNK, end - first);
    const Pair* const chunk = pairs.data() + first;
    if (!detail::avx2_enabled()) {
      gather_cubics(input, chunk, n, order, c);
    }
#if DRAPE_X86_KERNELS
    else if (eight) {
      switch (apart) {
        case Apart::No: gather_cubics_avx512<kind, Apart::No>(input, chunk, n, options.thickness, c); break;
        case Apart::AtZeroThickness:
          gather_cubics_avx512<kind, Apart::AtZeroThickness>(input, chunk, n, options.thickness, c);
          break;
        case Apart::WithThickness:
          gather_cubics_avx512<kind, Apart::WithThickness>(input, chunk, n, options.thickness, c);
          break;
      }
    } else {
      switch (apart) {
        case Apart::No: gather_cubics_avx2<kind, Apart::No>(input, chunk, n, options.thickness, c); break;
        case Apart::AtZeroThickness:
          gather_cubics_avx2<kind, Apart::AtZeroThickness>(input, chunk, n, options.thickness, c);
          break;
        case Apart::WithThickness:
          gather_cubics_avx2<kind, Apart::WithThickness>(input, chunk, n, options.thickness, c);
          break;
      }
    }
#endif  // DRAPE_X86_KERNELS
    // The tests that end with the chunk's decisions, counted at once; the others kept, in
    // order, and run when a chunk's worth are waiting.
    const std::uint64_t ended = filter ? c.culled : (conservative_first ? c.certainly_apart : 0);
    const auto ended_count = static_cast<std::uint64_t>(__builtin_popcountll(ended));
    counters.tests += ended_count;
    counters.culled += ended_count;
    if (conservative_first) counters.root_solves += ended_count;  // a miss, one interval examined
    for (std::uint64_t rest = chunk_bits(n) & ~ended; rest != 0; rest &= rest - 1) {
      const int i = __builtin_ctzll(rest);
      Left& l = left[left_count++];
      l.index = first + i;
      for (int k = 0; k < 4; ++k) l.cubic.b[k] = c.coefficient[k][i];
      l.cubic.error = c.error[i];
      l.cubic.extent = c.extent[i];
      assert(bool((c.culled >> i) & 1) == filter_culls(l.cubic));
      if (left_count == LEFT_MAX) {
        run_left<kind>(input, pairs, options, left, left_count, counters, hits);
        left_count = 0;
      }
    }
  }
  if (left_count > 0) run_left<kind>(input, pairs, options, left, left_count, counters, hits);
  return counters;
}

}  // namespace

BatchOutput run_batch(const BatchInput& input, const Options& options, int threads) {
  assert(input.start.size() == input.end.size());
  BatchOutput out;
  const std::size_t vf = input.vertex_face.size(), ee = input.edge_edge.size();
  if (threads <= 1) {
    out.counters += run_range<QueryKind::VertexFace>(input, input.vertex_face, options, 0, vf, out.vertex_face);
    out.counters += run_range<QueryKind::EdgeEdge>(input, input.edge_edge, options, 0, ee, out.edge_edge);
    return out;
  }
  // Counters are integer sums and the hits are sorted afterwards: the same whatever the split
  // and the order in which the ranges finish.
  struct Partial {
    BatchCounters counters;
    std::vector<BatchHit> vertex_face, edge_edge;
  };
  tbb::combinable<Partial> partial;
  tbb::task_arena arena(threads);
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, vf, GRAIN), [&](const auto& r) {
      Partial& p = partial.local();
      p.counters += run_range<QueryKind::VertexFace>(input, input.vertex_face, options, r.begin(), r.end(), p.vertex_face);
    });
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, ee, GRAIN), [&](const auto& r) {
      Partial& p = partial.local();
      p.counters += run_range<QueryKind::EdgeEdge>(input, input.edge_edge, options, r.begin(), r.end(), p.edge_edge);
    });
  });
  partial.combine_each([&](const Partial& p) {
    out.counters += p.counters;
    out.vertex_face.insert(out.vertex_face.end(), p.vertex_face.begin(), p.vertex_face.end());
    out.edge_edge.insert(out.edge_edge.end(), p.edge_edge.begin(), p.edge_edge.end());
  });
  const auto by_index = [](const BatchHit& a, const BatchHit& b) { return a.index < b.index; };
  std::sort(out.vertex_face.begin(), out.vertex_face.end(), by_index);
  std::sort(out.edge_edge.begin(), out.edge_edge.end(), by_index);
  return out;
}

}  // namespace drape::ccd
