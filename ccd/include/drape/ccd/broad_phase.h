#pragma once
/// \file
/// The broad phase: a dynamic bounding volume hierarchy over axis-aligned boxes (Bullet's
/// btDbvt, double precision), updated in place from step to step, and the candidate
/// elementary tests generated from overlapping triangle pairs.

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

/// The boxes of single vertices moving from start to end, grown by margin: feature_pairs
/// culls a feature pair whose features' boxes (unions of their vertices' boxes) are apart.
std::vector<Aabb> vertex_boxes(std::span<const Vec3> start, std::span<const Vec3> end, Scalar margin);

inline bool overlap(const Aabb& a, const Aabb& b) {
  return (a.min.array() <= b.max.array()).all() && (b.min.array() <= a.max.array()).all();
}

/// A btDbvt over boxes, one leaf per box, kept behind this type.
class BoxTree {
 public:
  BoxTree();
  ~BoxTree();
  BoxTree(BoxTree&&) noexcept;
  BoxTree& operator=(BoxTree&&) noexcept;

  /// Sets the boxes. The first call (or a change of count) builds the tree; later calls move
  /// each leaf to its new box and let Bullet refit and rebalance incrementally.
  void update(std::span<const Aabb> boxes);
  std::size_t size() const;
  /// Overlapping leaves (i < j) of this tree against itself, sorted.
  std::vector<std::pair<std::int32_t, std::int32_t>> self_pairs() const;
  /// Overlapping leaves (i in this tree, j in other), sorted.
  std::vector<std::pair<std::int32_t, std::int32_t>> pairs_with(const BoxTree& other) const;

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
/// With vertex boxes (vertex_boxes(), indexed like the triangles), a pair is also dropped when
/// the boxes of its two features do not overlap: with boxes grown by the same margin as the
/// triangles', such features stay more than twice the margin apart along some axis during the
/// whole step, so no elementary test could report them. Most pairs of neighbouring triangles
/// of one sheet go this way; they are nearly coplanar, which no coplanarity filter can cull.
struct Candidates {
  std::vector<VertexFacePair> vertex_face;
  std::vector<EdgeEdgePair> edge_edge;
};

using TriangleIndices = std::array<std::int32_t, 3>;

/// pairs index triangles_a (first) and triangles_b (second); for self-collision pass the same
/// span twice.
Candidates feature_pairs(std::span<const TriangleIndices> triangles_a, std::span<const TriangleIndices> triangles_b,
                         std::span<const std::pair<std::int32_t, std::int32_t>> pairs,
                         std::span<const Aabb> vertex_boxes = {});

}  // namespace drape::ccd
