// The separation stage of the filter: where the coplanarity cubic does have roots in the step,
// the features' boxes over the whole step, or de Casteljau halving that locates the roots in
// short sub-intervals and a separating axis over each, show the features apart there. ccd.md,
// "The separation stage".
#include "separation.h"

#include "kernels.h"

namespace drape::ccd::detail {

namespace {

// Whether the projections p of points [0, split) and [split, 4), at the two times, form ranges
// farther apart than need. For finite coordinates: roots_apart returns before any axis test for
// a cubic that is not finite (a NaN coordinate makes b0 or b3 NaN), so none reaches here from
// the filter.
bool ranges_apart(const Scalar (&p)[4][2], int split, Scalar need) {
  Scalar a_lo = std::numeric_limits<Scalar>::infinity(), a_hi = -a_lo, b_lo = a_lo, b_hi = -a_lo;
  for (int i = 0; i < 4; ++i) {
    const Scalar lo = std::min(p[i][0], p[i][1]), hi = std::max(p[i][0], p[i][1]);
    if (i < split) {
      a_lo = std::min(a_lo, lo);
      a_hi = std::max(a_hi, hi);
    } else {
      b_lo = std::min(b_lo, lo);
      b_hi = std::max(b_hi, hi);
    }
  }
  return (b_lo - a_hi > need) || (a_lo - b_hi > need);
}

// The same on an axis w, with need scaled by w's 1-norm (false for a zero axis: 0 > 0 fails).
bool apart_along(const Vec3 (&x)[4][2], int split, const Vec3& w, Scalar need) {
  Scalar p[4][2];
  for (int i = 0; i < 4; ++i) p[i][0] = w.dot(x[i][0]), p[i][1] = w.dot(x[i][1]);
  return ranges_apart(p, split, need * (std::abs(w[0]) + std::abs(w[1]) + std::abs(w[2])));
}

// The tree of halvings below b, DEPTH levels deep: bit i set when leaf i (left to right) may
// hold a root, that is when its coefficients are not certainly nonzero. Written as a recursion
// the compiler unrolls, so the coefficients stay in registers: the splits of one level are
// independent of each other and run side by side (a loop over an array of levels cost twice).
template <int DEPTH>
__attribute__((always_inline)) inline std::uint64_t kept_leaves(const Bernstein3& b, Scalar margin) {
  if constexpr (DEPTH == 0) {
    return std::uint64_t(!certainly_nonzero(b, margin));
  } else {
    Bernstein3 left, right;
    split_half(b, left, right);
    return kept_leaves<DEPTH - 1>(left, margin) | (kept_leaves<DEPTH - 1>(right, margin) << (1 << (DEPTH - 1)));
  }
}

// The gap plus the rounding margin of the axis tests: the same over every interval of a query.
Scalar gap_and_margin(const Query& q, Scalar gap) {
  return gap + PROJECTION_ERROR_FACTOR * UNIT_ROUNDOFF * max_abs_coordinate(q);
}

// The axes from the features' shape, after the coordinate axes failed (a few percent of the
// calls): out of line, so that the common path inlines into roots_apart.
__attribute__((noinline)) bool shape_axes_apart(QueryKind kind, const Query& q, Scalar lo, Scalar hi, Scalar need) {
  const int split = kind == QueryKind::VertexFace ? 1 : 2;  // the vertex, or edge_a, against the rest
  Vec3 x[4][2];
  for (int i = 0; i < 4; ++i) {
    const Vec3 motion = q.end[i] - q.start[i];
    x[i][0] = q.start[i] + lo * motion;
    x[i][1] = q.start[i] + hi * motion;
  }
  // An axis from the features' shape at the interval's midpoint (any fixed axis is valid;
  // these separate the features where they are coplanar, which is where the cubic's roots are).
  Vec3 m[4];
  for (int i = 0; i < 4; ++i) m[i] = 0.5 * (x[i][0] + x[i][1]);
  if (kind == QueryKind::VertexFace) {
    // The in-plane normal of the triangle edge the vertex lies farthest outside of: the
    // normals n x e point inwards, so that edge has the lowest (v - f) . (n x e) / |n x e|_1.
    const Vec3 e[3] = {m[2] - m[1], m[3] - m[2], m[1] - m[3]};
    const Vec3 n = e[0].cross(-e[2]);
    int best = 0;
    Scalar best_value = std::numeric_limits<Scalar>::infinity();
    Vec3 axis[3];
    for (int i = 0; i < 3; ++i) {
      axis[i] = n.cross(e[i]);
      const Scalar norm = axis[i].lpNorm<1>();
      const Scalar value = (m[0] - m[1 + i]).dot(axis[i]) / norm;
      if (value < best_value) {
        best_value = value;
        best = i;
      }
    }
    return apart_along(x, split, axis[best], need);
  }
  // Coplanar edges whose lines cross outside one of them are separated by the other's line:
  // the in-plane normals of the two edges (parallel edges are left to the coordinate axes).
  const Vec3 a = m[1] - m[0], b = m[3] - m[2];
  const Vec3 n = a.cross(b);
  return apart_along(x, split, n.cross(b), need) || apart_along(x, split, n.cross(a), need);
}

// need: with NEED_GIVEN the query's gap_and_margin, else the gap (and gap_and_margin on return).
template <bool NEED_GIVEN>
inline bool coordinate_axes_apart_inline(QueryKind kind, const Query& q, Scalar lo, Scalar hi, Scalar& need) {
  return one_query_boxes_apart(kind, q, lo, hi, NEED_GIVEN, need);
}

// apart_over with the query's gap_and_margin already known.
inline bool apart_over_with_need(QueryKind kind, const Query& q, Scalar lo, Scalar hi, Scalar need) {
  lo = std::max(Scalar(0), lo - TIME_WIDENING);
  hi = std::min(Scalar(1), hi + TIME_WIDENING);
  // The coordinate axes first: the cheapest, and enough for most far crossings.
  if (coordinate_axes_apart_inline<true>(kind, q, lo, hi, need)) return true;
  return shape_axes_apart(kind, q, lo, hi, need);
}

__attribute__((always_inline)) inline std::uint64_t kept_at_depth(const Bernstein3& b, Scalar margin, int depth) {
  switch (std::clamp(depth, 1, MAX_SEPARATION_DEPTH)) {
    case 1: return kept_leaves<1>(b, margin);
    case 2: return kept_leaves<2>(b, margin);
    case 3: return kept_leaves<3>(b, margin);
    case 4: return kept_leaves<4>(b, margin);
    case 5: return kept_leaves<5>(b, margin);
    default: return kept_leaves<6>(b, margin);
  }
}

}  // namespace

bool apart_over(QueryKind kind, const Query& q, Scalar lo, Scalar hi, Scalar gap) {
  return apart_over_with_need(kind, q, lo, hi, gap_and_margin(q, gap));
}

bool coordinate_axes_apart(QueryKind kind, const Query& q, Scalar lo, Scalar hi, Scalar gap, Scalar& need) {
  need = gap;
  return coordinate_axes_apart_inline<false>(kind, q, lo, hi, need);
}

std::uint64_t kept_sub_intervals(const Bernstein3& b, Scalar margin, int depth) {
  return kept_at_depth(b, margin, depth);
}

bool roots_apart(QueryKind kind, const Query& q, const CoplanarityCubic& cubic, Scalar gap, int depth,
                 Scalar cubic_margin) {
  if (!stage_runs(cubic, depth)) return false;
  const Scalar largest = max_abs_coordinate(q);
  if (!(largest <= STAGE_COORDINATE_LIMIT)) return false;
  // The whole step first: features whose boxes stay apart over it are apart at every root,
  // wherever the cubic has them. Many pairs the broad phase lets through never come that near
  // (its boxes hold whole triangles, or features padded by the thickness), and end here
  // without the tree of halvings. need: the gap and the rounding margin, for every interval.
  Scalar need = gap + PROJECTION_ERROR_FACTOR * UNIT_ROUNDOFF * largest;
  if (coordinate_axes_apart_inline<true>(kind, q, 0, 1, need)) return true;
  return roots_apart_within(kind, q, cubic, need, depth, cubic_margin);
}

bool roots_apart_within(QueryKind kind, const Query& q, const CoplanarityCubic& cubic, Scalar need, int depth,
                        Scalar cubic_margin) {
  depth = std::min(depth, MAX_SEPARATION_DEPTH);
  // A sub-interval holds no root of the exact or the computed cubic, and no sign change of a
  // root finder's evaluation of it, when its coefficients exceed this in one sign: twice the
  // coefficients' error, and the rounding of the halving and of an evaluation in the power
  // basis (Horner). So every root any method could find lies in a kept sub-interval.
  const Scalar margin = 2 * cubic.error + 256 * UNIT_ROUNDOFF * max_abs(cubic.b) + cubic_margin;
  std::uint64_t kept = kept_at_depth(cubic.b, margin, depth);
  const int leaves = 1 << depth;
  if (kept == 0) return true;  // the signs varied, but the cubic does not vanish
  const std::uint64_t all = leaves == 64 ? ~std::uint64_t(0) : (std::uint64_t(1) << leaves) - 1;
  if (kept == all) return false;  // roots may lie anywhere: the whole step's boxes were tested above
  // Each run of adjacent kept sub-intervals is tested once (a cubic has at most three roots).
  const Scalar width = Scalar(1) / Scalar(leaves);
  int runs = 0;
  while (kept != 0) {
    const int first = __builtin_ctzll(kept);
    const int past = first + __builtin_ctzll(~(kept >> first));  // the first dropped one after the run
    if (++runs > 3) return false;
    if (!apart_over_with_need(kind, q, first * width, past * width, need)) return false;
    kept &= past >= 64 ? 0 : (~std::uint64_t(0) << past);
  }
  return true;
}

// The portable box test (kernels.h's one_query_boxes_apart on targets without four lanes of
// doubles): the same interpolated coordinates (start + t * motion, no FMA), exact minima and
// maxima, so the same decisions and need.
bool boxes_apart_scalar(QueryKind kind, const Query& q, Scalar lo, Scalar hi, bool need_given, Scalar& need) {
  const int split = kind == QueryKind::VertexFace ? 1 : 2;
  if (!need_given) need = gap_and_margin(q, need);
  for (int k = 0; k < 3; ++k) {
    Scalar p[4][2];
    for (int i = 0; i < 4; ++i) {
      const Scalar start = q.start[i][k], motion = q.end[i][k] - start;
      p[i][0] = start + lo * motion;
      p[i][1] = start + hi * motion;
    }
    if (ranges_apart(p, split, need)) return true;
  }
  return false;
}

}  // namespace drape::ccd::detail
