#include "drape/core/mesh.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

namespace drape {
namespace {

Edge make_edge(int a, int b) { return a < b ? Edge{a, b} : Edge{b, a}; }

// Relative area below which a triangle counts as degenerate: |n| <= ratio * (mesh size)^2.
constexpr Scalar DEGENERATE_AREA_RATIO = 1e-12;

}  // namespace

std::vector<Edge> mesh_edges(const TriangleMesh& mesh) {
  std::map<Edge, int> seen;
  std::vector<Edge> edges;
  for (const Triangle& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      const Edge e = make_edge(t[k], t[(k + 1) % 3]);
      if (seen.emplace(e, int(edges.size())).second) edges.push_back(e);
    }
  }
  return edges;
}

std::vector<std::array<int, 4>> hinges(const TriangleMesh& mesh) {
  // Edge -> the opposite vertices of the triangles sharing it.
  std::map<Edge, std::vector<int>> opposite;
  std::vector<Edge> order;
  for (const Triangle& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      const Edge e = make_edge(t[k], t[(k + 1) % 3]);
      auto& list = opposite[e];
      if (list.empty()) order.push_back(e);
      list.push_back(t[(k + 2) % 3]);
    }
  }
  std::vector<std::array<int, 4>> found;
  for (const Edge& e : order) {
    const auto& list = opposite[e];
    if (list.size() == 2 && list[0] != list[1]) found.push_back({e[0], e[1], list[0], list[1]});
  }
  return found;
}

std::vector<Edge> bending_pairs(const TriangleMesh& mesh) {
  std::vector<Edge> pairs;
  for (const auto& h : hinges(mesh)) pairs.push_back(make_edge(h[2], h[3]));
  return pairs;
}

Scalar surface_area(const TriangleMesh& mesh) {
  Scalar area = 0;
  for (const Triangle& t : mesh.triangles)
    area += 0.5 * (mesh.vertices[t[1]] - mesh.vertices[t[0]]).cross(mesh.vertices[t[2]] - mesh.vertices[t[0]]).norm();
  return area;
}

std::string mesh_problem(const TriangleMesh& mesh) {
  std::ostringstream out;
  if (mesh.vertices.empty() || mesh.triangles.empty()) return "the mesh has no triangles";
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    if (!mesh.vertices[i].allFinite()) {
      out << "vertex " << i << " has a non-finite coordinate";
      return out.str();
    }
  }
  Vec3 lo = mesh.vertices[0], hi = mesh.vertices[0];
  for (const Vec3& v : mesh.vertices) lo = lo.cwiseMin(v), hi = hi.cwiseMax(v);
  const Scalar size = (hi - lo).norm();
  const int n = int(mesh.vertices.size());
  std::map<Edge, int> uses;
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
    const Triangle& t = mesh.triangles[i];
    for (int k = 0; k < 3; ++k) {
      if (t[k] < 0 || t[k] >= n) {
        out << "triangle " << i << " refers to vertex " << t[k] << ", but the mesh has " << n << " vertices";
        return out.str();
      }
    }
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
      out << "triangle " << i << " repeats a vertex (" << t[0] << ", " << t[1] << ", " << t[2] << ")";
      return out.str();
    }
    const Scalar twice_area =
        (mesh.vertices[t[1]] - mesh.vertices[t[0]]).cross(mesh.vertices[t[2]] - mesh.vertices[t[0]]).norm();
    if (!(twice_area > DEGENERATE_AREA_RATIO * size * size)) {
      out << "triangle " << i << " has zero area (degenerate)";
      return out.str();
    }
    for (int k = 0; k < 3; ++k) {
      if (++uses[make_edge(t[k], t[(k + 1) % 3])] > 2) {
        out << "edge (" << std::min(t[k], t[(k + 1) % 3]) << ", " << std::max(t[k], t[(k + 1) % 3])
            << ") is shared by more than two triangles (non-manifold)";
        return out.str();
      }
    }
  }
  return "";
}

}  // namespace drape
