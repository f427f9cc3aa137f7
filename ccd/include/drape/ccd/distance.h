#pragma once
/// \file
/// Closest points between a point and a triangle and between two segments.
///
/// Closest points between a point and a triangle and between two segments, robust to zero-area
/// triangles, zero-length and parallel segments. The regions follow Ericson, "Real-Time
/// Collision Detection" (2005), sections 5.1.5 and 5.1.9.
///
/// Templates over the floating-point type: the conservative CCD method re-examines the few
/// queries that double precision cannot decide in long double. Everything else uses double.

#include <algorithm>
#include <cmath>
#include <limits>

#include "drape/ccd/types.h"

namespace drape::ccd {

template <class T>
using Vector3 = Eigen::Matrix<T, 3, 1>;

template <class T>
struct PointTriangleClosestT {
  T distance_squared = 0;
  Vector3<T> point = Vector3<T>::Zero();  ///< closest point on the triangle
  /// Barycentric weights of the triangle's corners b and c at that point (a has 1 - sum).
  T weight_b = 0;
  T weight_c = 0;
};

template <class T>
struct SegmentSegmentClosestT {
  T distance_squared = 0;
  Vector3<T> point_a = Vector3<T>::Zero();  ///< closest point on segment a
  Vector3<T> point_b = Vector3<T>::Zero();  ///< closest point on segment b
  T s = 0;                                  ///< parameter of point_a along a0 -> a1
  T u = 0;                                  ///< parameter of point_b along b0 -> b1
};

using PointTriangleClosest = PointTriangleClosestT<Scalar>;
using SegmentSegmentClosest = SegmentSegmentClosestT<Scalar>;

/// Relative area below which a triangle is treated as the union of its edges: the barycentric
/// solve would divide by a number lost in rounding. |n|^2 <= this * (longest edge)^4.
inline constexpr Scalar DEGENERATE_TRIANGLE_RATIO = 1e-24;

/// Parameter in [0, 1] of the point of segment ab closest to p.
template <class T>
T closest_point_segment_parameter(const Vector3<T>& p, const Vector3<T>& a, const Vector3<T>& b) {
  const Vector3<T> ab = b - a;
  const T length_squared = ab.squaredNorm();
  if (!(length_squared > 0)) return 0;
  return std::clamp<T>((p - a).dot(ab) / length_squared, 0, 1);
}

namespace detail {

// Closest point over the three edges: the answer for a zero-area triangle.
template <class T>
PointTriangleClosestT<T> closest_on_edges(const Vector3<T>& p, const Vector3<T>& a, const Vector3<T>& b,
                                          const Vector3<T>& c) {
  PointTriangleClosestT<T> best;
  best.distance_squared = std::numeric_limits<T>::infinity();
  const Vector3<T>* corners[3] = {&a, &b, &c};
  const T weights[3][2] = {{0, 0}, {1, 0}, {0, 1}};
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3;
    const T s = closest_point_segment_parameter(p, *corners[i], *corners[j]);
    const Vector3<T> q = *corners[i] + s * (*corners[j] - *corners[i]);
    const T d2 = (p - q).squaredNorm();
    if (d2 < best.distance_squared) {
      best.distance_squared = d2;
      best.point = q;
      best.weight_b = (1 - s) * weights[i][0] + s * weights[j][0];
      best.weight_c = (1 - s) * weights[i][1] + s * weights[j][1];
    }
  }
  return best;
}

}  // namespace detail

/// Closest point of triangle (a, b, c) to p. A zero-area triangle is treated as the union of
/// its edges.
template <class T>
PointTriangleClosestT<T> closest_point_triangle(const Vector3<T>& p, const Vector3<T>& a, const Vector3<T>& b,
                                                const Vector3<T>& c) {
  const Vector3<T> ab = b - a;
  const Vector3<T> ac = c - a;
  const T longest = std::max({ab.squaredNorm(), ac.squaredNorm(), (c - b).squaredNorm()});
  if (!(ab.cross(ac).squaredNorm() > T(DEGENERATE_TRIANGLE_RATIO) * longest * longest))
    return detail::closest_on_edges(p, a, b, c);

  PointTriangleClosestT<T> out;
  const auto finish = [&](T wb, T wc) {
    out.weight_b = wb;
    out.weight_c = wc;
    out.point = a + wb * ab + wc * ac;
    out.distance_squared = (p - out.point).squaredNorm();
    return out;
  };
  const Vector3<T> ap = p - a;
  const T d1 = ab.dot(ap);
  const T d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return finish(0, 0);  // vertex region a
  const Vector3<T> bp = p - b;
  const T d3 = ab.dot(bp);
  const T d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return finish(1, 0);  // vertex region b
  const T vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return finish(d1 / (d1 - d3), 0);  // edge ab
  const Vector3<T> cp = p - c;
  const T d5 = ab.dot(cp);
  const T d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return finish(0, 1);  // vertex region c
  const T vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return finish(0, d2 / (d2 - d6));  // edge ac
  const T va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {  // edge bc
    const T w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return finish(1 - w, w);
  }
  const T denominator = va + vb + vc;
  if (!(denominator > 0)) return detail::closest_on_edges(p, a, b, c);
  return finish(vb / denominator, vc / denominator);  // face interior
}

/// Closest points of segments a0a1 and b0b1. Parallel segments get one of their closest pairs.
template <class T>
SegmentSegmentClosestT<T> closest_segment_segment(const Vector3<T>& a0, const Vector3<T>& a1, const Vector3<T>& b0,
                                                  const Vector3<T>& b1) {
  const Vector3<T> da = a1 - a0;
  const Vector3<T> db = b1 - b0;
  const Vector3<T> r = a0 - b0;
  const T aa = da.squaredNorm();
  const T bb = db.squaredNorm();
  const T f = db.dot(r);
  T s = 0;
  T u = 0;
  if (!(aa > 0) && !(bb > 0)) {
    // Both segments are points.
  } else if (!(aa > 0)) {
    u = std::clamp<T>(f / bb, 0, 1);
  } else {
    const T c = da.dot(r);
    if (!(bb > 0)) {
      s = std::clamp<T>(-c / aa, 0, 1);
    } else {
      const T ab = da.dot(db);
      const T denominator = aa * bb - ab * ab;  // >= 0, zero for parallel segments
      s = denominator > 0 ? std::clamp<T>((ab * f - c * bb) / denominator, 0, 1) : T(0);
      u = (ab * s + f) / bb;
      if (u < 0) {
        u = 0;
        s = std::clamp<T>(-c / aa, 0, 1);
      } else if (u > 1) {
        u = 1;
        s = std::clamp<T>((ab - c) / aa, 0, 1);
      }
    }
  }
  SegmentSegmentClosestT<T> out;
  out.s = s;
  out.u = u;
  out.point_a = a0 + s * da;
  out.point_b = b0 + u * db;
  out.distance_squared = (out.point_a - out.point_b).squaredNorm();
  return out;
}

}  // namespace drape::ccd

namespace drape::ccd {

/// A distance with a bound on how far it may exceed the true distance because of the
/// conditioning of the closest-point formulas (not counting the rounding of the positions).
/// The conservative CCD method excludes a contact only when distance - error is positive.
template <class T>
struct DistanceEstimate {
  T distance = 0;
  T error = 0;
  T param0 = 0;  ///< vertex-face: weight of b; edge-edge: s
  T param1 = 0;  ///< vertex-face: weight of c; edge-edge: u
};

/// Safety factor of the conditioning bounds below, in units of the unit roundoff.
inline constexpr Scalar CONDITIONING_ERROR_FACTOR = 16.0;

/// Safety factor of the rounding margin of the estimates' inside tests below (a triple product
/// of a cross product with the normal, each rounded: about 11 u l^3 |offset|), in units of u.
inline constexpr Scalar INSIDE_MARGIN_FACTOR = 32.0;

/// Point-triangle distance, never more than error above the true one (but for the rounding of
/// the positions themselves). Where the triangle is well enough shaped, the distance to its
/// plane (error about u |ap| l^2 / |n|, l the longest edge, |n| twice the area), taken when the
/// point projects inside the triangle by sign tests widened by their rounding, else the
/// distance to its edges; both never exceed the true distance by more than their rounding.
/// (Barycentric weights from the closest-point regions are off by u l^4 / |n|^2, and the point
/// they give by l times that: on a thin triangle, far more than the plane distance's error.)
/// On a thinner triangle the edges alone, which overestimate by at most its width |n| / l.
template <class T>
DistanceEstimate<T> point_triangle_distance(const Vector3<T>& p, const Vector3<T>& a, const Vector3<T>& b,
                                            const Vector3<T>& c) {
  const T u = std::numeric_limits<T>::epsilon() / 2;
  const Vector3<T> ab = b - a, ac = c - a, ap = p - a;
  const T longest = std::sqrt(std::max({ab.squaredNorm(), ac.squaredNorm(), (c - b).squaredNorm()}));
  const Vector3<T> n = ab.cross(ac);
  const T twice_area = n.norm();
  const T local = std::max(longest, ap.norm());
  const T face_error = T(CONDITIONING_ERROR_FACTOR) * u * local * longest * longest / twice_area;
  const T width = longest > 0 ? twice_area / longest : T(0);
  DistanceEstimate<T> out;
  if (twice_area > 0 && face_error < width) {
    // Signed areas of the point's projection against each edge, times |n|^2: all >= 0 inside.
    const T weight_a = (c - b).cross(p - b).dot(n), weight_b = (a - c).cross(p - c).dot(n);
    const T weight_c = ab.cross(ap).dot(n);
    const T margin = T(INSIDE_MARGIN_FACTOR) * u * longest * longest * longest * local;
    if (weight_a >= -margin && weight_b >= -margin && weight_c >= -margin) {
      const T n2 = twice_area * twice_area;
      out.distance = std::abs(ap.dot(n)) / twice_area;
      out.error = face_error;
      out.param0 = std::clamp<T>(weight_b / n2, 0, 1);
      out.param1 = std::clamp<T>(weight_c / n2, 0, 1);
      return out;
    }
  }
  // Outside the triangle (certainly, in the branch above), or too thin: its edges.
  const auto closest = detail::closest_on_edges<T>(p, a, b, c);
  out.distance = std::sqrt(closest.distance_squared);
  out.error = (twice_area > 0 && face_error < width) ? T(CONDITIONING_ERROR_FACTOR) * u * local
                                                     : width + T(CONDITIONING_ERROR_FACTOR) * u * local;
  out.param0 = closest.weight_b;
  out.param1 = closest.weight_c;
  return out;
}

/// Segment-segment distance, never more than error above the true one (but for the rounding of
/// the positions). The four endpoint-to-segment distances, and, where the segments are far
/// enough from parallel, the distance between their lines (error about u (|w| + l) l^2 / |n|,
/// n = da x db, w = b0 - a0) when both closest points of the lines lie within the segments by
/// sign tests widened by their rounding (else the segments' closest pair has an endpoint). Nearer
/// parallel, the endpoints alone, which overestimate by at most l sin(angle), l the longer segment.
template <class T>
DistanceEstimate<T> segment_segment_distance(const Vector3<T>& a0, const Vector3<T>& a1, const Vector3<T>& b0,
                                             const Vector3<T>& b1) {
  const T u = std::numeric_limits<T>::epsilon() / 2;
  const Vector3<T> da = a1 - a0, db = b1 - b0, w = b0 - a0;
  const T la = da.norm(), lb = db.norm();
  const T longest = std::max(la, lb);
  const T local = longest + w.norm();
  const Vector3<T> n = da.cross(db);
  const T n_norm = n.norm();
  const T sine = (la > 0 && lb > 0) ? std::min<T>(n_norm / (la * lb) + 4 * u, 1) : T(1);
  const T line_error = T(CONDITIONING_ERROR_FACTOR) * u * local * longest * longest / n_norm;
  const T rounding = T(CONDITIONING_ERROR_FACTOR) * u * local;
  const T endpoint_error = longest * sine + rounding;

  // The four endpoint-to-segment distances (squared; one square root at the end).
  DistanceEstimate<T> out;
  T best = std::numeric_limits<T>::infinity();
  const Vector3<T>* ends[4] = {&a0, &a1, &b0, &b1};
  for (int e = 0; e < 4; ++e) {
    const bool on_a = e < 2;  // the endpoint belongs to segment a; measure to segment b
    const Vector3<T>& from = on_a ? b0 : a0;
    const Vector3<T>& to = on_a ? b1 : a1;
    const T t = closest_point_segment_parameter<T>(*ends[e], from, to);
    const T d2 = (*ends[e] - (from + t * (to - from))).squaredNorm();
    if (d2 < best) {
      best = d2;
      out.param0 = on_a ? T(e) : t;
      out.param1 = on_a ? t : T(e - 2);
    }
  }
  out.distance = std::sqrt(best);
  if (!(n_norm > 0 && line_error < endpoint_error)) {
    out.error = endpoint_error;
    return out;
  }
  out.error = std::max(line_error, rounding);
  // The lines' closest points a0 + s da and b0 + t db: s = (w x db) . n / |n|^2, t = (w x da) . n / |n|^2.
  const T n2 = n_norm * n_norm;
  const T s_times_n2 = w.cross(db).dot(n), t_times_n2 = w.cross(da).dot(n);
  const T margin = T(INSIDE_MARGIN_FACTOR) * u * longest * longest * longest * local;
  if (s_times_n2 >= -margin && s_times_n2 <= n2 + margin && t_times_n2 >= -margin && t_times_n2 <= n2 + margin) {
    const T between_lines = std::abs(w.dot(n)) / n_norm;
    if (between_lines < out.distance) {
      out.distance = between_lines;
      out.param0 = std::clamp<T>(s_times_n2 / n2, 0, 1);
      out.param1 = std::clamp<T>(t_times_n2 / n2, 0, 1);
    }
  }
  return out;
}

}  // namespace drape::ccd
