#pragma once
/// \file
/// The elementary CCD queries, their options and their results.

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "drape/ccd/types.h"

namespace drape::ccd {

/// Four points at the start (t = 0) and the end (t = 1) of a step; each moves linearly.
/// Vertex-face: points are the vertex, then face[0], face[1], face[2].
/// Edge-edge: points are edge_a[0], edge_a[1], edge_b[0], edge_b[1].
/// (The row order of the public query files, FORMAT.md.)
struct Query {
  std::array<Vec3, 4> start;
  std::array<Vec3, 4> end;
};

/// A vertex against a triangle.
struct VertexFaceQuery : Query {};
/// An edge against another edge.
struct EdgeEdgeQuery : Query {};

enum class QueryKind : std::uint8_t { VertexFace, EdgeEdge };

/// How the roots of the coplanarity cubic are looked for.
enum class Method : std::uint8_t {
  Cubic,         ///< all real roots by a closed-form cubic solver, no filter (the paper's baseline)
  Dnf,           ///< cull when the four Bernstein coefficients share one strict sign, else Cubic
  Vincent,       ///< the paper's filter: Bernstein sign variations, bracketed root or subdivision
  Conservative,  ///< error-bounded exclusion; never reports "no contact" for a contact
};

inline constexpr std::array<Method, 4> ALL_METHODS = {Method::Cubic, Method::Dnf, Method::Vincent,
                                                      Method::Conservative};

std::string_view method_name(Method method);
std::string_view kind_name(QueryKind kind);
/// Parses "cubic", "dnf", "vincent" or "conservative"; nullopt for anything else.
std::optional<Method> parse_method(std::string_view name);

/// Accuracy knobs of the elementary tests. Lengths are in scene units, times in units of the step.
struct Options {
  Method method = Method::Vincent;

  /// Minimum separation: features closer than this count as touching. Zero reproduces the
  /// exact-contact ground truth of the public query files; cloth runs use their thickness.
  Scalar thickness = 0.0;

  /// Inside test of Cubic, Dnf and Vincent: at a root of the cubic, the features touch when
  /// their distance is at most thickness + contact_tolerance * (the query's extent: the largest
  /// 1-norm of a point's offset from the first face or edge point). Relative, dimensionless;
  /// 1e-9 absorbs the root's rounding (about 1e-12 relative) and stays far below any gap a
  /// simulation can resolve.
  Scalar contact_tolerance = 1e-9;

  /// Root refinement stops when the bracket is narrower than this (units of the step).
  Scalar root_tolerance = 1e-13;

  /// Vincent: subdivision levels before an interval still holding two or more sign variations
  /// (a double root, a tangential contact) is tested at its midpoint. 2^-30 of the step.
  int max_subdivision_depth = 30;

  /// Vincent and conservative: levels of the separation stage, 0 to 6. When the cubic may
  /// vanish in the step, it is halved this many times (de Casteljau, 2^depth sub-intervals) and
  /// each run of sub-intervals where it may vanish (conservative: come within what the
  /// thickness allows) is tested for a separating axis between the features; when every one is
  /// separated the test ends there (Path::Separated): no contact, without root finding or
  /// search. 0 turns the stage off: the paper's filter alone. Vincent's answers are the same
  /// either way; conservative's too, but for near misses within its time tolerance of the
  /// thickness, which the search may report and the stage clears. Deeper separates more tests
  /// and costs more on each.
  int separation_depth = 2;

  /// Conservative: an interval narrower than this (units of the step) that neither the cubic
  /// nor the distance bound excludes is reported as a contact at its start. It bounds both the
  /// error of the reported time of contact and how near a near-miss must come to be reported.
  Scalar time_tolerance = 1e-9;

  /// Conservative: intervals examined before the test stops and reports a contact at the
  /// earliest interval not yet excluded (a sliding, exactly coplanar motion can need many).
  int max_intervals = 2048;
};

/// How a result was decided; counted in the batch statistics.
enum class Path : std::uint8_t {
  Culled,      ///< the filter proved the cubic has no root in [0, 1]; no root finding
  Separated,   ///< the cubic has roots in [0, 1], but over short intervals around them the features
               ///< are apart along a separating axis: no contact, no root finding
  Solved,      ///< roots were isolated or solved for, and the inside test decided
  Degenerate,  ///< decided on a degenerate path: cubic identically zero (coplanar motion),
               ///< tangential root at the subdivision bound, or the interval budget ran out
};

/// Outcome of one elementary test.
struct Result {
  bool hit = false;
  /// Earliest time of contact in [0, 1] (valid when hit).
  Scalar toc = 1.0;
  /// Contact parameters at toc (valid when hit): the features' closest points there, whichever
  /// path decided; vertex-face, barycentric weights (w1, w2) of face[1] and face[2] (face[0]
  /// has 1 - w1 - w2); edge-edge, (s, u) along edge_a and edge_b.
  Vec2 params = Vec2::Zero();
  Path path = Path::Culled;
  /// Root-finding calls made: bracketed refinements, cubic solves or subdivided intervals.
  std::uint16_t root_solves = 0;
};

/// The elementary tests. Pure functions: no state, no allocation.
Result vertex_face_ccd(const VertexFaceQuery& query, const Options& options);
Result edge_edge_ccd(const EdgeEdgeQuery& query, const Options& options);
/// Dispatch on the kind.
Result elementary_ccd(QueryKind kind, const Query& query, const Options& options);

}  // namespace drape::ccd
