#pragma once
// Internal to ccd/: the SIMD kernels of the filter and its separation stage, and the
// self-collision culling's normal cones, written once with Google Highway (kernels_batch.cpp,
// kernels_one_query.cpp, kernels_cones.cpp, their lane helpers in lanes-inl.h)
// and compiled for every instruction set Highway targets here
// (its portable one-lane code, SSE4, AVX2, AVX-512), the best one chosen at run time. Every
// kernel gives the scalar code's bits and decisions on every target: the same operations in
// the same order, no FMA, min and max as std::min and std::max (NaN and signed zeros included).

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "drape/ccd/batch.h"
#include "drape/ccd/coplanarity.h"

namespace drape::ccd::detail {

/// A pair's four points, as the one-query functions take them (Query::start and end).
inline std::array<std::int32_t, 4> points(const VertexFacePair& p) { return {p.vertex, p.face[0], p.face[1], p.face[2]}; }
inline std::array<std::int32_t, 4> points(const EdgeEdgePair& p) {
  return {p.edge_a[0], p.edge_a[1], p.edge_b[0], p.edge_b[1]};
}
inline const std::array<std::int32_t, 3>& points(const std::array<std::int32_t, 3>& triangle) { return triangle; }

/// Tests whose cubics a batch computes together, a test per SIMD lane.
constexpr std::size_t CHUNK = 64;

/// The tests [0, n) of a chunk as bits.
inline std::uint64_t chunk_bits(std::size_t n) { return n >= CHUNK ? ~std::uint64_t(0) : (std::uint64_t(1) << n) - 1; }

/// A chunk's cubics, a coordinate array per coefficient, and its decisions as bits.
struct ChunkCubics {
  alignas(64) Scalar coefficient[4][CHUNK], error[CHUNK], extent[CHUNK];
  static_assert(CHUNK == 64, "one bit per test of a chunk in a 64-bit mask");
  std::uint64_t culled = 0;  ///< bit i: filter_culls of test i's cubic
  /// Bit i: the conservative method's first question, asked only with Apart other than No:
  /// resolved, and every coefficient beyond its error, plus with a thickness its share of the
  /// cubic (thickness_to_cubic), in one sign (certainly_nonzero on the whole step).
  std::uint64_t certainly_apart = 0;
};

/// Which of the conservative method's first question the cubic kernel asks: none, at zero
/// thickness (the error alone), or with the thickness's share of the cubic.
enum class Apart { No, AtZeroThickness, WithThickness };

/// The cubics of pairs [0, n), n <= CHUNK, into c.
void chunk_cubics(const BatchInput& input, const VertexFacePair* pairs, std::size_t n, Apart apart, Scalar thickness,
                  ChunkCubics& c);
void chunk_cubics(const BatchInput& input, const EdgeEdgePair* pairs, std::size_t n, Apart apart, Scalar thickness,
                  ChunkCubics& c);

/// A test a chunk's decisions left (not culled, not certainly apart), with its cubic.
struct Left {
  std::size_t index;
  CoplanarityCubic cubic;
};
constexpr int LEFT_MAX = 64;

/// The separation stage for left[0, count) (count <= LEFT_MAX), a test per lane, as the methods
/// ask it (stage_runs, then vincent_entry or conservative_entry at zero thickness):
/// - stage: bit j when left[j] goes on to the stage at all;
/// - whole_step_apart: of those, the ones whose features' boxes over the whole step are more
///   than the gap (vincent: contact_distance; conservative: its thickness, 0 here) apart, with
///   need[j] that gap plus the rounding margin (coordinate_axes_apart over [0, 1]);
/// - decided, apart: of the others, those roots_apart_within answers from the tree of halvings
///   and at most one run of kept sub-intervals (depth levels), and which of them it separates.
struct StageBits {
  std::uint64_t stage = 0, whole_step_apart = 0, decided = 0, apart = 0;
  Scalar need[LEFT_MAX];
};
StageBits separation_stage(const BatchInput& input, const VertexFacePair* pairs, const Left* left, int count,
                           bool vincent, Scalar gap, Scalar contact_tolerance, int depth);
StageBits separation_stage(const BatchInput& input, const EdgeEdgePair* pairs, const Left* left, int count,
                           bool vincent, Scalar gap, Scalar contact_tolerance, int depth);

/// The cubic of one query, a point's coordinates in the lanes of one vector where the target
/// has four lanes of doubles (coplanarity_cubic's bits; the scalar code elsewhere). With cull,
/// returns filter_culls and writes cubic only when it is false.
bool one_query_cubic(QueryKind kind, const Query& query, bool cull, CoplanarityCubic& cubic);

/// coordinate_axes_apart's box test on one query over [lo, hi], the coordinates in lanes where
/// the target has four lanes of doubles: with need_given need is the query's gap and margin,
/// else need holds the gap and receives the gap and margin.
bool one_query_boxes_apart(QueryKind kind, const Query& q, Scalar lo, Scalar hi, bool need_given, Scalar& need);

/// The normal cones of a patch tree's leaves (patch_tree.cpp), a leaf per lane. The least
/// cosine, between a cone's axis and any normal coefficient, of a cone that counts as within 90
/// degrees (89.99994 degrees): far above the error of the computed directions, which DEGENERATE
/// bounds. A normal coefficient shorter than DEGENERATE times the product of its edges' lengths
/// is a degenerate triangle whose computed direction means nothing: its patches are never culled.
constexpr Scalar CONE_MARGIN = 1e-6;
constexpr Scalar DEGENERATE = 1e-8;
/// Triangles a leaf holds at most (PatchTree's leaves hold no more).
constexpr std::int32_t CONE_LEAF_TRIANGLES = 8;
/// Leaf l's cone over a step: sum, the sum of its triangles' normal coefficients (each
/// triangle's normal (x1 - x0) x (x2 - x0), a quadratic in t over the step, by its three
/// Bernstein coefficients, which bound it); axis, the sum's direction ((0, 0, 1) when it is
/// zero); cos and sin of the least angle between the axis and any coefficient (cos 0 when a
/// coefficient is not on the axis' side or is degenerate), and bit l of ok when every
/// coefficient is within 90 degrees of it by CONE_MARGIN (cos above it) and none is degenerate.
struct ChunkCones {
  alignas(64) Scalar sum[3][CHUNK], axis[3][CHUNK], cos[CHUNK], sin[CHUNK];
  std::uint64_t ok = 0;
};
/// The cones of leaves [0, n), n <= CHUNK: leaf l's triangles are triangles[first[l],
/// first[l] + count[l]), 1 <= count[l] <= CONE_LEAF_TRIANGLES, their corners at start and end.
void chunk_cones(const Vec3* start, const Vec3* end, const std::array<std::int32_t, 3>* triangles,
                 const std::int32_t* first, const std::int32_t* count, std::size_t n, ChunkCones& c);

/// For tests: the targets this build compiled and this machine runs, best first (the last is
/// the portable one-lane code); restricting the kernels to one of them (0: all again); the
/// name of the one that runs now; on the target that runs, the helpers min, max and abs lane
/// by lane (n a multiple of 8), and the batch's filter decision for n cubics.
std::vector<std::int64_t> kernel_targets();
void use_kernel_target(std::int64_t target);
std::string kernel_target_name();
void min_max_abs(const double* a, const double* b, std::size_t n, double* min, double* max, double* abs);
void filter_decisions(const CoplanarityCubic* cubics, std::size_t n, bool* culled);

}  // namespace drape::ccd::detail
