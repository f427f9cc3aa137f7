#pragma once
/// \file
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
  std::uint64_t culled = 0;       ///< decided by the filter alone (Path::Culled)
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

struct BatchOutput {
  std::vector<Result> vertex_face;  ///< one per input pair, same order
  std::vector<Result> edge_edge;
  BatchCounters counters;
};

/// Runs every test of the batch with options.method, on up to threads threads (TBB). Each
/// result lands at its pair's index and the counters are summed per range of tests (integer
/// sums), so the output does not depend on the thread count. Indices must lie in [0, start.size()).
BatchOutput run_batch(const BatchInput& input, const Options& options, int threads = 1);

/// The query of one pair, gathered from the vertex arrays.
VertexFaceQuery gather(const BatchInput& input, const VertexFacePair& pair);
EdgeEdgeQuery gather(const BatchInput& input, const EdgeEdgePair& pair);

}  // namespace drape::ccd
