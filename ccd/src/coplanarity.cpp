#include "drape/ccd/coplanarity.h"

#include "avx2.h"
#include "problem.h"

namespace drape::ccd {
Power3 coplanarity_power(QueryKind kind, const Query& query) {
  const auto order = coplanarity_order(kind);
  const auto x = [&](int i) -> const Vec3& { return query.start[order[i - 1]]; };
  const auto v = [&](int i) -> Vec3 { return query.end[order[i - 1]] - query.start[order[i - 1]]; };
  const Vec3 x21 = x(2) - x(1), x31 = x(3) - x(1), x41 = x(4) - x(1);
  const Vec3 v21 = v(2) - v(1), v31 = v(3) - v(1), v41 = v(4) - v(1);
  const Vec3 mixed = v21.cross(x31) + x21.cross(v31);
  return {x21.cross(x31).dot(x41), mixed.dot(x41) + x21.cross(x31).dot(v41),
          v21.cross(v31).dot(x41) + mixed.dot(v41), v21.cross(v31).dot(v41)};
}

namespace detail {

#if DRAPE_X86_KERNELS
namespace {

// coplanarity_cubic_in<double> for one query with AVX2: a point's x, y, z in lanes 0-2 of one
// register (lane 3 is never summed), the cross products by lane permutations, the eight triple
// products summed across lanes after a 4x4 transpose, the six 1-norms by horizontal adds. Every
// rounded operation is the scalar code's, on the same operands in the same order (no FMA;
// x + (-0) = x where a lane must pass a value through), so the bits are the same. About a
// third of its instructions.

// (u1, u2, u0) and (u2, u0, u1): u x v = yzx(u) zxy(v) - zxy(u) yzx(v), lane by lane.
DRAPE_AVX2 __m256d yzx(__m256d u) { return _mm256_permute4x64_pd(u, _MM_SHUFFLE(3, 0, 2, 1)); }
DRAPE_AVX2 __m256d zxy(__m256d u) { return _mm256_permute4x64_pd(u, _MM_SHUFFLE(3, 1, 0, 2)); }
DRAPE_AVX2 __m256d cross(__m256d uyzx, __m256d uzxy, __m256d vyzx, __m256d vzxy) {
  return _mm256_sub_pd(_mm256_mul_pd(uyzx, vzxy), _mm256_mul_pd(uzxy, vyzx));
}

// Lane i of the result: (p_i[0] + p_i[1]) + p_i[2], the scalar code's order of a 3-term sum.
DRAPE_AVX2 __m256d lane_sums(__m256d p0, __m256d p1, __m256d p2, __m256d p3) {
  const __m256d t0 = _mm256_unpacklo_pd(p0, p1), t1 = _mm256_unpackhi_pd(p0, p1);
  const __m256d t2 = _mm256_unpacklo_pd(p2, p3), t3 = _mm256_unpackhi_pd(p2, p3);
  const __m256d x = _mm256_permute2f128_pd(t0, t2, 0x20), y = _mm256_permute2f128_pd(t1, t3, 0x20);
  const __m256d z = _mm256_permute2f128_pd(t0, t2, 0x31);
  return _mm256_add_pd(_mm256_add_pd(x, y), z);
}

// std::max(|s|_1, |e|_1) for points s, e with x, y, z in lanes 0-2: the absolute values with
// lane 3 cleared, so that a horizontal add gives |x| + |y| and |z| + 0 = |z|, then their sum;
// the larger by maxsd with the operands swapped (see max4).
DRAPE_AVX2 Scalar larger_norm(__m256d s, __m256d e) {
  const __m256d abs_xyz = _mm256_castsi256_pd(_mm256_set_epi64x(0, 0x7fffffffffffffff, 0x7fffffffffffffff,
                                                                 0x7fffffffffffffff));
  const __m256d h = _mm256_hadd_pd(_mm256_and_pd(s, abs_xyz), _mm256_and_pd(e, abs_xyz));
  const __m128d n = _mm_add_pd(_mm256_castpd256_pd128(h), _mm256_extractf128_pd(h, 1));  // |s|_1, |e|_1
  return _mm_cvtsd_f64(_mm_max_sd(_mm_unpackhi_pd(n, n), n));
}

// The cubic of one query, into out; with CULL, first the filter's decision, and out is
// written only when the filter does not cull (returns true when it does).
template <QueryKind kind, bool CULL>
__attribute__((target("avx2"))) bool cubic_avx2(const Query& query, CoplanarityCubic& out) {
  constexpr std::array<int, 4> order = coplanarity_order(kind);
  const __m256d x1s = load_start(query, order[0]), x1e = load_end(query, order[0]);
  const __m256d A0 = _mm256_sub_pd(load_start(query, order[1]), x1s);
  const __m256d A1 = _mm256_sub_pd(load_end(query, order[1]), x1e);
  const __m256d B0 = _mm256_sub_pd(load_start(query, order[2]), x1s);
  const __m256d B1 = _mm256_sub_pd(load_end(query, order[2]), x1e);
  const __m256d C0 = _mm256_sub_pd(load_start(query, order[3]), x1s);
  const __m256d C1 = _mm256_sub_pd(load_end(query, order[3]), x1e);
  const __m256d B0yzx = yzx(B0), B0zxy = zxy(B0), B1yzx = yzx(B1), B1zxy = zxy(B1);
  const __m256d C0yzx = yzx(C0), C0zxy = zxy(C0), C1yzx = yzx(C1), C1zxy = zxy(C1);
  const __m256d B0C0 = cross(B0yzx, B0zxy, C0yzx, C0zxy), B1C0 = cross(B1yzx, B1zxy, C0yzx, C0zxy);
  const __m256d B0C1 = cross(B0yzx, B0zxy, C1yzx, C1zxy), B1C1 = cross(B1yzx, B1zxy, C1yzx, C1zxy);
  // first: [A0 B0 C0], [A1 B0 C0], [A1 B1 C0], [A1 B1 C1] (the first terms of b0..b3);
  // rest: [A0 B1 C0], [A1 B0 C1] (second terms of b1, b2), [A0 B0 C1], [A0 B1 C1] (third).
  const __m256d first = lane_sums(_mm256_mul_pd(A0, B0C0), _mm256_mul_pd(A1, B0C0), _mm256_mul_pd(A1, B1C0),
                                  _mm256_mul_pd(A1, B1C1));
  const __m256d rest = lane_sums(_mm256_mul_pd(A0, B1C0), _mm256_mul_pd(A1, B0C1), _mm256_mul_pd(A0, B0C1),
                                 _mm256_mul_pd(A0, B1C1));
  const __m256d negative_zero = _mm256_set1_pd(-0.0);
  const __m256d second = _mm256_blend_pd(_mm256_permute4x64_pd(rest, _MM_SHUFFLE(3, 1, 0, 0)), negative_zero, 0b1001);
  const __m256d third = _mm256_blend_pd(_mm256_permute4x64_pd(rest, _MM_SHUFFLE(3, 3, 2, 2)), negative_zero, 0b1001);
  const __m256d b = _mm256_div_pd(_mm256_add_pd(_mm256_add_pd(first, second), third), _mm256_set_pd(1, 3, 3, 1));
  // 1-norms of A0, A1, B0, B1 and C0, C1; a, b, c the larger of each pair.
  const Scalar a = larger_norm(A0, A1), bb = larger_norm(B0, B1), c = larger_norm(C0, C1);
  const Scalar error = Scalar(COPLANARITY_ERROR_FACTOR) * UNIT_ROUNDOFF * a * bb * c;
  if (CULL && filter_culls_avx2(b, error)) return true;
  // Two 128-bit stores: the caller copies the result 16 bytes at a time, and a 16-byte load
  // from the upper half of one 32-byte store may not be forwarded from it.
  _mm_storeu_pd(out.b.data(), _mm256_castpd256_pd128(b));
  _mm_storeu_pd(out.b.data() + 2, _mm256_extractf128_pd(b, 1));
  out.error = error;
  out.extent = std::max({a, bb, c});
  return false;
}

}  // namespace


CoplanarityCubic vertex_face_cubic_avx2(const Query& query) {
  CoplanarityCubic out;
  cubic_avx2<QueryKind::VertexFace, false>(query, out);
  return out;
}

CoplanarityCubic edge_edge_cubic_avx2(const Query& query) {
  CoplanarityCubic out;
  cubic_avx2<QueryKind::EdgeEdge, false>(query, out);
  return out;
}

bool vertex_face_culled_avx2(const Query& query, CoplanarityCubic& cubic) {
  return cubic_avx2<QueryKind::VertexFace, true>(query, cubic);
}

bool edge_edge_culled_avx2(const Query& query, CoplanarityCubic& cubic) {
  return cubic_avx2<QueryKind::EdgeEdge, true>(query, cubic);
}

#endif  // DRAPE_X86_KERNELS
}  // namespace detail
}  // namespace drape::ccd
