#pragma once
/// \file
/// The broad phase: a btDbvt over swept triangle boxes and the feature pairs it gives.
///
/// The broad phase: a dynamic bounding volume hierarchy over axis-aligned boxes (Bullet's
/// btDbvt, double precision), updated in place from step to step, and the candidate
/// elementary tests generated from overlapping triangle pairs.

#include <algorithm>
#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <utility>
#include <vector>

#include "drape/ccd/batch.h"

namespace drape::ccd {

struct Aabb {
  Vec3 min = Vec3::Zero();
  Vec3 max = Vec3::Zero();
};

/// The box around a triangle's corners at the start and the end of a step, grown by margin.
Aabb swept_box(const std::array<std::int32_t, 3>& triangle, std::span<const Vec3> start, std::span<const Vec3> end,
               Scalar margin);

inline bool overlap(const Aabb& a, const Aabb& b) {
  return (a.min.array() <= b.max.array()).all() && (b.min.array() <= a.max.array()).all();
}

/// The swept volume of a vertex or a feature for feature_pairs' culling: the intervals its
/// positions at the start and the end of the step cover along 9 axes, x, y, z and the six face
/// diagonals x+y, x-y, x+z, x-z, y+z, y-z (an 18-DOP, tighter than a box around slanted
/// features), each grown by the margin times the axis' length. Two volumes apart along an axis
/// mean their points stay more than twice the margin apart during the whole step.
struct FeatureVolume {
  static constexpr int AXES = 9;
  std::array<Scalar, AXES> min, max;
  void merge(const FeatureVolume& other) {
    for (int k = 0; k < AXES; ++k) min[k] = std::min(min[k], other.min[k]), max[k] = std::max(max[k], other.max[k]);
  }
};

inline bool overlap(const FeatureVolume& a, const FeatureVolume& b) {
  bool apart = false;
  for (int k = 0; k < FeatureVolume::AXES; ++k) apart |= (a.min[k] > b.max[k]) | (b.min[k] > a.max[k]);
  return !apart;
}

/// The volumes of single vertices moving from start to end, grown by margin.
std::vector<FeatureVolume> vertex_volumes(std::span<const Vec3> start, std::span<const Vec3> end, Scalar margin);

/// Features of one sheet that lie close in its rest shape may keep a smaller gap than the
/// thickness (drape keeps fraction times their rest distance, at most the thickness): such a
/// test needs its features' volumes to overlap only within that share of their margin. For a
/// test whose four vertices all belong to one group (a cloth; vertices past group's end or
/// of group -1 belong to none), the margin is scaled by min(1, fraction d / thickness), d the
/// least rest distance between a vertex of one feature and one of the other (at least the
/// features' rest distance, so the scaled margin still holds every pair closer than its gap).
struct RestGaps {
  std::span<const Vec3> rest;            ///< per vertex of a group: its rest position
  std::span<const std::int32_t> group;  ///< per vertex: its group, -1 for none
  Scalar fraction = 0;                   ///< the share of the rest distance kept as the gap
  Scalar thickness = 0;                  ///< the gap's cap
  Scalar margin = 0;                     ///< the vertex volumes' margin (vertex_volumes())
};

/// Whether a and b (grown by margin) still overlap with each shrunk by shrink along every axis
/// (times the axis' length): shrink 0 is overlap().
bool overlap_within(const FeatureVolume& a, const FeatureVolume& b, Scalar shrink);

/// A btDbvt over boxes, one leaf per box, kept behind this type.
class BoxTree {
 public:
  BoxTree();
  ~BoxTree();
  BoxTree(BoxTree&&) noexcept;
  BoxTree& operator=(BoxTree&&) noexcept;

  /// Sets the boxes. The first call (or a change of count) builds the tree; later calls give
  /// each leaf its new box, refit the inner nodes (the tree's shape kept) and let Bullet
  /// rebalance one leaf.
  void update(std::span<const Aabb> boxes);
  std::size_t size() const;
  /// Overlapping leaves (i < j) of this tree against itself, sorted.
  std::vector<std::pair<std::int32_t, std::int32_t>> self_pairs() const;
  /// Overlapping leaves (i in this tree, j in other), sorted.
  std::vector<std::pair<std::int32_t, std::int32_t>> pairs_with(const BoxTree& other) const;
  /// The pairs (i, j) of boxes[i], i in which (each once), and this tree's leaf j that overlap, sorted:
  /// pairs_with's answer for a tree of those boxes, without building or refitting one (a few
  /// boxes near a small obstacle).
  std::vector<std::pair<std::int32_t, std::int32_t>> pairs_with_boxes(std::span<const Aabb> boxes,
                                                                      std::span<const std::int32_t> which) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The elementary tests of overlapping triangle pairs: each triangle pair gives 6 vertex-face
/// and 9 edge-edge tests; features sharing a vertex are skipped, and each vertex-face and
/// edge-edge pair appears once however many triangle pairs hold it. Indices refer to one
/// vertex array (offset the second mesh's indices when the two meshes differ). Sorted, so the
/// order does not depend on how the pairs were found.
///
/// With vertex volumes (vertex_volumes(), indexed like the triangles), a pair is also dropped
/// when the volumes of its two features (the merged volumes of their vertices) do not overlap:
/// grown by the same margin as the triangles' boxes, such features stay more than twice the
/// margin apart during the whole step, so no elementary test could report them. Most pairs of
/// neighbouring triangles of one sheet go this way; they are nearly coplanar, which no
/// coplanarity filter can cull.
struct Candidates {
  std::vector<VertexFacePair> vertex_face;
  std::vector<EdgeEdgePair> edge_edge;
};

using TriangleIndices = std::array<std::int32_t, 3>;

/// Which triangle answers for each corner and edge of a mesh: the first triangle holding it
/// (representative triangles, Curtis, Tamstorf and Manocha 2008). Per triangle, bit k is set
/// when it answers for corner k, bit 3 + i when it answers for edge i (corner i to i + 1), and
/// bit 6 when it answers for its face (no earlier triangle has the same corners).
struct FeatureOwners {
  std::vector<std::uint8_t> bits;
};
FeatureOwners feature_owners(std::span<const TriangleIndices> triangles);

/// pairs index triangles_a (first) and triangles_b (second); for self-collision pass the same
/// span twice. threads: the pairs are split into chunks done in parallel (TBB); the result is
/// sorted and the same for any thread count. With moved (a flag per vertex), only the features
/// with a moved vertex are kept. With rest gaps, the volumes of tests within one group overlap
/// within their rest gap's share of the margin (RestGaps).
Candidates feature_pairs(std::span<const TriangleIndices> triangles_a, std::span<const TriangleIndices> triangles_b,
                         std::span<const std::pair<std::int32_t, std::int32_t>> pairs,
                         std::span<const FeatureVolume> vertex_volumes = {}, int threads = 1,
                         std::span<const std::uint8_t> moved = {}, const RestGaps* rest = nullptr);

/// The same tests, each made once by the pair of the triangles answering for its two features
/// (owners_a of triangles_a, owners_b of triangles_b), in the order of pairs and not sorted: no
/// sort and no removal of repeats. pairs must hold every pair of triangles whose boxes (grown
/// by the volumes' margin) overlap, adjacent ones too, but for pairs inside a region whose
/// features cannot touch (ccd::PatchTree's culled patches). With vertex volumes, the same tests
/// as the overload above, except those inside such regions that reached it through a pair
/// outside them; without, fewer (a test only from its own features' triangles, not from every
/// overlapping pair holding them): the paper's count needs the overload above.
Candidates feature_pairs(std::span<const TriangleIndices> triangles_a, std::span<const TriangleIndices> triangles_b,
                         std::span<const std::pair<std::int32_t, std::int32_t>> pairs, const FeatureOwners& owners_a,
                         const FeatureOwners& owners_b, std::span<const FeatureVolume> vertex_volumes = {}, int threads = 1,
                         std::span<const std::uint8_t> moved = {}, const RestGaps* rest = nullptr);

/// Keeps the tests whose features' volumes overlap, as feature_pairs culls them: a vertex's
/// volume against its face's (its corners' merged), an edge's against the other's.
void keep_overlapping(Candidates& tests, std::span<const FeatureVolume> vertex_volumes, const RestGaps* rest = nullptr);

}  // namespace drape::ccd
