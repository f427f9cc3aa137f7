#pragma once
/// \file
/// The independent penetration check of a frame, with exact predicates.
///
/// The independent penetration check: do any two non-adjacent cloth triangles meet, or a cloth
/// triangle and an obstacle (a mesh's triangle, a sphere's ball, a plane's lower half-space)?
/// Decided exactly (CGAL's filtered exact predicates: floating point where its answer is
/// certain, exact arithmetic where it is not), so coplanar overlaps and exact touches are found.
/// It shares no code with the CCD library, so it can judge the collision pipeline's output.

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "drape/core/model.h"

namespace drape {

/// How two closed shapes meet.
enum class PenetrationKind : std::uint8_t {
  Crossing,         ///< one passes through the other (a triangle through a triangle; into a ball or below a plane)
  CoplanarOverlap,  ///< two triangles in one plane share points
  Touching,         ///< they meet only where one's boundary lies on the other (distance exactly zero)
};

const char* penetration_kind_name(PenetrationKind kind);

struct Penetration {
  int triangle = 0;   ///< cloth triangle
  int other = -1;     ///< the other cloth triangle, or the obstacle's triangle (-1: sphere or plane)
  int obstacle = -1;  ///< -1: cloth against cloth; else the obstacle's index
  PenetrationKind kind = PenetrationKind::Crossing;
  std::string describe() const;
};

/// Every pair that meets at time t for the given cloth positions (up to limit pairs).
std::vector<Penetration> find_penetrations(const Model& model, const std::vector<Vec3>& positions, Scalar t,
                                           std::size_t limit = 1000);

/// What a scene's start holds that its collisions cannot answer for: the pairs that meet at
/// time 0 (find_penetrations) among those the scene's collisions keep apart (a cloth and an
/// obstacle with collisions.obstacles on, two cloth triangles with collisions.self on). The
/// collision pipeline keeps a cloth free of intersections from a start free of them; it does
/// not part meshes that already pass through each other (it holds them as they are, or its
/// fail-safe freezes the cloth). error: the pairs of cloth triangles, or of a cloth triangle
/// and a mesh obstacle's, that cross or overlap in a plane, described for the scene's file
/// (its JSON paths, each cloth's and obstacle's mesh file and triangle numbers, the count)
/// with what is expected instead; empty when there are none. warning: cloth inside a sphere or
/// below a plane (whose inside is known everywhere: the first step pushes its vertices out),
/// and the pairs that only touch (at distance exactly zero), which the run starts from and
/// keeps at most as close; empty when there are none.
struct StartCheck {
  std::string error, warning;
};
StartCheck check_start(const Model& model);

using TriangleCorners = std::array<Vec3, 3>;

/// How two triangles (closed, possibly degenerate) meet, exactly; nullopt when they do not.
std::optional<PenetrationKind> triangles_meet(const TriangleCorners& s, const TriangleCorners& t);

/// How a triangle meets a solid ball, exactly; nullopt when every point is outside.
std::optional<PenetrationKind> triangle_meets_ball(const TriangleCorners& s, const Vec3& centre, Scalar radius);

/// How a triangle meets the half-space below a plane (normal pointing to the free side),
/// exactly; nullopt when every corner is on the free side.
std::optional<PenetrationKind> triangle_meets_half_space(const TriangleCorners& s, const Vec3& point, const Vec3& normal);

}  // namespace drape
