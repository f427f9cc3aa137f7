#pragma once
/// \file
/// Obstacles posed at a time: distances, normals, surface velocities and the push out.
///
/// Obstacles posed at a time: where the analytic shapes are, how far a point is from them, and
/// how fast their surface moves.

#include <optional>
#include <utility>

#include "drape/core/model.h"

namespace drape {

/// The closest surface point's data for a point near an analytic obstacle.
struct SurfaceContact {
  Scalar signed_distance = 0;        ///< positive on the free side
  Vec3 normal = Vec3::UnitZ();       ///< unit, pointing to the free side
  Vec3 surface_velocity = Vec3::Zero();
};

/// A sphere or plane posed at one time: many points' distances without posing it again.
struct PosedShape {
  const Obstacle* obstacle = nullptr;
  bool sphere = false;
  Vec3 point = Vec3::Zero();    ///< the centre, or a point of the plane
  Vec3 normal = Vec3::UnitZ();  ///< the plane's (unit, to the free side)
  Scalar radius = 0;
  /// The signed distance of x (positive on the free side) and the unit normal there.
  std::pair<Scalar, Vec3> distance(const Vec3& x) const {
    if (!sphere) return {normal.dot(x - point), normal};
    const Vec3 offset = x - point;
    const Scalar length = offset.norm();
    return {length - radius, length > 0 ? Vec3(offset / length) : Vec3::UnitZ()};
  }
};

/// Sphere or plane (not a mesh) at time t.
PosedShape pose_shape(const Obstacle& obstacle, Scalar t);

/// Sphere or plane posed at time t, seen from x.
SurfaceContact analytic_contact(const PosedShape& shape, Scalar t, const Vec3& x);

/// A vertex at start moving by h * motion over a step ending at t_next (the shape posed at
/// t_next): when its end lies within depth of the shape's surface, motion is changed so that it
/// ends at depth along the surface normal, and the contact there is returned.
std::optional<SurfaceContact> push_out(const PosedShape& shape, Scalar t_next, const Vec3& start, Scalar h, Scalar depth,
                                       Vec3& motion);

/// A cloth face or edge keeps this fraction of its corners' depth (or reach) from a sphere:
/// enough that it never touches it, and little enough that a cloth resting on a sphere with its
/// corners at the depth is not pushed off by its faces' sag between them (a chord of length L
/// sags L^2 / (8 r) towards a sphere of radius r: only meshes coarser than 2 sqrt(r depth)
/// reach it, such as a curtain of 6 cm cells struck by a 10 cm ball).
constexpr Scalar FACE_DEPTH_FRACTION = 0.5;

/// Keeps every free cloth vertex (no handle) out of the spheres and planes over a step from
/// start ending at t_next (Bridson, Fedkiw and Anderson 2002, section 7.1): one whose
/// predicted position start + h motion lies within depth of a surface moves (push_out) to land
/// at depth on it; then a sphere that comes between a triangle's corners (its closest point
/// inside the triangle within FACE_DEPTH_FRACTION of depth of the surface) pushes the
/// triangle out to that depth, the corners sharing the change by weight and inverse mass. With velocities (the response after the solve, at the thickness), the
/// motion also feels Coulomb friction from that push, and the velocity loses its approaching
/// normal part and feels Coulomb friction relative to the surface; without (the collision
/// pipeline between its rounds), only the motion changes. friction: Coulomb's coefficient (the
/// scene's, or 0 for a step taken again sliding). Returns how many vertices moved.
int keep_out_of_analytic_obstacles(const Model& model, const std::vector<Vec3>& start, Scalar t_next, Scalar h,
                                   Scalar depth, Scalar friction, std::vector<Vec3>& motion, std::vector<Vec3>* velocities);

/// The velocity at time t of the obstacle's body point now at x (translation plus rotation).
Vec3 body_velocity(const Motion& motion, const Vec3& x_now, Scalar t);

/// A mesh obstacle's vertices at time t.
std::vector<Vec3> posed_vertices(const Obstacle& obstacle, Scalar t);

/// Smallest distance from any of the points to the obstacle at time t (signed for analytic
/// shapes: negative inside).
Scalar distance_to_obstacle(const Obstacle& obstacle, Scalar t, const std::vector<Vec3>& points);

}  // namespace drape
