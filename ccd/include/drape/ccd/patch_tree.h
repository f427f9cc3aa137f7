#pragma once
/// \file
/// Self-collision culling: patches of one mesh proven free of self-contact over a step.
///
/// Self-collision culling: a hierarchy of connected patches of one triangle mesh, each patch
/// proven free of self-contact over a step by a continuous normal cone and a contour test, so
/// that a flat or gently curved, untwisted region of cloth gives no candidate pairs.
///
/// The test is Volino and Magnenat-Thalmann's (1994): a connected surface whose normals all
/// lie within 90 degrees of one direction d, and whose boundary contour projected along d has
/// no self-intersection, does not intersect itself. Over a step every corner moves linearly,
/// so a triangle's normal is a quadratic in t whose three Bernstein coefficients bound it
/// (Tang, Curtis, Yoon and Manocha 2009, continuous normal cones); the contour is tested as a
/// star around the mean of its corners, each contour edge's signed area around it a quadratic
/// whose Bernstein coefficients must all be positive, and it must wind around that point once
/// (the unprojected star test of Wang, Liu, Tang, Tong and Manocha 2017). A patch that passes
/// stays embedded during the whole step, so no two of its features can touch.

#include <array>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "drape/ccd/broad_phase.h"

namespace drape::ccd {

/// What one self_pairs call did, for the statistics.
struct SelfCullCounters {
  long patches_tested = 0;  ///< patches whose cone and contour were tested
  long patches_culled = 0;  ///< of those, proven free of self-contact (their pairs never enumerated)
  long triangles_culled = 0;  ///< triangles inside the culled patches
  SelfCullCounters& operator+=(const SelfCullCounters& other) {
    patches_tested += other.patches_tested;
    patches_culled += other.patches_culled;
    triangles_culled += other.triangles_culled;
    return *this;
  }
};

class PatchTree {
 public:
  PatchTree() = default;
  /// Builds the hierarchy once from the mesh's connectivity; reference (a shape of the mesh,
  /// the rest shape) only guides where patches are split. Triangles are joined across an edge
  /// only when exactly two of them share it with opposite windings (a consistently oriented,
  /// manifold edge); a patch is tested only when it is a topological disk.
  PatchTree(std::span<const TriangleIndices> triangles, std::span<const Vec3> reference);

  /// The triangle pairs (i < j) whose swept boxes (corners at start and at end, grown by
  /// margin) overlap, leaving out every pair inside a patch proven free of self-contact for the
  /// whole step. Sorted; the same for any thread count. With moved (a flag per vertex), only the
  /// pairs with a triangle holding a moved vertex: a later detection round's, when the others'
  /// motion is the one an earlier round already tested.
  ///
  /// Without orphans, pairs of triangles sharing a vertex are listed too (their other features
  /// can still meet). With orphans, they never are: their tests, made once when the tree was
  /// built (orphan sets, Curtis, Tamstorf and Manocha 2008: feature_pairs' owned tests of every
  /// such pair, grouped by the lowest patch holding both), come in orphans instead, those of
  /// the patches the traversal reached (not culled), with a moved vertex when moved is given;
  /// not culled by feature volumes (keep_overlapping). Pairs and orphans together then give
  /// feature_pairs' owned overload exactly the tests the pairs alone gave it without orphans.
  std::vector<std::pair<std::int32_t, std::int32_t>> self_pairs(std::span<const Vec3> start, std::span<const Vec3> end,
                                                                Scalar margin, int threads = 1,
                                                                SelfCullCounters* counters = nullptr,
                                                                std::span<const std::uint8_t> moved = {},
                                                                Candidates* orphans = nullptr);

 private:
  // Triangles a leaf holds at most: its self pairs are tested box against box.
  static constexpr std::int32_t LEAF_TRIANGLES = 8;

  struct Node {
    std::int32_t right = -1;           // the right child's index (the left is the next node); -1 for a leaf
    std::int32_t first = 0, count = 0;  // the node's triangles: order_[first, first + count)
    std::int32_t contour_first = 0, contour_count = 0;  // the disk's boundary: contours_[...]; 0 when not a disk
  };
  // Per-call state: the triangles' boxes (in order_'s order) and each node's box and normal
  // cone (axis, cosine and sine of the half-angle; cone_ok false when it is not within 90
  // degrees or holds a degenerate triangle).
  struct Motion {
    std::span<const Vec3> start, end;
    std::vector<Aabb> triangle_box;
    std::vector<Aabb> box;
    std::vector<Vec3> sum;  // area-weighted normal coefficients, summed: the cone's axis
    std::vector<Vec3> axis;
    std::vector<Scalar> cos, sin;
    std::vector<char> cone_ok;
    // Restricted to pairs with a moved triangle (moved vertices given): which triangles (in
    // order_'s order) and which nodes hold one. Empty: every pair.
    std::vector<char> triangle_moved, node_moved;
    bool restricted() const { return !node_moved.empty(); }
    bool keeps(std::int32_t i, std::int32_t j) const {
      return !restricted() || triangle_moved[std::size_t(i)] || triangle_moved[std::size_t(j)];
    }
    bool holds_moved(std::int32_t node) const { return !restricted() || node_moved[std::size_t(node)]; }
    // With orphans: pairs sharing a vertex are left out, and per node whether the traversal
    // reached it not culled (its pairs and its children's across pairs listed), set by own and
    // the parallel split (each node by one task).
    bool skip_adjacent = false;
    mutable std::vector<char> reached;
  };
  struct BuildScratch {
    std::vector<std::array<std::int32_t, 3>> neighbours;  // across each triangle's edges; -1: none
    std::vector<std::int32_t> stamp, position;          // the node a triangle was last in, and where
    std::vector<std::int32_t> vertex_seen;              // per vertex: the last node that counted it
    std::vector<std::int32_t> boundary_stamp, boundary_next;  // per vertex: the last node whose boundary leaves it, and to where
  };

  std::int32_t build(std::vector<std::int32_t>& set, BuildScratch& scratch, std::span<const Vec3> reference);
  bool culled(const Motion& motion, std::int32_t node, SelfCullCounters& counters) const;
  void self(const Motion& motion, std::int32_t node, std::vector<std::pair<std::int32_t, std::int32_t>>& out,
            SelfCullCounters& counters) const;
  // A node's pairs once it is known not to be culled.
  void own(const Motion& motion, std::int32_t node, std::vector<std::pair<std::int32_t, std::int32_t>>& out,
           SelfCullCounters& counters) const;
  void across(const Motion& motion, std::int32_t a, std::int32_t b,
              std::vector<std::pair<std::int32_t, std::int32_t>>& out) const;

  // The orphan sets, built once: the pairs of triangles sharing a vertex by their lowest
  // common node, and each node's tests of them (CSR: orphan_vf_start_[node] to [node + 1]).
  void build_orphans();
  // Whether a leaf pair (order_ positions i and j) is listed: kept by the moved restriction,
  // boxes overlapping, and, with orphans, not sharing a corner.
  bool lists(const Motion& motion, std::int32_t i, std::int32_t j) const;
  std::vector<VertexFacePair> orphan_vf_;
  std::vector<EdgeEdgePair> orphan_ee_;
  std::vector<std::int32_t> orphan_vf_start_, orphan_ee_start_;

  std::vector<TriangleIndices> triangles_;
  std::vector<std::int32_t> order_;     // triangle indices, each leaf's contiguous
  std::vector<std::int32_t> contours_;  // the disks' boundary vertices, counter-clockwise about their normals
  std::vector<Node> nodes_;             // depth first: a node's left child follows it
  std::vector<std::int32_t> leaves_;    // the leaf nodes
  // The triangles in order_'s order (triangles_[order_[k]]), and for the cones' kernel each
  // leaf's first and count in it.
  std::vector<TriangleIndices> ordered_;
  std::vector<std::int32_t> leaf_first_, leaf_count_;
  Motion motion_;
};

}  // namespace drape::ccd
