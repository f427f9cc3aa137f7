#pragma once
/// \file
/// The collision pipeline of a step: broad phase, CCD, impulses, impact zones, fail-safe.
///
/// The collision pipeline of a step (Bridson, Fedkiw and Anderson, "Robust treatment of
/// collisions, contact and friction for cloth animation", SIGGRAPH 2002; Harmon et al.,
/// "Robust treatment of simultaneous collisions", SIGGRAPH 2008): given the start positions,
/// which are intersection-free, and the velocities the solver proposes, it changes the
/// velocities until the straight-line motion of the step is free of collisions, cloth against
/// itself and against mesh obstacles:
///   broad phase (btDbvt over swept triangle boxes) -> elementary tests (the scene's CCD
///   method, in parallel) -> proximity repulsion of approaching features within the thickness
///   (or within their rest distance's share, for neighbours of a fine mesh) -> CCD impulses,
///   iterated -> rigid impact zones -> the fail-safe (colliding vertices keep their start
///   positions, then all cloth vertices do).

#include <array>
#include <functional>
#include <memory>
#include <string>

#include "drape/ccd/batch.h"
#include "drape/core/model.h"

namespace drape {

/// Separation speed an impulse leaves between colliding features, as a fraction of
/// thickness / h: enough that the next round does not find the same contact again.
constexpr Scalar SEPARATION_FRACTION = 0.1;
/// Features of one cloth closer than the thickness in the rest shape keep this fraction of
/// their rest distance as their gap instead of the thickness (docs/collisions.md).
constexpr Scalar REST_FRACTION = 0.5;

/// How a run executes the pipeline, beyond the model (whose scene's collisions section gives
/// the thickness, the CCD method and the impulse and impact-zone rounds): neither changes the
/// simulation.
struct CollisionSettings {
  int threads = 1;  ///< narrow-phase threads (results do not depend on it)
  /// A detection round after the first runs only the tests with a vertex whose motion changed
  /// since the round before, keeping that round's other hits; false: every round runs every
  /// test (the same hits, in the same order; for tests and benchmarks).
  bool incremental_rounds = true;
};

/// What the pipeline did in one step; summed into the frame statistics.
struct CollisionCounters {
  long bvh_pairs = 0;           ///< overlapping triangle pairs, summed over detection rounds
  long culled_triangles = 0;    ///< triangles in patches proven free of self-contact (their pairs never enumerated), summed over rounds
  ccd::BatchCounters tests;     ///< elementary tests (vertex-face + edge-edge), culled, ...
  long vf_tests = 0, ee_tests = 0;
  long ccd_hits = 0;            ///< collisions found, summed over rounds
  long proximity_impulses = 0;
  long held_self_contacts = 0;  ///< the cloth's contacts with itself held in the implicit solve (collisions.self_in_solve)
  long rest_clamped_pairs = 0;  ///< proximity pairs whose gap the rest shape made smaller than the thickness
  long impulse_iterations = 0;  ///< CCD-impulse rounds that found collisions
  long impact_zones = 0;        ///< zones formed (counted each round)
  long fail_safes = 0;          ///< steps that needed the fail-safe
  double ccd_ms = 0;            ///< detection rounds: broad and narrow phase, and the contacts built from the hits
  double broad_ms = 0;          ///< the broad phase: swept boxes, the trees, and their pairs' features (all rounds and contact searches)
  double narrow_ms = 0;         ///< the narrow phase: the elementary tests of the detection rounds
  double response_ms = 0;       ///< everything else
  void add(const CollisionCounters& other);
};

/// What the user should know when the thickness is large against a cloth's edges: with
/// self-collision on and a stretch edge shorter than thickness / REST_FRACTION, neighbours of
/// the rest shape keep REST_FRACTION of their rest distance instead of the thickness (counted
/// in the statistics as rest_clamped_pairs). Empty when nothing to say.
std::string thickness_note(const Model& model);

/// Two directions from a cloth feature to an obstacle closer than this cosine (about 18
/// degrees) are one contact of the implicit solve: the nearest is kept, and an edge's or
/// face's contact is left to its corners' own when each has one in such a direction.
constexpr Scalar SAME_DIRECTION = 0.95;
/// An edge's or face's contact of the implicit solve is kept only where its closest point lies
/// inside the feature (each of its weights, and the obstacle feature's, above this);
/// otherwise it is a vertex's contact, found as such, or, for an obstacle's vertex closest to a
/// cloth triangle's edge, that edge's.
constexpr Scalar INNER_WEIGHT = 0.01;

/// Two cloth edges are a contact of the implicit solve only when the sine of their angle is at
/// least this (about 6 degrees): nearly parallel edges have no common perpendicular to hold.
constexpr Scalar SELF_EDGE_CROSSING = 0.1;

/// A contact the implicit solve keeps (Baraff and Witkin 1998, section 5.3: a constraint on
/// the velocity along the contact's normal; here held by a penalty): the relative velocity of
/// its cloth points, sum_k weight_k v_k over its cloth vertices (a vertex; an edge's two, by
/// the closest point's weights; a triangle's three), along normal (unit, from the obstacle to
/// the cloth) must reach at least target (m/s) at the step's end. A contact of the cloth with
/// itself (`self`) has both sides' vertices, a vertex and a triangle's three or two edges' two,
/// one side's weights negative: sum_k weight_k v_k is then the two points' relative velocity,
/// which its normal (from the second side to the first) may not close.
struct SolveContact {
  std::array<int, 4> vertex{-1, -1, -1, -1};
  std::array<Scalar, 4> weight{};
  int count = 1;  ///< cloth vertices in use
  Vec3 normal = Vec3::UnitZ();
  Scalar target = 0;
  Vec3 surface_velocity = Vec3::Zero();  ///< the obstacle's at the contact, for friction
  Scalar distance = 0;                   ///< m: between the cloth's point and the obstacle's at the step's start
  bool analytic = false;                 ///< with a sphere or plane (else a mesh obstacle or the cloth)
  bool self = false;                     ///< the cloth with itself (no obstacle, no friction in the solve)
};

class CollisionPipeline {
 public:
  CollisionPipeline(const Model& model, const CollisionSettings& settings);
  ~CollisionPipeline();
  /// start: positions at time t (intersection-free). motion: proposed velocities, changed in
  /// place so that start + h motion is free of collisions. Kinematic vertices (pinned cloth
  /// vertices, obstacles) are never changed. friction: Coulomb's coefficient of the impulses
  /// (the scene's, or 0 for a step taken again sliding).
  CollisionCounters resolve(const std::vector<Vec3>& start, Scalar t, Scalar h, std::vector<Vec3>& motion, Scalar friction);

  /// The contacts of the free cloth with the mesh obstacles at the step's start, within reach:
  /// a cloth vertex and an obstacle's triangle, a cloth edge and an obstacle's edge (each
  /// closest at an inner point of both), an obstacle's vertex and a cloth triangle (closest
  /// inside it) or a cloth edge (its projection on a triangle's plane on the edge, within
  /// INNER_WEIGHT); for each cloth feature the nearest in each distinct direction (a rim gives
  /// the top's and the side's). Each may not approach the obstacle within the step. The broad
  /// phase's time and pairs join counters.
  std::vector<SolveContact> mesh_contacts(const std::vector<Vec3>& start, Scalar t, Scalar h, Scalar reach,
                                          CollisionCounters& counters);

  /// The contacts of the cloth with itself at the step's start (self-collision on): each
  /// vertex-face and edge-edge pair of free vertices closer than reach times the gap the
  /// response keeps between them (the thickness, or the rest shape's share of it), closest
  /// inside both features (each weight above INNER_WEIGHT) and, for two edges, not nearly
  /// parallel (SELF_EDGE_CROSSING), in a whole round's order. The broad phase's time and pairs
  /// join counters.
  std::vector<SolveContact> self_contacts(const std::vector<Vec3>& start, Scalar reach, CollisionCounters& counters);

  /// Whether the scene needs the pipeline at all (self-collision on, or mesh obstacles with
  /// obstacle collisions on): a scene pays only for what it asks for.
  static bool needed(const Model& model);

  /// Called with the elementary tests of every detection round (the first of a step, then one
  /// after each impulse or impact-zone round) and the count of overlapping triangle pairs they
  /// came from: the benchmarks measure each CCD method on exactly these.
  using Observer = std::function<void(const ccd::BatchInput&, long triangle_pairs)>;
  void set_observer(Observer observer);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace drape
