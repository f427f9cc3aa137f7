#pragma once
/// \file
/// The independent penetration check: do any two non-adjacent cloth triangles intersect, or a
/// cloth triangle and an obstacle triangle, or is a cloth vertex inside an analytic obstacle?
/// It shares no code with the CCD library (its own sweep-and-prune and segment-triangle tests),
/// so it can judge the collision pipeline's output.

#include <string>
#include <vector>

#include "drape/core/model.h"

namespace drape {

struct Penetration {
  int triangle = 0;        ///< cloth triangle (or cloth vertex, for analytic obstacles)
  int other = 0;           ///< the other cloth triangle, or the obstacle's triangle
  int obstacle = -1;       ///< -1: cloth against cloth; else the obstacle's index
  std::string describe() const;
};

/// Every intersecting pair at time t for the given cloth positions (up to limit pairs).
std::vector<Penetration> find_penetrations(const Model& model, const std::vector<Vec3>& positions, Scalar t,
                                           std::size_t limit = 1000);

/// Whether segment pq crosses triangle abc at an interior point of both (Moller and
/// Trumbore 1997, strict inequalities: touching does not count).
bool segment_crosses_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c);

/// Whether two triangles intersect (non-coplanar: an edge of one crosses the other).
bool triangles_intersect(const std::array<Vec3, 3>& s, const std::array<Vec3, 3>& t);

}  // namespace drape
