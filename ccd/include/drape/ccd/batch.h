#pragma once
/// \file
/// Many elementary CCD tests at once over one vertex array: the entry point the cloth pipeline calls.
///
/// The batch entry point: many elementary tests over one vertex array at t = 0 and t = 1, the
/// form the cloth pipeline calls.

#include <cstdint>
#include <span>
#include <vector>

#include "drape/ccd/query.h"

namespace drape::ccd {

struct VertexFacePair {
  std::int32_t vertex = 0;
  std::array<std::int32_t, 3> face{};
};

struct EdgeEdgePair {
  std::array<std::int32_t, 2> edge_a{};
  std::array<std::int32_t, 2> edge_b{};
};

/// What a batch did; summed into the frame statistics.
struct BatchCounters {
  std::uint64_t tests = 0;        ///< elementary tests run
  std::uint64_t culled = 0;       ///< decided by the filter alone, no root finding (Path::Culled or Separated)
  std::uint64_t separated = 0;    ///< of those, by the separation stage (Path::Separated)
  std::uint64_t root_solves = 0;  ///< root-finding calls (Result::root_solves summed)
  std::uint64_t hits = 0;         ///< tests reporting a contact
  std::uint64_t degenerate = 0;   ///< tests decided on a degenerate path

  void add(const Result& result);
  BatchCounters& operator+=(const BatchCounters& other);
};

struct BatchInput {
  std::span<const Vec3> start;  ///< positions at t = 0
  std::span<const Vec3> end;    ///< positions at t = 1, same size as start
  std::span<const VertexFacePair> vertex_face;
  std::span<const EdgeEdgePair> edge_edge;
};

/// A test that reports a contact: its index in the input's pairs and its result.
struct BatchHit {
  std::size_t index = 0;
  Result result;
};

/// Only the hits are kept: a frame runs millions of tests and reports contacts for about one
/// in a hundred; a result per test would cost more memory traffic than a culled test itself.
struct BatchOutput {
  std::vector<BatchHit> vertex_face;  ///< the vertex-face hits, in increasing index
  std::vector<BatchHit> edge_edge;    ///< the edge-edge hits, in increasing index
  BatchCounters counters;
};

/// Runs every test of the batch with options.method, on up to threads threads (TBB). The hits
/// are sorted by index and the counters are summed per range of tests (integer sums), so the
/// output does not depend on the thread count. Indices must lie in [0, start.size()).
BatchOutput run_batch(const BatchInput& input, const Options& options, int threads = 1);

/// The query of one pair, gathered from the vertex arrays.
VertexFaceQuery gather(const BatchInput& input, const VertexFacePair& pair);
EdgeEdgeQuery gather(const BatchInput& input, const EdgeEdgePair& pair);

}  // namespace drape::ccd
