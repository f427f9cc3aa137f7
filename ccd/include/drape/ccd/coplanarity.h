#pragma once
/// \file
/// The coplanarity cubic of four moving points, its rounding error and the filter's sign cull.
///
/// The coplanarity cubic d(t) = (x2(t) - x1(t)) x (x3(t) - x1(t)) . (x4(t) - x1(t)) of four
/// linearly moving points (the paper's Section 3.1; ccd-notes.md section 1).

#include <algorithm>
#include <cmath>
#include <limits>

#include "drape/ccd/bernstein.h"
#include "drape/ccd/query.h"

namespace drape::ccd {

/// Safety factor on the rounding-error bound of the coefficients (derivation below).
inline constexpr Scalar COPLANARITY_ERROR_FACTOR = 16.0;

/// The Bernstein coefficients of d on [0, 1], in precision T, with a bound on their rounding
/// error: every |computed b_i - exact b_i| <= error.
template <class T>
struct CoplanarityCubicT {
  std::array<T, 4> b{};
  T error = 0;
  /// Size of the configuration: the largest 1-norm of x2 - x1, x3 - x1 or x4 - x1 at t = 0 or
  /// t = 1. The length unit of the relative contact tolerance.
  T extent = 0;
};
using CoplanarityCubic = CoplanarityCubicT<Scalar>;

/// The query's points as x1..x4 of the paper: vertex-face (face[0], face[1], face[2], vertex),
/// edge-edge (edge_a[0], edge_a[1], edge_b[0], edge_b[1]).
constexpr std::array<int, 4> coplanarity_order(QueryKind kind) {
  return kind == QueryKind::VertexFace ? std::array<int, 4>{1, 2, 3, 0} : std::array<int, 4>{0, 1, 2, 3};
}

/// Bernstein coefficients by blossoming: with A(t), B(t), C(t) = x21, x31, x41 linear in t,
/// b0 = [A0 B0 C0], b1 = ([A1 B0 C0] + [A0 B1 C0] + [A0 B0 C1]) / 3,
/// b2 = ([A1 B1 C0] + [A1 B0 C1] + [A0 B1 C1]) / 3, b3 = [A1 B1 C1], [A B C] = A . (B x C).
/// They are functions of the differences of the input coordinates, so their error is relative
/// to those differences and not to the coordinates' magnitude.
///
/// Error bound: each difference is rounded once; a triple product expands into six products of
/// three differences, each term carrying at most 8 roundings; b1 and b2 add three more. So
/// |error| <= 11 u sum|terms| <= 11 u |A|_1 |B|_1 |C|_1, with u the unit roundoff of T and |.|_1
/// the larger 1-norm over t = 0 and t = 1. COPLANARITY_ERROR_FACTOR (16) replaces the 11.
template <class T>
CoplanarityCubicT<T> coplanarity_cubic_in(QueryKind kind, const Query& query) {
  // Written out in scalars: this is the hot path of every method (a third of the time of a
  // culled test), and the compiler does better with it than with 3-vector expressions.
  const auto order = coplanarity_order(kind);
  T A0[3], A1[3], B0[3], B1[3], C0[3], C1[3];
  for (int k = 0; k < 3; ++k) {
    const T x1s = T(query.start[order[0]][k]), x1e = T(query.end[order[0]][k]);
    A0[k] = T(query.start[order[1]][k]) - x1s;
    A1[k] = T(query.end[order[1]][k]) - x1e;
    B0[k] = T(query.start[order[2]][k]) - x1s;
    B1[k] = T(query.end[order[2]][k]) - x1e;
    C0[k] = T(query.start[order[3]][k]) - x1s;
    C1[k] = T(query.end[order[3]][k]) - x1e;
  }
  const auto cross = [](const T* u, const T* v, T* out) {
    out[0] = u[1] * v[2] - u[2] * v[1];
    out[1] = u[2] * v[0] - u[0] * v[2];
    out[2] = u[0] * v[1] - u[1] * v[0];
  };
  const auto dot = [](const T* u, const T* v) { return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]; };
  // Four cross products serve all eight triple products.
  T B0C0[3], B1C0[3], B0C1[3], B1C1[3];
  cross(B0, C0, B0C0);
  cross(B1, C0, B1C0);
  cross(B0, C1, B0C1);
  cross(B1, C1, B1C1);
  CoplanarityCubicT<T> out;
  out.b[0] = dot(A0, B0C0);
  out.b[1] = (dot(A1, B0C0) + dot(A0, B1C0) + dot(A0, B0C1)) / T(3);
  out.b[2] = (dot(A1, B1C0) + dot(A1, B0C1) + dot(A0, B1C1)) / T(3);
  out.b[3] = dot(A1, B1C1);
  const auto l1 = [](const T* s, const T* e) {
    return std::max(std::abs(s[0]) + std::abs(s[1]) + std::abs(s[2]), std::abs(e[0]) + std::abs(e[1]) + std::abs(e[2]));
  };
  const T unit_roundoff = std::numeric_limits<T>::epsilon() / 2;
  const T a = l1(A0, A1), b = l1(B0, B1), c = l1(C0, C1);
  out.error = T(COPLANARITY_ERROR_FACTOR) * unit_roundoff * a * b * c;
  out.extent = std::max({a, b, c});
  return out;
}

/// The cubic in double precision: what every method starts from.
inline CoplanarityCubic coplanarity_cubic(QueryKind kind, const Query& query) {
  return coplanarity_cubic_in<Scalar>(kind, query);
}

/// Coefficients within this factor of their rounding-error bound leave the cubic's roots
/// unreliable (the motion is coplanar, or nearly, to working precision): the root-finding
/// methods then decide by distance instead (their degenerate path) and the conservative method
/// searches in long double. 2^11 is the gain of long double over double.
inline constexpr Scalar POORLY_RESOLVED_RATIO = 2048.0;
inline bool cubic_poorly_resolved(const CoplanarityCubic& c) { return max_abs(c.b) <= POORLY_RESOLVED_RATIO * c.error; }

/// The sign part of the filter's cull: one strict sign, and both ends clear of their rounding
/// error, so d(t) has no root on [0, 1]. Meaningful for a resolved cubic.
inline bool signs_cull(const CoplanarityCubic& c) {
  return same_strict_sign(c.b) & (std::min(std::abs(c.b[0]), std::abs(c.b[3])) > c.error);
}

/// The filter's cull, shared by dnf and vincent: a resolved cubic that signs_cull.
inline bool filter_culls(const CoplanarityCubic& c) { return !cubic_poorly_resolved(c) & signs_cull(c); }

/// elementary_ccd with the cubic already computed: it must equal coplanarity_cubic(kind, query)
/// bit for bit (the batch entry point computes the cubics of many tests at once).
Result elementary_ccd(QueryKind kind, const Query& query, const Options& options, const CoplanarityCubic& cubic);

}  // namespace drape::ccd
