// drape check's exact decisions (penetration.h): CGAL's Epick kernel for the triangle tests
// (exact predicates, filtered), Epeck for the ball (an exact squared distance, lazily), and a
// sweep and prune over the triangles' boxes in double (comparisons of doubles are exact).
#include "drape/core/penetration.h"

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>

#include "drape/core/obstacle.h"

namespace drape {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using E = CGAL::Exact_predicates_exact_constructions_kernel;

K::Point_3 point(const Vec3& v) { return {v.x(), v.y(), v.z()}; }
E::Point_3 exact_point(const Vec3& v) { return {v.x(), v.y(), v.z()}; }

// A closed triangle as CGAL sees it: the triangle, or the segment or point it degenerates to.
struct Feature {
  enum class Shape { Triangle, Segment, Point } shape = Shape::Triangle;
  std::array<K::Point_3, 3> corners;
  K::Triangle_3 triangle() const { return {corners[0], corners[1], corners[2]}; }
  K::Segment_3 segment() const { return {corners[0], corners[1]}; }
};

Feature feature_of(const TriangleCorners& c) {
  Feature f;
  for (int i = 0; i < 3; ++i) f.corners[std::size_t(i)] = point(c[std::size_t(i)]);
  if (!CGAL::collinear(f.corners[0], f.corners[1], f.corners[2])) return f;
  // Collinear corners: the segment between the lexicographically least and greatest.
  const auto [lo, hi] = std::minmax_element(f.corners.begin(), f.corners.end(), [](const K::Point_3& a, const K::Point_3& b) {
    return CGAL::compare_xyz(a, b) == CGAL::SMALLER;
  });
  const K::Point_3 a = *lo, b = *hi;
  f.corners = {a, b, b};
  f.shape = a == b ? Feature::Shape::Point : Feature::Shape::Segment;
  return f;
}

bool features_meet(const Feature& s, const Feature& t) {
  using S = Feature::Shape;
  if (s.shape == S::Triangle && t.shape == S::Triangle) return CGAL::do_intersect(s.triangle(), t.triangle());
  if (s.shape == S::Triangle && t.shape == S::Segment) return CGAL::do_intersect(s.triangle(), t.segment());
  if (s.shape == S::Segment && t.shape == S::Triangle) return CGAL::do_intersect(t.triangle(), s.segment());
  if (s.shape == S::Segment && t.shape == S::Segment) return CGAL::do_intersect(s.segment(), t.segment());
  if (s.shape == S::Point && t.shape == S::Point) return s.corners[0] == t.corners[0];
  const Feature& p = s.shape == S::Point ? s : t;
  const Feature& other = s.shape == S::Point ? t : s;
  return other.shape == S::Triangle ? other.triangle().has_on(p.corners[0]) : other.segment().has_on(p.corners[0]);
}

// Signs of the corners of one feature against the plane of a triangle: both strict signs
// present (it passes through the plane), all zero (in the plane), or neither.
struct Sides {
  bool positive = false, negative = false;
};
Sides sides(const Feature& plane_of, const Feature& f) {
  Sides out;
  for (const K::Point_3& p : f.corners) {
    const CGAL::Orientation o = CGAL::orientation(plane_of.corners[0], plane_of.corners[1], plane_of.corners[2], p);
    out.positive = out.positive || o == CGAL::POSITIVE;
    out.negative = out.negative || o == CGAL::NEGATIVE;
  }
  return out;
}

struct TriangleBox {
  Vec3 lo, hi;
  int index;
};

TriangleBox box_of(const TriangleCorners& t, int index) {
  return {t[0].cwiseMin(t[1]).cwiseMin(t[2]), t[0].cwiseMax(t[1]).cwiseMax(t[2]), index};
}

bool boxes_overlap(const Vec3& lo_a, const Vec3& hi_a, const Vec3& lo_b, const Vec3& hi_b) {
  return (lo_a.array() <= hi_b.array()).all() && (lo_b.array() <= hi_a.array()).all();
}

// Sweep and prune along x: every pair of boxes (one from each list) overlapping on all axes,
// touching boxes included.
template <class Visit>
void overlapping(std::vector<TriangleBox> a, std::vector<TriangleBox> b, bool same, Visit visit) {
  const auto by_lo = [](const TriangleBox& u, const TriangleBox& v) { return u.lo.x() < v.lo.x(); };
  std::sort(a.begin(), a.end(), by_lo);
  if (same) {
    for (std::size_t i = 0; i < a.size(); ++i)
      for (std::size_t j = i + 1; j < a.size() && a[j].lo.x() <= a[i].hi.x(); ++j)
        if (boxes_overlap(a[i].lo, a[i].hi, a[j].lo, a[j].hi)) visit(a[i].index, a[j].index);
    return;
  }
  std::sort(b.begin(), b.end(), by_lo);
  for (const TriangleBox& u : a) {
    for (const TriangleBox& v : b) {
      if (v.lo.x() > u.hi.x()) break;
      if (boxes_overlap(u.lo, u.hi, v.lo, v.hi)) visit(u.index, v.index);
    }
  }
}

}  // namespace

const char* penetration_kind_name(PenetrationKind kind) {
  switch (kind) {
    case PenetrationKind::Crossing: return "crossing";
    case PenetrationKind::CoplanarOverlap: return "coplanar overlap";
    case PenetrationKind::Touching: return "touching";
  }
  return "?";
}

std::string Penetration::describe() const {
  const std::string how = std::string(" (") + penetration_kind_name(kind) + ")";
  if (obstacle < 0) return "cloth triangles " + std::to_string(triangle) + " and " + std::to_string(other) + how;
  if (other < 0) return "cloth triangle " + std::to_string(triangle) + " and obstacle " + std::to_string(obstacle) + how;
  return "cloth triangle " + std::to_string(triangle) + " and triangle " + std::to_string(other) + " of obstacle " +
         std::to_string(obstacle) + how;
}

std::optional<PenetrationKind> triangles_meet(const TriangleCorners& s, const TriangleCorners& t) {
  const Feature fs = feature_of(s), ft = feature_of(t);
  if (!features_meet(fs, ft)) return std::nullopt;
  using S = Feature::Shape;
  const bool s_flat = fs.shape == S::Triangle, t_flat = ft.shape == S::Triangle;
  if (!s_flat && !t_flat) return PenetrationKind::Touching;  // segments and points cannot pass through
  // t's corners against s's plane and s's against t's (where each is a triangle).
  const Sides t_on_s = s_flat ? sides(fs, ft) : Sides{true, true};
  const Sides s_on_t = t_flat ? sides(ft, fs) : Sides{true, true};
  const bool coplanar = s_flat ? (!t_on_s.positive && !t_on_s.negative) : (!s_on_t.positive && !s_on_t.negative);
  if (coplanar) return PenetrationKind::CoplanarOverlap;
  // Meeting, not coplanar: each passes through the other's plane, or one only touches it.
  if (t_on_s.positive && t_on_s.negative && s_on_t.positive && s_on_t.negative) return PenetrationKind::Crossing;
  return PenetrationKind::Touching;
}

std::optional<PenetrationKind> triangle_meets_ball(const TriangleCorners& s, const Vec3& centre, Scalar radius) {
  const Feature f = feature_of(s);
  const E::Point_3 c = exact_point(centre);
  const E::FT r2 = E::FT(radius) * E::FT(radius);
  E::FT d2;
  switch (f.shape) {
    case Feature::Shape::Triangle:
      d2 = CGAL::squared_distance(c, E::Triangle_3(exact_point(s[0]), exact_point(s[1]), exact_point(s[2])));
      break;
    case Feature::Shape::Segment: {
      const E::Point_3 a(f.corners[0].x(), f.corners[0].y(), f.corners[0].z());
      const E::Point_3 b(f.corners[1].x(), f.corners[1].y(), f.corners[1].z());
      d2 = CGAL::squared_distance(c, E::Segment_3(a, b));
      break;
    }
    case Feature::Shape::Point: d2 = CGAL::squared_distance(c, exact_point(s[0])); break;
  }
  switch (CGAL::compare(d2, r2)) {
    case CGAL::SMALLER: return PenetrationKind::Crossing;
    case CGAL::EQUAL: return PenetrationKind::Touching;
    default: return std::nullopt;
  }
}

std::optional<PenetrationKind> triangle_meets_half_space(const TriangleCorners& s, const Vec3& point_on, const Vec3& normal) {
  const E::Point_3 p = exact_point(point_on);
  const E::Vector_3 n(normal.x(), normal.y(), normal.z());
  bool below = false, on = false;
  for (const Vec3& corner : s) {
    const CGAL::Sign side = CGAL::sign((exact_point(corner) - p) * n);
    below = below || side == CGAL::NEGATIVE;
    on = on || side == CGAL::ZERO;
  }
  if (below) return PenetrationKind::Crossing;
  if (on) return PenetrationKind::Touching;
  return std::nullopt;
}

std::vector<Penetration> find_penetrations(const Model& model, const std::vector<Vec3>& x, Scalar t, std::size_t limit) {
  std::vector<Penetration> found;
  const auto corners = [&](const Triangle& tri, const std::vector<Vec3>& p) {
    return TriangleCorners{p[std::size_t(tri[0])], p[std::size_t(tri[1])], p[std::size_t(tri[2])]};
  };
  std::vector<TriangleBox> cloth;
  for (std::size_t i = 0; i < model.triangles.size(); ++i) cloth.push_back(box_of(corners(model.triangles[i], x), int(i)));

  // Cloth against cloth: triangles sharing a vertex touch by construction and are skipped.
  overlapping(cloth, {}, true, [&](int i, int j) {
    if (found.size() >= limit) return;
    const Triangle& a = model.triangles[std::size_t(i)];
    const Triangle& b = model.triangles[std::size_t(j)];
    for (int u : a)
      for (int v : b)
        if (u == v) return;
    if (const auto kind = triangles_meet(corners(a, x), corners(b, x)))
      found.push_back({std::min(i, j), std::max(i, j), -1, *kind});
  });
  // Cloth against the obstacles.
  for (std::size_t o = 0; o < model.obstacles.size(); ++o) {
    const Obstacle& obstacle = model.obstacles[o];
    const ObstacleSpec& spec = obstacle.spec;
    if (spec.kind == ObstacleSpec::Kind::Sphere) {
      const Vec3 centre = spec.motion.position(spec.center, t);
      const Vec3 reach = Vec3::Constant(spec.radius);
      for (const TriangleBox& box : cloth) {
        if (found.size() >= limit) break;
        if (!boxes_overlap(box.lo, box.hi, centre - reach, centre + reach)) continue;  // the ball's box
        if (const auto kind = triangle_meets_ball(corners(model.triangles[std::size_t(box.index)], x), centre, spec.radius))
          found.push_back({box.index, -1, int(o), *kind});
      }
      continue;
    }
    if (spec.kind == ObstacleSpec::Kind::Plane) {
      const Vec3 on = spec.motion.position(spec.point, t);
      const Vec3 normal = spec.motion.position(spec.point + spec.normal, t) - on;
      for (std::size_t i = 0; i < model.triangles.size() && found.size() < limit; ++i)
        if (const auto kind = triangle_meets_half_space(corners(model.triangles[i], x), on, normal))
          found.push_back({int(i), -1, int(o), *kind});
      continue;
    }
    const std::vector<Vec3> posed = posed_vertices(obstacle, t);
    std::vector<TriangleBox> boxes;
    for (std::size_t i = 0; i < obstacle.mesh.triangles.size(); ++i)
      boxes.push_back(box_of(corners(obstacle.mesh.triangles[i], posed), int(i)));
    overlapping(cloth, boxes, false, [&](int i, int j) {
      if (found.size() >= limit) return;
      if (const auto kind = triangles_meet(corners(model.triangles[std::size_t(i)], x),
                                           corners(obstacle.mesh.triangles[std::size_t(j)], posed)))
        found.push_back({i, j, int(o), *kind});
    });
  }
  std::sort(found.begin(), found.end(), [](const Penetration& a, const Penetration& b) {
    return std::tie(a.obstacle, a.triangle, a.other) < std::tie(b.obstacle, b.triangle, b.other);
  });
  return found;
}

namespace {

// A cloth triangle (global index): its cloth and its number within that cloth's mesh.
std::pair<std::size_t, int> cloth_of(const Model& model, int triangle) {
  std::size_t c = 0;
  while (c + 1 < model.cloths.size() && triangle >= model.cloths[c + 1].first_triangle) ++c;
  return {c, triangle - model.cloths[c].first_triangle};
}

std::string cloth_name(const Model& model, std::size_t c) {
  const ClothSpec& spec = model.scene.cloths[c];
  return "/cloths/" + std::to_string(c) + (spec.grid ? " (a grid)" : " (" + spec.mesh_file.filename().string() + ")");
}

// One meeting pair as the scene names it.
std::string pair_text(const Model& model, const Penetration& p) {
  const bool cross = p.kind == PenetrationKind::Crossing, overlap = p.kind == PenetrationKind::CoplanarOverlap;
  const auto [c, t] = cloth_of(model, p.triangle);
  if (p.obstacle < 0) {
    const auto [d, u] = cloth_of(model, p.other);
    const std::string how = cross ? " pass through each other" : overlap ? " overlap in one plane" : " touch";
    if (c == d) return cloth_name(model, c) + " triangles " + std::to_string(t) + " and " + std::to_string(u) + how;
    return cloth_name(model, c) + " triangle " + std::to_string(t) + " and " + cloth_name(model, d) + " triangle " +
           std::to_string(u) + how;
  }
  const ObstacleSpec& spec = model.obstacles[std::size_t(p.obstacle)].spec;
  std::string obstacle = "/obstacles/" + std::to_string(p.obstacle);
  if (spec.kind == ObstacleSpec::Kind::Sphere) obstacle += " (a sphere)";
  else if (spec.kind == ObstacleSpec::Kind::Plane) obstacle += " (a plane: the half-space below it)";
  else obstacle += " (" + spec.mesh_file.filename().string() + ") triangle " + std::to_string(p.other);
  return cloth_name(model, c) + " triangle " + std::to_string(t) +
         (cross ? " passes through " : overlap ? " overlaps in one plane with " : " touches ") + obstacle;
}

}  // namespace

StartCheck check_start(const Model& model) {
  constexpr std::size_t LIMIT = 100000;  // pairs examined at most (the count says "at least" then)
  constexpr std::size_t SHOWN = 3;       // pairs described
  std::vector<Penetration> meeting, inside, touching;
  const CollisionSpec& collisions = model.scene.collisions;
  const std::vector<Penetration> found = find_penetrations(model, model.initial_positions, 0, LIMIT);
  for (const Penetration& p : found) {
    if (p.obstacle < 0 ? !collisions.self : !collisions.obstacles) continue;
    const bool analytic = p.obstacle >= 0 && model.obstacles[std::size_t(p.obstacle)].spec.kind != ObstacleSpec::Kind::Mesh;
    (p.kind == PenetrationKind::Touching ? touching : analytic ? inside : meeting).push_back(p);
  }
  const auto listed = [&](const std::vector<Penetration>& pairs) {
    std::string text;
    for (std::size_t k = 0; k < pairs.size() && k < SHOWN; ++k) text += (k > 0 ? "; " : "") + pair_text(model, pairs[k]);
    if (pairs.size() > SHOWN)
      text += "; and " + std::string(found.size() >= LIMIT ? "at least " : "") + std::to_string(pairs.size() - SHOWN) + " more pairs";
    return text;
  };
  StartCheck check;
  if (!meeting.empty()) {
    const bool self = std::any_of(meeting.begin(), meeting.end(), [](const Penetration& p) { return p.obstacle < 0; });
    const bool obstacle = std::any_of(meeting.begin(), meeting.end(), [](const Penetration& p) { return p.obstacle >= 0; });
    std::string expected = "expected a start free of intersections (drape keeps a cloth free of them only from such a start): ";
    if (obstacle) expected += "the cloths clear of the obstacles (their transform), or collisions.obstacles false";
    if (self && obstacle) expected += "; ";
    if (self) expected += "each cloth's mesh free of self-intersections and the cloths clear of each other, or collisions.self false";
    check.error = model.scene.file.string() + ": the scene starts with its meshes meeting (triangles counted from 0 in each mesh): " +
                  listed(meeting) + "; " + expected;
  }
  // A sphere's or a plane's inside is known everywhere: the first step moves the vertices
  // inside out to the surface (a kick the energy check may report).
  if (!inside.empty())
    check.warning = "the scene starts with cloth inside a sphere or below a plane, which its first step pushes out (triangles "
                    "counted from 0 in each mesh): " + listed(inside);
  if (!touching.empty())
    check.warning += std::string(check.warning.empty() ? "" : "; and ") +
                     "the scene starts with meshes touching (at distance exactly zero; triangles counted from 0 in each mesh), "
                     "which the run keeps at most as close: " + listed(touching);
  return check;
}

}  // namespace drape
