#pragma once
/// \file
/// The coplanarity cubic d(t) = (x2(t) - x1(t)) x (x3(t) - x1(t)) . (x4(t) - x1(t)) of four
/// linearly moving points (the paper's Section 3.1; ccd-notes.md section 1).

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
};
using CoplanarityCubic = CoplanarityCubicT<Scalar>;

/// The query's points as x1..x4 of the paper: vertex-face (face[0], face[1], face[2], vertex),
/// edge-edge (edge_a[0], edge_a[1], edge_b[0], edge_b[1]).
inline std::array<int, 4> coplanarity_order(QueryKind kind) {
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
  using V = Eigen::Matrix<T, 3, 1>;
  const auto order = coplanarity_order(kind);
  const auto start = [&](int i) -> V { return query.start[order[i]].template cast<T>(); };
  const auto end = [&](int i) -> V { return query.end[order[i]].template cast<T>(); };
  const V x1s = start(0), x1e = end(0);
  const V A0 = start(1) - x1s, A1 = end(1) - x1e;
  const V B0 = start(2) - x1s, B1 = end(2) - x1e;
  const V C0 = start(3) - x1s, C1 = end(3) - x1e;
  // Four cross products serve all eight triple products.
  const V B0C0 = B0.cross(C0), B1C0 = B1.cross(C0), B0C1 = B0.cross(C1), B1C1 = B1.cross(C1);
  CoplanarityCubicT<T> out;
  out.b[0] = A0.dot(B0C0);
  out.b[1] = (A1.dot(B0C0) + A0.dot(B1C0) + A0.dot(B0C1)) / T(3);
  out.b[2] = (A1.dot(B1C0) + A1.dot(B0C1) + A0.dot(B1C1)) / T(3);
  out.b[3] = A1.dot(B1C1);
  const auto l1 = [](const V& s, const V& e) { return std::max(s.template lpNorm<1>(), e.template lpNorm<1>()); };
  const T unit_roundoff = std::numeric_limits<T>::epsilon() / 2;
  out.error = T(COPLANARITY_ERROR_FACTOR) * unit_roundoff * l1(A0, A1) * l1(B0, B1) * l1(C0, C1);
  return out;
}

/// The cubic in double precision: what every method starts from.
inline CoplanarityCubic coplanarity_cubic(QueryKind kind, const Query& query) {
  return coplanarity_cubic_in<Scalar>(kind, query);
}

/// Power-basis coefficients a0..a3 by the formulas of the paper (Provot's form). Used to check
/// the Bernstein form.
Power3 coplanarity_power(QueryKind kind, const Query& query);

}  // namespace drape::ccd
