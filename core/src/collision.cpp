#include "drape/core/collision.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <tuple>
#include <numeric>

#include "drape/ccd/broad_phase.h"
#include "drape/ccd/distance.h"
#include "drape/ccd/patch_tree.h"
#include "drape/core/obstacle.h"

namespace drape {

void CollisionCounters::add(const CollisionCounters& o) {
  bvh_pairs += o.bvh_pairs;
  culled_triangles += o.culled_triangles;
  tests += o.tests;
  vf_tests += o.vf_tests;
  ee_tests += o.ee_tests;
  ccd_hits += o.ccd_hits;
  proximity_impulses += o.proximity_impulses;
  rest_clamped_pairs += o.rest_clamped_pairs;
  impulse_iterations += o.impulse_iterations;
  impact_zones += o.impact_zones;
  fail_safes += o.fail_safes;
  ccd_ms += o.ccd_ms;
  broad_ms += o.broad_ms;
  narrow_ms += o.narrow_ms;
  response_ms += o.response_ms;
}

std::string thickness_note(const Model& model, const CollisionSettings& settings) {
  if (!model.scene.collisions.self) return {};
  Scalar shortest = std::numeric_limits<Scalar>::infinity();
  for (const Spring& s : model.springs)
    if (s.kind == SpringKind::Stretch) shortest = std::min(shortest, s.rest_length);
  const Scalar thickness = model.scene.collisions.thickness;
  if (!(settings.rest_fraction * shortest < thickness)) return {};
  char text[512];
  std::snprintf(text, sizeof text,
                "the thickness (%.3g m) is large against the cloth's shortest edge (%.3g m): features of one cloth "
                "closer than %.3g m in the rest shape keep %.0f %% of their rest distance apart instead of the "
                "thickness (counted per frame as rest_clamped_pairs in stats.csv; docs/collisions.md)",
                thickness, shortest, thickness / settings.rest_fraction, 100 * settings.rest_fraction);
  return text;
}

bool CollisionPipeline::needed(const Model& model) {
  if (model.scene.collisions.self) return true;
  if (!model.scene.collisions.obstacles) return false;
  for (const Obstacle& o : model.obstacles)
    if (o.spec.kind == ObstacleSpec::Kind::Mesh) return true;
  return false;
}

namespace {

// Two directions from a cloth vertex to an obstacle closer than this cosine are one contact
// of the implicit solve (mesh_contacts): the nearest of them is kept.
constexpr Scalar SAME_DIRECTION = 0.95;
// An edge-edge or obstacle-vertex contact of the implicit solve is kept only when its closest
// points lie inside both features by more than this weight; otherwise it is a cloth vertex's
// contact with an obstacle's triangle, found as such.
constexpr Scalar INNER_WEIGHT = 0.01;
// The simultaneous impulses of a round (Impl::impulses): at most this many Gauss-Seidel sweeps,
// fewer once no impulse changes by more than IMPULSE_TOLERANCE times thickness / h.
constexpr int IMPULSE_SWEEPS = 100;
constexpr Scalar IMPULSE_TOLERANCE = 1e-3;

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point begin) { return std::chrono::duration<double, std::milli>(Clock::now() - begin).count(); }

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

}  // namespace

struct CollisionPipeline::Impl {
  const Model& model;
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
  std::vector<Vec3> start, end;      // combined positions at t and t + h
  std::vector<ccd::Aabb> boxes;
  std::vector<ccd::FeatureVolume> features;  // per-vertex swept volumes for feature_pairs (empty: no feature culling)
  ccd::Options options;
  CollisionPipeline::Observer observer;

  explicit Impl(const Model& m, const CollisionSettings& s) : model(m), settings(s) {
    cloth_vertices = int(m.vertex_count());
    for (const Triangle& t : m.triangles) cloth_triangles.push_back({t[0], t[1], t[2]});
    int offset = cloth_vertices;
    if (m.scene.collisions.obstacles) {
      for (const Obstacle& o : m.obstacles) {
        if (o.spec.kind != ObstacleSpec::Kind::Mesh) continue;
        MeshObstacle mo{&o, offset, {}, {}, {}};
        for (const Triangle& t : o.mesh.triangles) mo.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
        mo.owners = ccd::feature_owners(mo.triangles);
        offset += int(o.mesh.vertices.size());
        obstacles.push_back(std::move(mo));
      }
    }
    inverse_mass.assign(offset, 0.0);
    cloth_of_vertex.assign(std::size_t(cloth_vertices), 0);
    for (std::size_t c = 0; c < m.cloths.size(); ++c)
      for (int v = 0; v < m.cloths[c].vertex_count; ++v) cloth_of_vertex[std::size_t(m.cloths[c].first_vertex + v)] = int(c);
    for (int v = 0; v < cloth_vertices; ++v)
      if (m.pin_of_vertex[v] < 0) inverse_mass[v] = 1.0 / m.masses[v];
    start.resize(offset);
    end.resize(offset);
    if (m.scene.collisions.self && m.scene.collisions.self_culling) patch_tree = ccd::PatchTree(cloth_triangles, m.initial_positions);
    cloth_owners = ccd::feature_owners(cloth_triangles);
    options.method = m.scene.collisions.method;
    options.thickness = 0;  // exact contact; the thickness is kept by proximity repulsion
  }

  // Candidate elementary tests for the motion start -> end, boxes grown by margin; the cloth
  // against itself too when self-collision is on and self is asked for; with moved (a flag per
  // vertex), only the tests with a moved vertex.
  ccd::Candidates candidates(Scalar margin, CollisionCounters& counters, bool self = true,
                             std::span<const std::uint8_t> moved = {}) {
    const auto begin = Clock::now();
    ccd::Candidates all;
    const bool self_pairs = self && model.scene.collisions.self;
    const bool culling = self_pairs && model.scene.collisions.self_culling;
    // The cloth's btDbvt serves the mesh obstacles, and self-collision without culling.
    if (!obstacles.empty() || (self_pairs && !culling)) {
      boxes.resize(cloth_triangles.size());
      for (std::size_t i = 0; i < cloth_triangles.size(); ++i) boxes[i] = ccd::swept_box(cloth_triangles[i], start, end, margin);
      cloth_tree.update(boxes);
    }
    bool features_ready = false;
    const auto append = [&](std::span<const ccd::TriangleIndices> other, const ccd::FeatureOwners& other_owners,
                            const std::vector<std::pair<std::int32_t, std::int32_t>>& pairs) {
      counters.bvh_pairs += long(pairs.size());
      if (pairs.empty()) return;
      if (!features_ready) {
        if (model.scene.collisions.feature_boxes) features = ccd::vertex_volumes(start, end, margin);
        else features.clear();
        features_ready = true;
      }
      // Each test once by its features' triangles; without feature volumes (the paper's count,
      // every test of every overlapping pair), every pair's tests, sorted and made unique.
      ccd::Candidates c =
          features.empty() ? ccd::feature_pairs(cloth_triangles, other, pairs, features, settings.threads, moved)
                           : ccd::feature_pairs(cloth_triangles, other, pairs, cloth_owners, other_owners, features,
                                                settings.threads, moved);
      all.vertex_face.insert(all.vertex_face.end(), c.vertex_face.begin(), c.vertex_face.end());
      all.edge_edge.insert(all.edge_edge.end(), c.edge_edge.begin(), c.edge_edge.end());
    };
    if (culling) {
      ccd::SelfCullCounters culled;
      append(cloth_triangles, cloth_owners, patch_tree.self_pairs(start, end, margin, settings.threads, &culled, moved));
      counters.culled_triangles += culled.triangles_culled;
    } else if (self_pairs) {
      append(cloth_triangles, cloth_owners, cloth_tree.self_pairs());
    }
    for (MeshObstacle& mo : obstacles) {
      std::vector<ccd::Aabb> obstacle_boxes(mo.triangles.size());
      for (std::size_t i = 0; i < mo.triangles.size(); ++i) obstacle_boxes[i] = ccd::swept_box(mo.triangles[i], start, end, margin);
      mo.tree.update(obstacle_boxes);
      append(mo.triangles, mo.owners, cloth_tree.pairs_with(mo.tree));
    }
    counters.broad_ms += ms_since(begin);
    return all;
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
  int impulses(ContactSet& set, Scalar h, std::vector<Vec3>& motion) const {
    const auto apply = [&](std::size_t i, const Vec3& change) {
      const Contact& c = set.contacts[i];
      for (int k = 0; k < 4; ++k)
        if (c.vertex[k] < cloth_vertices) motion[c.vertex[k]] += c.weight[k] * inverse_mass[c.vertex[k]] / set.denominator[i] * change;
    };
    const Scalar tolerance = IMPULSE_TOLERANCE * model.scene.collisions.thickness / h;
    for (int sweep = 0; sweep < IMPULSE_SWEEPS; ++sweep) {
      Scalar largest = 0;
      for (std::size_t i = 0; i < set.contacts.size(); ++i) {
        if (!(set.denominator[i] > 0)) continue;
        const Contact& c = set.contacts[i];
        const Scalar change = std::max<Scalar>(-set.pushed[i], set.target[i] - relative_velocity(c, h, motion).dot(c.normal));
        // A contact starts pushing only for an approach beyond the tolerance: a resting contact
        // that the solve held approaches by rounding, and an impulse there would set off the
        // response's re-solve for nothing.
        if (change == 0 || (set.pushed[i] == 0 && change < tolerance)) continue;
        set.pushed[i] += change;
        largest = std::max(largest, std::abs(change));
        apply(i, change * c.normal);
      }
      if (!(largest > tolerance)) break;
    }
    int count = 0;
    for (std::size_t i = 0; i < set.contacts.size(); ++i) {
      if (!(set.pushed[i] > 0)) continue;
      ++count;
      const Contact& c = set.contacts[i];
      const Vec3 relative = relative_velocity(c, h, motion);
      const Vec3 tangential = relative - relative.dot(c.normal) * c.normal;
      const Scalar slide = tangential.norm();
      const Scalar rub = std::min(model.scene.friction * set.pushed[i] - set.rubbed[i], slide);
      if (!(rub > 0)) continue;
      set.rubbed[i] += rub;
      apply(i, -rub * tangential / slide);
    }
    return count;
  }

  // The contact of a vertex-face or edge-edge pair: weights from the closest points at time s
  // of the step, normal from the features at toc oriented as they were at the start.
  Contact contact(bool vertex_face, const std::array<int, 4>& v, Scalar toc) const {
    const auto at = [&](int k, Scalar s) -> Vec3 { return start[v[k]] + s * (end[v[k]] - start[v[k]]); };
    Contact c;
    c.vertex_face = vertex_face;
    c.vertex = v;
    if (vertex_face) {
      const auto closest = ccd::closest_point_triangle<Scalar>(at(0, toc), at(1, toc), at(2, toc), at(3, toc));
      const Scalar wb = closest.weight_b, wc = closest.weight_c;
      c.weight = {1, -(1 - wb - wc), -wb, -wc};
      Vec3 n = (at(2, toc) - at(1, toc)).cross(at(3, toc) - at(1, toc));
      const Vec3 offset_at_start = at(0, 0) - ccd::closest_point_triangle<Scalar>(at(0, 0), at(1, 0), at(2, 0), at(3, 0)).point;
      if (!(n.norm() > 0)) n = offset_at_start;
      if (n.dot(offset_at_start) < 0) n = -n;
      c.normal = n.norm() > 0 ? Vec3(n.normalized()) : Vec3::UnitZ();
    } else {
      const auto closest = ccd::closest_segment_segment<Scalar>(at(0, toc), at(1, toc), at(2, toc), at(3, toc));
      c.weight = {1 - closest.s, closest.s, -(1 - closest.u), -closest.u};
      Vec3 n = (at(1, toc) - at(0, toc)).cross(at(3, toc) - at(2, toc));
      const auto at_start = ccd::closest_segment_segment<Scalar>(at(0, 0), at(1, 0), at(2, 0), at(3, 0));
      const Vec3 offset_at_start = at_start.point_a - at_start.point_b;
      if (!(n.squaredNorm() > 1e-12 * (at(1, toc) - at(0, toc)).squaredNorm() * (at(3, toc) - at(2, toc)).squaredNorm()))
        n = offset_at_start;
      if (n.dot(offset_at_start) < 0) n = -n;
      c.normal = n.norm() > 0 ? Vec3(n.normalized()) : Vec3::UnitZ();
    }
    return c;
  }

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

  // The time of contact the response uses: vincent's for any method that agrees on the hit,
  // so that the method chosen changes the cost of detection, never the simulation (cubic and
  // dnf find the same roots, to rounding; those last bits would otherwise grow into different
  // trajectories). Where vincent sees no hit (conservative's near misses), the method's own.
  Scalar canonical_toc(ccd::QueryKind kind, const ccd::Query& query, Scalar toc) const {
    if (options.method == ccd::Method::Vincent) return toc;
    ccd::Options vincent = options;
    vincent.method = ccd::Method::Vincent;
    const ccd::Result r = ccd::elementary_ccd(kind, query, vincent);
    return r.hit ? r.toc : toc;
  }

  // One detection round: the collisions of the current motion. A later round passes the flags
  // of the vertices whose motion changed since the round before, and that round's hits: the
  // tests without a moved vertex have the motion that round tested, so its hits among them
  // stand and only the others are run (the hits in the order a whole round gives them).
  std::vector<std::pair<Contact, Scalar>> detect(Scalar h, const std::vector<Vec3>& motion, CollisionCounters& counters,
                                                 ccd::Candidates* keep = nullptr,
                                                 const std::vector<std::uint8_t>* moved = nullptr,
                                                 const std::vector<std::pair<Contact, Scalar>>* before = nullptr) {
    const auto begin = Clock::now();
    set_end(h, motion);
    const long pairs_before = counters.bvh_pairs;
    ccd::Candidates c = candidates(model.scene.collisions.thickness, counters, true,
                                   moved ? std::span<const std::uint8_t>(*moved) : std::span<const std::uint8_t>{});
    const ccd::BatchInput input{start, end, c.vertex_face, c.edge_edge};
    if (observer) observer(input, counters.bvh_pairs - pairs_before);
    const auto narrow_begin = Clock::now();
    const ccd::BatchOutput out = ccd::run_batch(input, options, settings.threads);
    counters.narrow_ms += ms_since(narrow_begin);
    counters.tests += out.counters;
    counters.vf_tests += long(c.vertex_face.size());
    counters.ee_tests += long(c.edge_edge.size());
    std::vector<std::pair<Contact, Scalar>> hits;
    for (const ccd::BatchHit& hit : out.vertex_face) {
      const auto& p = c.vertex_face[hit.index];
      const Scalar toc = canonical_toc(ccd::QueryKind::VertexFace, ccd::gather(input, p), hit.result.toc);
      hits.emplace_back(contact(true, {p.vertex, p.face[0], p.face[1], p.face[2]}, toc), toc);
    }
    for (const ccd::BatchHit& hit : out.edge_edge) {
      const auto& p = c.edge_edge[hit.index];
      const Scalar toc = canonical_toc(ccd::QueryKind::EdgeEdge, ccd::gather(input, p), hit.result.toc);
      hits.emplace_back(contact(false, {p.edge_a[0], p.edge_a[1], p.edge_b[0], p.edge_b[1]}, toc), toc);
    }
    if (moved && before)
      for (const auto& hit : *before)
        if (std::none_of(hit.first.vertex.begin(), hit.first.vertex.end(), [&](int v) { return (*moved)[std::size_t(v)] != 0; }))
          hits.push_back(hit);
    // The tests come unsorted (feature_pairs' owners): the hits in a whole round's order.
    std::sort(hits.begin(), hits.end(), [&](const auto& a, const auto& b) { return listed_before(a.first, b.first); });
    counters.ccd_hits += long(hits.size());
    counters.ccd_ms += ms_since(begin);
    if (keep) *keep = std::move(c);
    return hits;
  }

  // The self-collision response must not push cloth into a sphere or plane (the integrator
  // answered those before): a free vertex whose end position lies within half the thickness of
  // one is moved back out to that depth. Runs before every re-detection, so what the final
  // detection sees is both above the shapes and, when it finds nothing, intersection-free.
  void keep_out_of_analytic_obstacles(Scalar t_next, Scalar h, std::vector<Vec3>& motion) const {
    if (!model.scene.collisions.obstacles) return;
    const Scalar floor = 0.5 * model.scene.collisions.thickness;
    for (const Obstacle& obstacle : model.obstacles) {
      if (obstacle.spec.kind == ObstacleSpec::Kind::Mesh) continue;
      const PosedShape shape = pose_shape(obstacle, t_next);
      for (int v = 0; v < cloth_vertices; ++v)
        if (inverse_mass[v] > 0) push_out(shape, t_next, start[v], h, floor, motion[v]);
    }
  }

  // The gap kept between two features: the thickness, but for features of one cloth that are
  // closer than it in the rest shape (neighbours on a mesh finer than the thickness), which
  // keep rest_fraction of their rest distance (docs/collisions.md, "Thickness and the rest
  // shape"). Pairs with an obstacle vertex, or across two cloths, keep the thickness.
  Scalar kept_gap(bool vertex_face, const std::array<int, 4>& v, CollisionCounters& counters) const {
    const Scalar thickness = model.scene.collisions.thickness;
    for (int k = 0; k < 4; ++k)
      if (v[k] >= cloth_vertices || cloth_of_vertex[std::size_t(v[k])] != cloth_of_vertex[std::size_t(v[0])]) return thickness;
    const auto& r = model.initial_positions;
    const auto p = [&](int k) -> const Vec3& { return r[std::size_t(v[k])]; };
    const Scalar rest_squared = vertex_face ? ccd::closest_point_triangle<Scalar>(p(0), p(1), p(2), p(3)).distance_squared
                                            : ccd::closest_segment_segment<Scalar>(p(0), p(1), p(2), p(3)).distance_squared;
    const Scalar f = settings.rest_fraction;
    if (f * f * rest_squared >= thickness * thickness) return thickness;
    ++counters.rest_clamped_pairs;
    return f * std::sqrt(rest_squared);
  }

  // Proximity repulsion (Bridson, Fedkiw and Anderson 2002, section 7.2: its inelastic impulse,
  // without the spring push that follows): features closer than their kept gap at the start
  // get, all together, the impulses that stop their approach, and no more. Never a separating
  // velocity: the normal kinetic energy only falls, and a resting or freely falling cloth gets
  // none.
  void repel(const ccd::Candidates& c, Scalar h, std::vector<Vec3>& motion, ContactSet& set, CollisionCounters& counters) {
    const Scalar thickness = model.scene.collisions.thickness;
    std::vector<Contact> near;
    const auto push = [&](bool vertex_face, Contact contact, const Vec3& offset) {
      const Scalar distance = offset.norm();
      if (!(distance < thickness) || !(distance > 0)) return;
      const Scalar gap = kept_gap(vertex_face, contact.vertex, counters);
      if (!(distance < gap)) return;
      contact.vertex_face = vertex_face;
      contact.normal = offset / distance;
      near.push_back(contact);
    };
    for (const auto& p : c.vertex_face) {
      const auto closest = ccd::closest_point_triangle<Scalar>(start[p.vertex], start[p.face[0]], start[p.face[1]], start[p.face[2]]);
      Contact contact;
      contact.vertex = {p.vertex, p.face[0], p.face[1], p.face[2]};
      contact.weight = {1, -(1 - closest.weight_b - closest.weight_c), -closest.weight_b, -closest.weight_c};
      push(true, contact, start[p.vertex] - closest.point);
    }
    for (const auto& p : c.edge_edge) {
      const auto closest = ccd::closest_segment_segment<Scalar>(start[p.edge_a[0]], start[p.edge_a[1]], start[p.edge_b[0]], start[p.edge_b[1]]);
      Contact contact;
      contact.vertex = {p.edge_a[0], p.edge_a[1], p.edge_b[0], p.edge_b[1]};
      contact.weight = {1 - closest.s, closest.s, -(1 - closest.u), -closest.u};
      push(false, contact, closest.point_a - closest.point_b);
    }
    // The tests come unsorted (feature_pairs' owners): the contacts in a whole round's order.
    std::sort(near.begin(), near.end(), [&](const Contact& a, const Contact& b) { return listed_before(a, b); });
    for (const Contact& contact : near) set.add(contact, 0, inverse_mass);
    counters.proximity_impulses += impulses(set, h, motion);
  }

  // Rigid impact zones: each zone's cloth vertices move with the zone's rigid motion (its
  // momentum and angular momentum kept), or with its kinematic vertices when it holds any.
  void apply_zones(Zones& zones, Scalar h, std::vector<Vec3>& motion, CollisionCounters& counters) {
    std::vector<std::vector<int>> members(start.size());
    for (int v = 0; v < int(start.size()); ++v) members[zones.find(v)].push_back(v);
    for (const auto& zone : members) {
      if (zone.size() < 2) continue;
      ++counters.impact_zones;
      Vec3 kinematic_velocity = Vec3::Zero();
      int kinematic = 0;
      Scalar mass = 0;
      Vec3 momentum = Vec3::Zero(), centre = Vec3::Zero();
      for (int v : zone) {
        if (inverse_mass[v] == 0) {
          kinematic_velocity += velocity(v, h, motion);
          ++kinematic;
          continue;
        }
        const Scalar m = 1 / inverse_mass[v];
        mass += m;
        momentum += m * motion[v];
        centre += m * start[v];
      }
      if (kinematic > 0) {
        for (int v : zone)
          if (v < cloth_vertices && inverse_mass[v] > 0) motion[v] = kinematic_velocity / kinematic;
        continue;
      }
      centre /= mass;
      const Vec3 linear = momentum / mass;
      Vec3 angular_momentum = Vec3::Zero();
      Mat3 inertia = Mat3::Zero();
      for (int v : zone) {
        const Scalar m = 1 / inverse_mass[v];
        const Vec3 r = start[v] - centre;
        angular_momentum += m * r.cross(motion[v] - linear);
        inertia += m * (r.squaredNorm() * Mat3::Identity() - r * r.transpose());
      }
      const Vec3 omega = inertia.completeOrthogonalDecomposition().solve(angular_momentum);
      for (int v : zone) motion[v] = linear + omega.cross(start[v] - centre);
    }
  }
};

CollisionPipeline::CollisionPipeline(const Model& model, const CollisionSettings& settings)
    : impl_(std::make_unique<Impl>(model, settings)) {}
CollisionPipeline::~CollisionPipeline() = default;

void CollisionPipeline::set_observer(Observer observer) {
  impl_->observer = std::move(observer);
}

std::vector<SolveContact> CollisionPipeline::mesh_contacts(const std::vector<Vec3>& start, Scalar t, Scalar h,
                                                           Scalar reach) {
  Impl& m = *impl_;
  std::vector<SolveContact> out;
  if (m.obstacles.empty()) return out;
  for (int v = 0; v < m.cloth_vertices; ++v) m.start[v] = m.end[v] = start[v];
  m.pose_obstacles(t, h);
  CollisionCounters unused;
  ccd::Candidates c = m.candidates(reach, unused, false);
  // In a whole round's order (feature_pairs' owners leave the tests unsorted): which of several
  // nearly equal contacts is kept depends on it.
  const auto vf_key = [&](const ccd::VertexFacePair& p) {
    const std::array<int, 4> v{p.vertex, p.face[0], p.face[1], p.face[2]};
    return std::make_pair(m.source(v), v);
  };
  const auto ee_key = [&](const ccd::EdgeEdgePair& p) {
    const std::array<int, 4> v{p.edge_a[0], p.edge_a[1], p.edge_b[0], p.edge_b[1]};
    return std::make_pair(m.source(v), v);
  };
  std::sort(c.vertex_face.begin(), c.vertex_face.end(), [&](const auto& a, const auto& b) { return vf_key(a) < vf_key(b); });
  std::sort(c.edge_edge.begin(), c.edge_edge.end(), [&](const auto& a, const auto& b) { return ee_key(a) < ee_key(b); });
  // Per cloth feature (its vertices), its nearest obstacle points in distinct directions.
  std::map<std::array<int, 3>, std::vector<std::pair<Scalar, SolveContact>>> near;
  const auto free = [&](int v) { return v < m.cloth_vertices && m.inverse_mass[std::size_t(v)] > 0; };
  const auto velocity = [&](int v) -> Vec3 { return (m.end[v] - m.start[v]) / h; };
  // offset: from the obstacle's point to the cloth's; obstacle_velocity: of the obstacle's point.
  const auto add = [&](SolveContact contact, const Vec3& offset, const Vec3& obstacle_velocity) {
    const Scalar distance = offset.norm();
    if (!(distance < reach) || !(distance > 0)) return;
    contact.normal = offset / distance;
    contact.surface_velocity = obstacle_velocity;
    contact.target = contact.normal.dot(obstacle_velocity);
    std::array<int, 3> key = contact.vertex;
    std::sort(key.begin(), key.end());
    auto& list = near[key];
    for (auto& [d, known] : list)
      if (known.normal.dot(contact.normal) > SAME_DIRECTION) {
        if (distance < d) d = distance, known = contact;
        return;
      }
    list.emplace_back(distance, contact);
  };
  const auto inner = [](Scalar w) { return w > INNER_WEIGHT && w < 1 - INNER_WEIGHT; };
  const auto& x = m.start;
  for (const auto& p : c.vertex_face) {
    const auto& f = p.face;
    const auto closest = ccd::closest_point_triangle<Scalar>(x[p.vertex], x[f[0]], x[f[1]], x[f[2]]);
    const Scalar wb = closest.weight_b, wc = closest.weight_c, wa = 1 - wb - wc;
    SolveContact contact;
    if (free(p.vertex)) {  // a cloth vertex and an obstacle's triangle
      contact.vertex = {p.vertex, -1, -1};
      contact.weight = {1, 0, 0};
      add(contact, x[p.vertex] - closest.point, wa * velocity(f[0]) + wb * velocity(f[1]) + wc * velocity(f[2]));
    } else if (p.vertex >= m.cloth_vertices && free(f[0]) && free(f[1]) && free(f[2]) && inner(wa) && inner(wb) &&
               inner(wc)) {  // an obstacle's vertex and a cloth triangle
      contact.vertex = {f[0], f[1], f[2]};
      contact.weight = {wa, wb, wc};
      contact.count = 3;
      add(contact, closest.point - x[p.vertex], velocity(p.vertex));
    }
  }
  for (const auto& p : c.edge_edge) {  // edge_a is the cloth's (its indices are the smaller)
    if (!free(p.edge_a[0]) || !free(p.edge_a[1])) continue;
    const auto closest = ccd::closest_segment_segment<Scalar>(x[p.edge_a[0]], x[p.edge_a[1]], x[p.edge_b[0]], x[p.edge_b[1]]);
    if (!inner(closest.s) || !inner(closest.u)) continue;  // a vertex's contact, found as such
    SolveContact contact;
    contact.vertex = {p.edge_a[0], p.edge_a[1], -1};
    contact.weight = {1 - closest.s, closest.s, 0};
    contact.count = 2;
    add(contact, closest.point_a - closest.point_b,
        (1 - closest.u) * velocity(p.edge_b[0]) + closest.u * velocity(p.edge_b[1]));
  }
  // An edge's or triangle's contact whose every vertex has its own contact in that direction
  // would over-determine the solve (penalties with different targets fighting): dropped.
  std::map<int, std::vector<Vec3>> vertex_normals;
  for (const auto& [key, list] : near)
    for (const auto& [d, contact] : list)
      if (contact.count == 1) vertex_normals[contact.vertex[0]].push_back(contact.normal);
  const auto has_own = [&](int v, const Vec3& normal) {
    const auto found = vertex_normals.find(v);
    if (found == vertex_normals.end()) return false;
    return std::any_of(found->second.begin(), found->second.end(),
                       [&](const Vec3& n) { return n.dot(normal) > SAME_DIRECTION; });
  };
  for (const auto& [key, list] : near)
    for (const auto& [d, contact] : list) {
      bool covered = contact.count > 1;
      for (int i = 0; i < contact.count && covered; ++i) covered = has_own(contact.vertex[i], contact.normal);
      if (!covered) out.push_back(contact);
    }
  return out;
}

CollisionCounters CollisionPipeline::resolve(const std::vector<Vec3>& start, Scalar t, Scalar h, std::vector<Vec3>& motion) {
  Impl& m = *impl_;
  CollisionCounters counters;
  const auto begin = Clock::now();
  for (int v = 0; v < m.cloth_vertices; ++v) m.start[v] = start[v];
  m.pose_obstacles(t, h);
  const Scalar separation = m.settings.separation_fraction * m.model.scene.collisions.thickness / h;

  // Proximity repulsion on the first round's candidates, then CCD impulses until no collision.
  ccd::Candidates first;
  auto hits = m.detect(h, motion, counters, &first);
  Impl::ContactSet contacts;
  // Detection is a function of the motion, test by test: a round after the first runs only the
  // tests with a vertex whose motion changed since the round before (none: its hits stand).
  std::vector<Vec3> detected = motion;
  std::vector<std::uint8_t> moved(m.start.size(), 0);
  const auto redetect = [&] {
    bool any = false;
    for (int v = 0; v < m.cloth_vertices; ++v) any |= (moved[std::size_t(v)] = motion[std::size_t(v)] != detected[std::size_t(v)]);
    if (!any) return;
    hits = m.settings.incremental_rounds ? m.detect(h, motion, counters, nullptr, &moved, &hits) : m.detect(h, motion, counters);
    detected = motion;
  };
  m.repel(first, h, motion, contacts, counters);
  m.keep_out_of_analytic_obstacles(t + h, h, motion);
  redetect();
  for (int round = 0; !hits.empty() && round < m.model.scene.collisions.max_impulse_iterations; ++round) {
    ++counters.impulse_iterations;
    for (const auto& [contact, toc] : hits) contacts.add(contact, separation, m.inverse_mass);
    m.impulses(contacts, h, motion);
    m.keep_out_of_analytic_obstacles(t + h, h, motion);
    redetect();
  }
  // Impact zones, growing until no collision is left.
  Zones zones(int(m.start.size()));
  for (int round = 0; !hits.empty() && round < m.model.scene.collisions.max_zone_iterations; ++round) {
    for (const auto& [contact, toc] : hits)
      for (int k = 1; k < 4; ++k) zones.join(contact.vertex[0], contact.vertex[k]);
    m.apply_zones(zones, h, motion, counters);
    m.keep_out_of_analytic_obstacles(t + h, h, motion);
    redetect();
  }
  // The fail-safe: colliding cloth vertices keep their start positions; then all of them.
  if (!hits.empty()) {
    ++counters.fail_safes;
    for (const auto& [contact, toc] : hits)
      for (int v : contact.vertex)
        if (v < m.cloth_vertices && m.inverse_mass[v] > 0) motion[v] = Vec3::Zero();
    redetect();
    if (!hits.empty())
      for (int v = 0; v < m.cloth_vertices; ++v)
        if (m.inverse_mass[v] > 0) motion[v] = Vec3::Zero();
  }
  counters.response_ms = ms_since(begin) - counters.ccd_ms;
  return counters;
}

}  // namespace drape
