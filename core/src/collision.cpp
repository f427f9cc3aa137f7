#include "drape/core/collision.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <tuple>

#include "collision_pipeline.h"
#include "drape/ccd/distance.h"
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
  held_self_contacts += o.held_self_contacts;
  rest_clamped_pairs += o.rest_clamped_pairs;
  impulse_iterations += o.impulse_iterations;
  impact_zones += o.impact_zones;
  fail_safes += o.fail_safes;
  ccd_ms += o.ccd_ms;
  broad_ms += o.broad_ms;
  narrow_ms += o.narrow_ms;
  response_ms += o.response_ms;
}

namespace {

// A mesh obstacle whose swept box meets at most this share (one in FEW_BOXES_SHARE) of the
// cloth's triangle boxes finds its pairs by those boxes alone, without the cloth's tree.
constexpr std::size_t FEW_BOXES_SHARE = 4;

// The cloths' shortest edge at rest.
Scalar shortest_rest_edge(const Model& model) {
  Scalar shortest = std::numeric_limits<Scalar>::infinity();
  for (const Triangle& t : model.triangles)
    for (int k = 0; k < 3; ++k)
      shortest = std::min(shortest, (model.initial_positions[std::size_t(t[k])] - model.initial_positions[std::size_t(t[(k + 1) % 3])]).norm());
  return shortest;
}

}  // namespace

std::string thickness_note(const Model& model) {
  if (!model.scene.collisions.self) return {};
  const Scalar shortest = shortest_rest_edge(model);
  const Scalar thickness = model.scene.collisions.thickness;
  if (!(REST_FRACTION * shortest < thickness)) return {};
  char text[512];
  std::snprintf(text, sizeof text,
                "the thickness (%.3g m) is large against the cloth's shortest edge (%.3g m): features of one cloth "
                "closer than %.3g m in the rest shape keep %.0f %% of their rest distance apart instead of the "
                "thickness (counted per frame as rest_clamped_pairs in stats.csv; docs/collisions.md)",
                thickness, shortest, thickness / REST_FRACTION, 100 * REST_FRACTION);
  return text;
}

bool CollisionPipeline::needed(const Model& model) {
  if (model.scene.collisions.self) return true;
  if (!model.scene.collisions.obstacles) return false;
  for (const Obstacle& o : model.obstacles)
    if (o.spec.kind == ObstacleSpec::Kind::Mesh) return true;
  return false;
}

// The pipeline of a model: the cloth's triangles, each mesh obstacle's (offset into one vertex
// array after the cloth's), the patch tree when self-collision culls, and each mesh's owners.
CollisionPipeline::Impl::Impl(const Model& m, const CollisionSettings& s) : model(m), settings(s) {
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
  may_move.assign(std::size_t(cloth_vertices), 0);
  for (int v = 0; v < cloth_vertices; ++v) {
    const int pin = m.pin_of_vertex[v];
    may_move[std::size_t(v)] = pin < 0 || m.scene.handles[std::size_t(m.pins[std::size_t(pin)].handle)].motion.moves();
  }
  start.resize(offset);
  end.resize(offset);
  if (m.scene.collisions.self && m.scene.collisions.self_culling) patch_tree = ccd::PatchTree(cloth_triangles, m.initial_positions);
  rest_gaps = m.scene.collisions.self && REST_FRACTION * shortest_rest_edge(m) < m.scene.collisions.thickness;
  cloth_owners = ccd::feature_owners(cloth_triangles);
  options.method = m.scene.collisions.method;
  options.thickness = 0;  // exact contact; the thickness is kept by proximity repulsion
}

ccd::Candidates CollisionPipeline::Impl::candidates(Scalar reach, CollisionCounters& counters, bool self,
                                                    std::span<const std::uint8_t> moved, bool with_obstacles) {
  const auto begin = Clock::now();
  // Two points closer than reach differ by less than reach along every axis (and by less than
  // reach times an axis' length along a diagonal), so boxes and feature volumes grown by half
  // of it on each side hold every such pair. Grown by the whole reach, they held pairs up to
  // twice it apart, which no caller wants: on a mesh finer than the thickness that was four
  // times the tests of a sheet at rest. The millionth keeps a pair at reach less a rounding.
  const Scalar margin = 0.5 * reach * (1 + 1e-6);
  ccd::Candidates all;
  const bool self_pairs = self && model.scene.collisions.self;
  const bool culling = self_pairs && model.scene.collisions.self_culling;
  // The tests must involve a vertex of mask: a later round's moved vertices, or a first
  // round's that may move (a clamped region of cloth resting on a still obstacle made most of
  // the Cusick drape's triangle pairs, all of them pointless).
  const std::span<const std::uint8_t> movable = movable_vertices();
  const std::span<const std::uint8_t> mask = moved.empty() ? movable : moved;
  // The cloth's btDbvt serves the mesh obstacles, and self-collision without culling. Serving
  // only still obstacles, it holds only the cloth triangles with a vertex that may move (free,
  // or a moving handle's) or moves: every test of the others would be dropped (a test's cloth
  // features belong to their triangle of the pair). Not narrowed to a round's movable or moved
  // vertices: a change of its triangles rebuilds the tree, which cost more than the pairs.
  // The mesh obstacles whose swept box meets the cloth's (both grown by the margin): no other
  // can give a pair, and with none the cloth's tree is neither updated nor traversed (a cloth
  // falling towards a table spent most of its broad phase there).
  const auto swept_range = [&](int first, int count) {
    ccd::Aabb box{start[std::size_t(first)], start[std::size_t(first)]};
    for (int v = first; v < first + count; ++v) {
      box.min = box.min.cwiseMin(start[std::size_t(v)]).cwiseMin(end[std::size_t(v)]);
      box.max = box.max.cwiseMax(start[std::size_t(v)]).cwiseMax(end[std::size_t(v)]);
    }
    box.min.array() -= margin;
    box.max.array() += margin;
    return box;
  };
  std::vector<std::uint8_t> near_cloth(obstacles.size(), 0);
  std::vector<ccd::Aabb> obstacle_range(obstacles.size());
  if (with_obstacles && !obstacles.empty() && cloth_vertices > 0) {
    const ccd::Aabb cloth_box = swept_range(0, cloth_vertices);
    for (std::size_t k = 0; k < obstacles.size(); ++k) {
      const int count = int(obstacles[k].obstacle->mesh.vertices.size());
      if (count > 0) obstacle_range[k] = swept_range(obstacles[k].first_vertex, count);
      near_cloth[k] = count > 0 && ccd::overlap(cloth_box, obstacle_range[k]);
    }
  }
  const bool any_near = std::any_of(near_cloth.begin(), near_cloth.end(), [](std::uint8_t n) { return n != 0; });
  const bool cloth_tree_needed = any_near || (self_pairs && !culling);
  if (cloth_tree_needed) {
    bool restrict = !movable.empty() && !(self_pairs && !culling);
    for (std::size_t v = std::size_t(cloth_vertices); v < movable.size() && restrict; ++v) restrict = !movable[v];
    tree_triangles.clear();
    for (std::size_t i = 0; i < cloth_triangles.size(); ++i) {
      const ccd::TriangleIndices& t = cloth_triangles[i];
      bool keep = !restrict;
      for (int k = 0; k < 3 && !keep; ++k) keep = may_move[std::size_t(t[k])] || movable[std::size_t(t[k])];
      if (keep) tree_triangles.push_back(std::int32_t(i));
    }
    boxes.resize(tree_triangles.size());
    for (std::size_t k = 0; k < tree_triangles.size(); ++k)
      boxes[k] = ccd::swept_box(cloth_triangles[std::size_t(tree_triangles[k])], start, end, margin);
  }
  // An obstacle whose swept box meets few of the cloth's boxes (a needle, a paddle under a
  // large cloth) takes those boxes down its own tree, one at a time: the cloth's tree is then
  // neither refitted nor traversed for it (the same pairs). Only its boxes can meet the
  // obstacle's triangles' boxes, which its swept box holds.
  std::vector<std::vector<std::int32_t>> near_boxes(obstacles.size());
  std::vector<std::uint8_t> by_boxes(obstacles.size(), 0);
  bool cloth_tree_used = self_pairs && !culling;
  for (std::size_t k = 0; k < obstacles.size(); ++k) {
    if (!near_cloth[k] || boxes.empty()) continue;
    // Counted until past the share: beyond it the list is not used (a cloth lying on a table).
    auto& near = near_boxes[k];
    for (std::size_t i = 0; i < boxes.size() && near.size() * FEW_BOXES_SHARE <= boxes.size(); ++i)
      if (ccd::overlap(boxes[i], obstacle_range[k])) near.push_back(std::int32_t(i));
    by_boxes[k] = near.size() * FEW_BOXES_SHARE <= boxes.size();
    if (!by_boxes[k]) near.clear(), cloth_tree_used = true;
  }
  if (cloth_tree_used && !boxes.empty()) cloth_tree.update(boxes);
  bool features_ready = false;
  const auto make_features = [&] {
    if (features_ready) return;
    if (model.scene.collisions.feature_boxes) features = ccd::vertex_volumes(start, end, margin);
    else features.clear();
    features_ready = true;
  };
  // A test of one cloth's features that lie close in its rest shape keeps only a share of the
  // thickness (kept_gap): its volumes need overlap only within that share of the margin.
  const ccd::RestGaps rest_shape{std::span<const Vec3>(model.initial_positions).first(std::size_t(cloth_vertices)), cloth_of_vertex,
                                 REST_FRACTION, model.scene.collisions.thickness, margin};
  const ccd::RestGaps* rest = rest_gaps ? &rest_shape : nullptr;
  const auto append = [&](std::span<const ccd::TriangleIndices> other, const ccd::FeatureOwners& other_owners,
                          const std::vector<std::pair<std::int32_t, std::int32_t>>& pairs, const ccd::RestGaps* gaps) {
    counters.bvh_pairs += long(pairs.size());
    if (pairs.empty()) return;
    make_features();
    // Each test once by its features' triangles; without feature volumes (the paper's count,
    // every test of every overlapping pair), every pair's tests, sorted and made unique.
    ccd::Candidates c =
        features.empty() ? ccd::feature_pairs(cloth_triangles, other, pairs, features, settings.threads, mask, gaps)
                         : ccd::feature_pairs(cloth_triangles, other, pairs, cloth_owners, other_owners, features,
                                              settings.threads, mask, gaps);
    all.vertex_face.insert(all.vertex_face.end(), c.vertex_face.begin(), c.vertex_face.end());
    all.edge_edge.insert(all.edge_edge.end(), c.edge_edge.begin(), c.edge_edge.end());
  };
  if (culling) {
    // With feature volumes (each test once by its owners), the pairs of triangles sharing a
    // vertex are never listed: their tests come from the tree's orphan sets.
    ccd::SelfCullCounters culled;
    ccd::Candidates orphans;
    const bool owned = model.scene.collisions.feature_boxes;
    append(cloth_triangles, cloth_owners,
           patch_tree.self_pairs(start, end, margin, settings.threads, &culled, mask, owned ? &orphans : nullptr), rest);
    counters.culled_triangles += culled.triangles_culled;
    if (!orphans.vertex_face.empty() || !orphans.edge_edge.empty()) {
      make_features();
      ccd::keep_overlapping(orphans, features, rest);
      all.vertex_face.insert(all.vertex_face.end(), orphans.vertex_face.begin(), orphans.vertex_face.end());
      all.edge_edge.insert(all.edge_edge.end(), orphans.edge_edge.begin(), orphans.edge_edge.end());
    }
  } else if (self_pairs) {
    append(cloth_triangles, cloth_owners, cloth_tree.self_pairs(), rest);
  }
  for (std::size_t k = 0; k < obstacles.size(); ++k) {
    if (!with_obstacles || tree_triangles.empty()) break;
    if (!near_cloth[k]) continue;
    MeshObstacle& mo = obstacles[k];
    std::vector<ccd::Aabb> obstacle_boxes(mo.triangles.size());
    for (std::size_t i = 0; i < mo.triangles.size(); ++i) obstacle_boxes[i] = ccd::swept_box(mo.triangles[i], start, end, margin);
    mo.tree.update(obstacle_boxes);
    auto pairs = by_boxes[k] ? mo.tree.pairs_with_boxes(boxes, near_boxes[k]) : cloth_tree.pairs_with(mo.tree);
    for (auto& [cloth, obstacle] : pairs) cloth = tree_triangles[std::size_t(cloth)];  // increasing: still sorted
    append(mo.triangles, mo.owners, pairs, nullptr);
  }
  counters.broad_ms += ms_since(begin);
  return all;
}

ccd::Result CollisionPipeline::Impl::canonical_hit(ccd::QueryKind kind, const ccd::Query& query, const ccd::Result& hit) const {
  if (options.method == ccd::Method::Vincent) return hit;
  ccd::Options vincent = options;
  vincent.method = ccd::Method::Vincent;
  const ccd::Result r = ccd::elementary_ccd(kind, query, vincent);
  return r.hit ? r : hit;
}

std::vector<std::pair<Contact, Scalar>> CollisionPipeline::Impl::detect(Scalar h, const std::vector<Vec3>& motion,
                                                                        CollisionCounters& counters, ccd::Candidates* keep,
                                                                        const std::vector<std::uint8_t>* moved,
                                                                        const std::vector<std::pair<Contact, Scalar>>* before) {
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
    const ccd::Result r = canonical_hit(ccd::QueryKind::VertexFace, ccd::gather(input, p), hit.result);
    hits.emplace_back(contact(true, {p.vertex, p.face[0], p.face[1], p.face[2]}, r), r.toc);
  }
  for (const ccd::BatchHit& hit : out.edge_edge) {
    const auto& p = c.edge_edge[hit.index];
    const ccd::Result r = canonical_hit(ccd::QueryKind::EdgeEdge, ccd::gather(input, p), hit.result);
    hits.emplace_back(contact(false, {p.edge_a[0], p.edge_a[1], p.edge_b[0], p.edge_b[1]}, r), r.toc);
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

CollisionPipeline::CollisionPipeline(const Model& model, const CollisionSettings& settings)
    : impl_(std::make_unique<Impl>(model, settings)) {}
CollisionPipeline::~CollisionPipeline() = default;

void CollisionPipeline::set_observer(Observer observer) {
  impl_->observer = std::move(observer);
}

CollisionCounters CollisionPipeline::resolve(const std::vector<Vec3>& start, Scalar t, Scalar h, std::vector<Vec3>& motion,
                                             Scalar friction) {
  Impl& m = *impl_;
  m.friction = friction;
  CollisionCounters counters;
  const auto begin = Clock::now();
  for (int v = 0; v < m.cloth_vertices; ++v) m.start[v] = start[v];
  m.pose_obstacles(t, h);
  const Scalar separation = SEPARATION_FRACTION * m.model.scene.collisions.thickness / h;

  // Proximity repulsion on the first round's candidates, then CCD impulses until no collision.
  // Detection is a function of the motion, test by test: a round after the first runs only the
  // tests with a vertex whose motion changed since the round before (none: its hits stand), and
  // so does the first round of a resolve of the step's start again, against the motion the last
  // one ended with free of collisions (Impl::LastResolve).
  std::vector<std::uint8_t> moved(m.start.size(), 0);
  Impl::LastResolve& last = m.last;
  const bool again = m.settings.incremental_rounds && last.clean && last.t == t && last.h == h &&
                     std::equal(start.begin(), start.begin() + m.cloth_vertices, last.start.begin(), last.start.end());
  last.clean = false;
  std::vector<std::pair<Contact, Scalar>> hits;
  if (again) {
    for (int v = 0; v < m.cloth_vertices; ++v) moved[std::size_t(v)] = motion[std::size_t(v)] != last.motion[std::size_t(v)];
    const std::vector<std::pair<Contact, Scalar>> none;
    ccd::Candidates changed;
    hits = m.detect(h, motion, counters, &changed, &moved, &none);
    // The proximity contacts: the last resolve's without a changed vertex, and those among the
    // changed tests (the self-collision culling of their patches is the motion's).
    const auto unchanged = [&](const std::array<int, 4>& vertex) {
      return std::none_of(vertex.begin(), vertex.end(), [&](int v) { return v < m.cloth_vertices && moved[std::size_t(v)]; });
    };
    std::vector<std::array<int, 4>> clamped;
    std::vector<Contact> near = m.near_contacts(changed, counters, &clamped);
    for (const Contact& c : last.near)
      if (unchanged(c.vertex)) near.push_back(c);
    for (const auto& pair : last.clamped)
      if (unchanged(pair)) clamped.push_back(pair), ++counters.rest_clamped_pairs;
    std::sort(near.begin(), near.end(), [&](const Contact& a, const Contact& b) { return m.listed_before(a, b); });
    last.near = std::move(near);
    last.clamped = std::move(clamped);
  } else {
    ccd::Candidates first;
    hits = m.detect(h, motion, counters, &first);
    last.clamped.clear();
    last.near = m.near_contacts(first, counters, &last.clamped);
    last.t = t, last.h = h;
    last.start.assign(start.begin(), start.begin() + m.cloth_vertices);
  }
  Impl::ContactSet contacts;
  std::vector<Vec3> detected = motion;
  const auto redetect = [&] {
    bool any = false;
    for (int v = 0; v < m.cloth_vertices; ++v) any |= (moved[std::size_t(v)] = motion[std::size_t(v)] != detected[std::size_t(v)]);
    if (!any) return;
    hits = m.settings.incremental_rounds ? m.detect(h, motion, counters, nullptr, &moved, &hits) : m.detect(h, motion, counters);
    detected = motion;
  };
  m.repel(last.near, h, motion, contacts, counters);
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
  last.clean = hits.empty();
  if (last.clean) last.motion.assign(motion.begin(), motion.begin() + m.cloth_vertices);
  counters.response_ms = ms_since(begin) - counters.ccd_ms;
  return counters;
}

}  // namespace drape
