#include "drape/core/penetration.h"

#include <algorithm>

#include "drape/core/obstacle.h"

namespace drape {

std::string Penetration::describe() const {
  if (obstacle < 0) return "cloth triangles " + std::to_string(triangle) + " and " + std::to_string(other);
  if (other < 0) return "cloth vertex " + std::to_string(triangle) + " inside obstacle " + std::to_string(obstacle);
  return "cloth triangle " + std::to_string(triangle) + " and triangle " + std::to_string(other) + " of obstacle " +
         std::to_string(obstacle);
}

bool segment_crosses_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 d = q - p, e1 = b - a, e2 = c - a;
  const Vec3 h = d.cross(e2);
  const Scalar det = e1.dot(h);
  if (det == 0) return false;  // parallel (or coplanar): no transversal crossing
  const Scalar inv = 1 / det;
  const Vec3 s = p - a;
  const Scalar u = inv * s.dot(h);
  if (!(u > 0 && u < 1)) return false;
  const Vec3 qv = s.cross(e1);
  const Scalar v = inv * d.dot(qv);
  if (!(v > 0 && u + v < 1)) return false;
  const Scalar t = inv * e2.dot(qv);
  return t > 0 && t < 1;
}

bool triangles_intersect(const std::array<Vec3, 3>& s, const std::array<Vec3, 3>& t) {
  for (int i = 0; i < 3; ++i) {
    if (segment_crosses_triangle(s[i], s[(i + 1) % 3], t[0], t[1], t[2])) return true;
    if (segment_crosses_triangle(t[i], t[(i + 1) % 3], s[0], s[1], s[2])) return true;
  }
  return false;
}

namespace {

struct TriangleBox {
  Vec3 lo, hi;
  int index;
};

TriangleBox box_of(const std::array<Vec3, 3>& t, int index) {
  return {t[0].cwiseMin(t[1]).cwiseMin(t[2]), t[0].cwiseMax(t[1]).cwiseMax(t[2]), index};
}

// Sweep and prune along x: every pair of boxes (one from each list) overlapping on all axes.
template <class Visit>
void overlapping(std::vector<TriangleBox> a, std::vector<TriangleBox> b, bool same, Visit visit) {
  const auto by_lo = [](const TriangleBox& u, const TriangleBox& v) { return u.lo.x() < v.lo.x(); };
  std::sort(a.begin(), a.end(), by_lo);
  if (same) {
    for (std::size_t i = 0; i < a.size(); ++i)
      for (std::size_t j = i + 1; j < a.size() && a[j].lo.x() <= a[i].hi.x(); ++j)
        if ((a[i].lo.array() <= a[j].hi.array()).all() && (a[j].lo.array() <= a[i].hi.array()).all())
          visit(a[i].index, a[j].index);
    return;
  }
  std::sort(b.begin(), b.end(), by_lo);
  for (const TriangleBox& u : a) {
    for (const TriangleBox& v : b) {
      if (v.lo.x() > u.hi.x()) break;
      if ((u.lo.array() <= v.hi.array()).all() && (v.lo.array() <= u.hi.array()).all()) visit(u.index, v.index);
    }
  }
}

}  // namespace

std::vector<Penetration> find_penetrations(const Model& model, const std::vector<Vec3>& x, Scalar t, std::size_t limit) {
  std::vector<Penetration> found;
  const auto corners = [&](const Triangle& tri, const std::vector<Vec3>& p) {
    return std::array<Vec3, 3>{p[tri[0]], p[tri[1]], p[tri[2]]};
  };
  std::vector<TriangleBox> cloth;
  for (std::size_t i = 0; i < model.triangles.size(); ++i) cloth.push_back(box_of(corners(model.triangles[i], x), int(i)));

  // Cloth against cloth: triangles sharing a vertex touch by construction and are skipped.
  overlapping(cloth, {}, true, [&](int i, int j) {
    if (found.size() >= limit) return;
    const Triangle& a = model.triangles[i];
    const Triangle& b = model.triangles[j];
    for (int u : a)
      for (int v : b)
        if (u == v) return;
    if (triangles_intersect(corners(a, x), corners(b, x))) found.push_back({std::min(i, j), std::max(i, j), -1});
  });
  // Cloth against the obstacles.
  for (std::size_t o = 0; o < model.obstacles.size(); ++o) {
    const Obstacle& obstacle = model.obstacles[o];
    if (obstacle.spec.kind != ObstacleSpec::Kind::Mesh) {
      for (std::size_t v = 0; v < x.size() && found.size() < limit; ++v)
        if (analytic_contact(obstacle, t, x[v]).signed_distance < 0) found.push_back({int(v), -1, int(o)});
      continue;
    }
    const std::vector<Vec3> posed = posed_vertices(obstacle, t);
    std::vector<TriangleBox> boxes;
    for (std::size_t i = 0; i < obstacle.mesh.triangles.size(); ++i)
      boxes.push_back(box_of(corners(obstacle.mesh.triangles[i], posed), int(i)));
    overlapping(cloth, boxes, false, [&](int i, int j) {
      if (found.size() < limit && triangles_intersect(corners(model.triangles[i], x), corners(obstacle.mesh.triangles[j], posed)))
        found.push_back({i, j, int(o)});
    });
  }
  std::sort(found.begin(), found.end(), [](const Penetration& a, const Penetration& b) {
    return std::tie(a.obstacle, a.triangle, a.other) < std::tie(b.obstacle, b.triangle, b.other);
  });
  return found;
}

}  // namespace drape
