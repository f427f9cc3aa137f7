#pragma once
/// \file
/// The collision pipeline's state and stages (internal to core): detection in collision.cpp,
/// the response (impulses, impact zones, proximity repulsion) in collision_response.cpp, and the
/// implicit solve's mesh contacts in collision_contacts.cpp.

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <map>
#include <numeric>
#include <span>
#include <tuple>
#include <utility>
#include <vector>

#include "drape/ccd/broad_phase.h"
#include "drape/ccd/patch_tree.h"
#include "drape/core/collision.h"
#include "drape/core/obstacle.h"

namespace drape {

// The simultaneous impulses of a round (Impl::impulses): at most this many Gauss-Seidel sweeps,
// fewer once no impulse changes by more than IMPULSE_TOLERANCE times thickness / h.
inline constexpr int IMPULSE_SWEEPS = 100;
inline constexpr Scalar IMPULSE_TOLERANCE = 1e-3;
// Between its rounds the pipeline keeps free vertices this fraction of the thickness out of the
// spheres and planes, by the same projection as the integrator's response before it (which
// keeps the whole thickness, with friction): a guard against the self-collision response
// pushing cloth into a shape, not a second response (docs/collisions.md).
inline constexpr Scalar ANALYTIC_KEEP_OUT = 0.5;

using Clock = std::chrono::steady_clock;
inline double ms_since(Clock::time_point begin) { return std::chrono::duration<double, std::milli>(Clock::now() - begin).count(); }

// A contact between four vertices: the relative velocity along normal is sum_k weight_k v_k . n.
struct Contact {
  bool vertex_face = true;  // else edge-edge
  std::array<int, 4> vertex{};
  std::array<Scalar, 4> weight{};
  Vec3 normal = Vec3::UnitZ();
};

// Union-find over vertices, for impact zones.
struct Zones {
  std::vector<int> parent;
  explicit Zones(int n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int v) { return parent[v] == v ? v : parent[v] = find(parent[v]); }
  void join(int a, int b) {
    a = find(a), b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);  // deterministic representative
  }
};

struct CollisionPipeline::Impl {
  const Model& model;
  Scalar friction = 0;  // Coulomb's coefficient of the resolve being run (CollisionPipeline::resolve)
  CollisionSettings settings;
  int cloth_vertices = 0;
  std::vector<ccd::TriangleIndices> cloth_triangles;
  struct MeshObstacle {
    const Obstacle* obstacle;
    int first_vertex;
    std::vector<ccd::TriangleIndices> triangles;  // indices into the combined vertex array
    ccd::BoxTree tree;
    ccd::FeatureOwners owners;
  };
  std::vector<MeshObstacle> obstacles;
  ccd::BoxTree cloth_tree;     // the cloth's triangles, against the mesh obstacles (and itself without self_culling)
  ccd::PatchTree patch_tree;   // self-collision with self_culling
  ccd::FeatureOwners cloth_owners;  // which triangle makes the tests of each cloth vertex and edge
  std::vector<Scalar> inverse_mass;  // combined array; 0 for kinematic vertices
  std::vector<int> cloth_of_vertex;  // cloth vertices only: the index of their cloth
  // Whether a cloth's rest shape has features closer than the thickness over REST_FRACTION
  // (an edge shorter than that): only then can a test's kept gap be less than the thickness,
  // and candidates() look at the rest shape's distances (ccd::RestGaps).
  bool rest_gaps = false;
  std::vector<Vec3> start, end;      // combined positions at t and t + h
  std::vector<ccd::Aabb> boxes;
  std::vector<std::int32_t> tree_triangles;  // the cloth triangles in cloth_tree, in order
  std::vector<std::uint8_t> movable;         // per vertex of the combined array (candidates)
  // Per cloth vertex: free, or pinned by a handle that moves at some time. The cloth's tree
  // against still obstacles holds the triangles with such a vertex: the same set in every
  // call (a step's first round sees a moving handle's vertices move, the solve's contact
  // search does not), so the tree is refitted, not rebuilt.
  std::vector<std::uint8_t> may_move;
  std::vector<ccd::FeatureVolume> features;  // per-vertex swept volumes for feature_pairs (empty: no feature culling)
  ccd::Options options;
  CollisionPipeline::Observer observer;

  explicit Impl(const Model& m, const CollisionSettings& s);

  // Candidate elementary tests for the motion start -> end: every test whose two features come
  // closer than reach at some time of the step (and some farther); the cloth against itself too
  // when self-collision is on and self is asked for, against the mesh obstacles unless obstacles
  // is false; with moved (a flag per vertex), only the tests with a moved vertex.
  ccd::Candidates candidates(Scalar reach, CollisionCounters& counters, bool self = true,
                             std::span<const std::uint8_t> moved = {}, bool obstacles = true);

  // Which vertices a first round's test must involve: those free to move or moving over the
  // step (a handle's, a moving obstacle's). A test of pinned and obstacle vertices that all
  // stay where they are finds no contact and can answer none. Empty when every vertex may move.
  std::span<const std::uint8_t> movable_vertices() {
    movable.resize(start.size());
    bool every = true;
    for (std::size_t v = 0; v < start.size(); ++v) {
      movable[v] = inverse_mass[v] > 0 || start[v] != end[v];
      every = every && movable[v];
    }
    return every ? std::span<const std::uint8_t>{} : std::span<const std::uint8_t>(movable);
  }

  // The mesh obstacles' vertices at t (start) and t + h (end).
  void pose_obstacles(Scalar t, Scalar h) {
    for (const MeshObstacle& mo : obstacles) {
      const auto now = posed_vertices(*mo.obstacle, t), next = posed_vertices(*mo.obstacle, t + h);
      std::copy(now.begin(), now.end(), start.begin() + mo.first_vertex);
      std::copy(next.begin(), next.end(), end.begin() + mo.first_vertex);
    }
  }

  void set_end(Scalar h, const std::vector<Vec3>& motion) {
    for (int v = 0; v < cloth_vertices; ++v) end[v] = start[v] + h * motion[v];
  }

  // Velocity of any vertex of the combined array: cloth from motion, obstacles from their poses.
  Vec3 velocity(int v, Scalar h, const std::vector<Vec3>& motion) const {
    return v < cloth_vertices ? motion[v] : Vec3((end[v] - start[v]) / h);
  }

  // The contact's relative velocity, sum_k weight_k v_k.
  Vec3 relative_velocity(const Contact& c, Scalar h, const std::vector<Vec3>& motion) const {
    Vec3 relative = Vec3::Zero();
    for (int k = 0; k < 4; ++k) relative += c.weight[k] * velocity(c.vertex[k], h, motion);
    return relative;
  }

  // The contacts of a step's response so far, each with the least relative normal velocity it
  // asks for (its target), the impulse it has applied (as the change of its own relative
  // normal velocity) and the tangential change its friction has made.
  struct ContactSet {
    std::vector<Contact> contacts;
    std::vector<Scalar> target, pushed, rubbed, denominator;
    std::map<std::pair<bool, std::array<int, 4>>, std::size_t> index;  // by kind and vertices
    // Adds a contact, or renews one found before (its impulse so far kept, the larger target).
    void add(const Contact& c, Scalar target_c, const std::vector<Scalar>& inverse_mass) {
      Scalar d = 0;
      for (int k = 0; k < 4; ++k) d += c.weight[k] * c.weight[k] * inverse_mass[c.vertex[k]];
      // (a vertex-face contact 1; 2 3 4 and an edge-edge one 1 2 - 3 4 are two contacts)
      const auto [place, added] = index.emplace(std::make_pair(c.vertex_face, c.vertex), contacts.size());
      if (!added) {
        const std::size_t i = place->second;
        // An impulse along a normal that has turned can no longer be taken back along the new one.
        if (contacts[i].normal.dot(c.normal) < SAME_DIRECTION) pushed[i] = 0, rubbed[i] = 0;
        contacts[i] = c;
        target[i] = std::max(target[i], target_c);
        denominator[i] = d;
        return;
      }
      contacts.push_back(c);
      target.push_back(target_c);
      pushed.push_back(0);
      rubbed.push_back(0);
      denominator.push_back(d);
    }
  };

  // The inelastic impulses of all the contacts so far, solved together (each a change of its
  // relative normal velocity, shared among its vertices by inverse mass and weight, Bridson,
  // Fedkiw and Anderson 2002, section 7.2): projected Gauss-Seidel over accumulated impulses
  // that never turn negative, so that a later contact, of this round or a later one, may take
  // back what an earlier one overdid (applied one after another, contacts of one edge with a
  // triangulated leg sent its vertex back at nearly its approach speed). Then Coulomb friction:
  // each contact's relative tangential velocity shrinks by friction times its normal impulse in
  // all, never reversing. Returns how many contacts push.
  int impulses(ContactSet& set, Scalar h, std::vector<Vec3>& motion) const;

  // The contact of a vertex-face or edge-edge pair from the narrow phase's hit: weights from
  // its contact parameters (the closest points at its time of contact), normal from the
  // features at that time oriented as they were at the start.
  Contact contact(bool vertex_face, const std::array<int, 4>& v, const ccd::Result& hit) const;

  // The order of a whole round's contacts, which the response keeps (its impulses are solved in
  // that order): vertex-face before edge-edge, each kind the cloth's own and then each mesh
  // obstacle's, each of those by its vertices.
  bool listed_before(const Contact& a, const Contact& b) const {
    return std::make_tuple(!a.vertex_face, source(a.vertex), a.vertex) < std::make_tuple(!b.vertex_face, source(b.vertex), b.vertex);
  }
  // Which list a test comes from: 0 the cloth's own, k the k-th mesh obstacle's.
  int source(const std::array<int, 4>& vertices) const {
    const int highest = *std::max_element(vertices.begin(), vertices.end());
    int block = 0;
    for (const MeshObstacle& mo : obstacles) block += highest >= mo.first_vertex;
    return block;
  }

  // The hit the response builds its contact from (time of contact and contact parameters):
  // vincent's for any method that agrees on the hit, so that the method chosen changes the
  // cost of detection, never the simulation (cubic and dnf find the same roots, to rounding;
  // those last bits would otherwise grow into different trajectories). Where vincent sees no
  // hit (conservative's near misses), the method's own. With vincent, the hit itself.
  ccd::Result canonical_hit(ccd::QueryKind kind, const ccd::Query& query, const ccd::Result& hit) const;

  // One detection round: the collisions of the current motion. A later round passes the flags
  // of the vertices whose motion changed since the round before, and that round's hits: the
  // tests without a moved vertex have the motion that round tested, so its hits among them
  // stand and only the others are run (the hits in the order a whole round gives them).
  std::vector<std::pair<Contact, Scalar>> detect(Scalar h, const std::vector<Vec3>& motion, CollisionCounters& counters,
                                                 ccd::Candidates* keep = nullptr,
                                                 const std::vector<std::uint8_t>* moved = nullptr,
                                                 const std::vector<std::pair<Contact, Scalar>>* before = nullptr);

  // The self-collision response must not push cloth into a sphere or plane (the integrator
  // answered those before): a free vertex whose end position lies within ANALYTIC_KEEP_OUT of
  // the thickness of one is moved back out to that depth, and a face a sphere comes between the
  // corners of to its share of it (drape::keep_out_of_analytic_obstacles, without friction). Runs before every re-detection, so what the final detection sees is both
  // above the shapes and, when it finds nothing, intersection-free.
  void keep_out_of_analytic_obstacles(Scalar t_next, Scalar h, std::vector<Vec3>& motion) const;

  // The gap kept between two features: the thickness, but for features of one cloth that are
  // closer than it in the rest shape (neighbours on a mesh finer than the thickness), which
  // keep REST_FRACTION of their rest distance (docs/collisions.md, "Thickness and the rest
  // shape"). Pairs with an obstacle vertex, or across two cloths, keep the thickness.
  Scalar kept_gap(bool vertex_face, const std::array<int, 4>& v, CollisionCounters& counters) const;

  // Proximity repulsion (Bridson, Fedkiw and Anderson 2002, section 7.2: its inelastic impulse,
  // without the spring push that follows): features closer than their kept gap at the start
  // get, all together, the impulses that stop their approach, and no more. Never a separating
  // velocity: the normal kinetic energy only falls, and a resting or freely falling cloth gets
  // none.
  void repel(const std::vector<Contact>& near, Scalar h, std::vector<Vec3>& motion, ContactSet& set, CollisionCounters& counters);
  // The features among the candidates closer than their kept gap at the start, repel's
  // contacts, in a whole round's order; with clamped, the pairs closer than the thickness whose
  // gap the rest shape set (counted in rest_clamped_pairs) are added to it.
  std::vector<Contact> near_contacts(const ccd::Candidates& c, CollisionCounters& counters,
                                     std::vector<std::array<int, 4>>* clamped = nullptr) const;

  // The step's last resolve (CollisionPipeline::resolve): its start and time, the motion it
  // ended with when that was free of collisions (clean), its proximity contacts and the pairs
  // whose gap the rest shape set. A resolve of the same start and step (the integrator's rounds
  // of strain limit and response) runs only the tests with a vertex whose motion differs from
  // that clean one: the others' features move as they did there, free of collisions (but for
  // a near miss within the narrow phase's tolerance, as between rounds). It keeps the proximity
  // contacts (and rest-set pairs) without such a vertex and lists the others from the tests it
  // runs. Not provably a whole detection's list: the self-collision culling that decides which
  // pairs are listed is a patch's, and a patch whose changed vertices turn its culling could
  // list or drop a pair of unchanged ones (docs/collisions.md).
  struct LastResolve {
    bool clean = false;
    Scalar t = 0, h = 0;
    std::vector<Vec3> start, motion;
    std::vector<Contact> near;
    std::vector<std::array<int, 4>> clamped;
  } last;

  // Rigid impact zones: each zone's cloth vertices move with the zone's rigid motion (its
  // momentum and angular momentum kept), or with its kinematic vertices when it holds any.
  void apply_zones(Zones& zones, Scalar h, std::vector<Vec3>& motion, CollisionCounters& counters);
};

}  // namespace drape
