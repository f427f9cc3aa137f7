#include "drape/ccd/batch.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <cassert>

namespace drape::ccd {

namespace {
// Tests per TBB task: a few microseconds of work, enough to amortise the scheduling.
constexpr std::size_t GRAIN = 256;
}  // namespace

void BatchCounters::add(const Result& result) {
  ++tests;
  culled += result.path == Path::Culled;
  degenerate += result.path == Path::Degenerate;
  root_solves += result.root_solves;
  hits += result.hit;
}

BatchCounters& BatchCounters::operator+=(const BatchCounters& other) {
  tests += other.tests;
  culled += other.culled;
  root_solves += other.root_solves;
  hits += other.hits;
  degenerate += other.degenerate;
  return *this;
}

VertexFaceQuery gather(const BatchInput& input, const VertexFacePair& pair) {
  VertexFaceQuery q;
  const std::array<std::int32_t, 4> index{pair.vertex, pair.face[0], pair.face[1], pair.face[2]};
  for (int i = 0; i < 4; ++i) {
    q.start[i] = input.start[index[i]];
    q.end[i] = input.end[index[i]];
  }
  return q;
}

EdgeEdgeQuery gather(const BatchInput& input, const EdgeEdgePair& pair) {
  EdgeEdgeQuery q;
  const std::array<std::int32_t, 4> index{pair.edge_a[0], pair.edge_a[1], pair.edge_b[0], pair.edge_b[1]};
  for (int i = 0; i < 4; ++i) {
    q.start[i] = input.start[index[i]];
    q.end[i] = input.end[index[i]];
  }
  return q;
}

BatchOutput run_batch(const BatchInput& input, const Options& options, int threads) {
  assert(input.start.size() == input.end.size());
  BatchOutput out;
  out.vertex_face.resize(input.vertex_face.size());
  out.edge_edge.resize(input.edge_edge.size());
  const auto vertex_face = [&](std::size_t i) { out.vertex_face[i] = vertex_face_ccd(gather(input, input.vertex_face[i]), options); };
  const auto edge_edge = [&](std::size_t i) { out.edge_edge[i] = edge_edge_ccd(gather(input, input.edge_edge[i]), options); };
  if (threads <= 1) {
    for (std::size_t i = 0; i < out.vertex_face.size(); ++i) vertex_face(i);
    for (std::size_t i = 0; i < out.edge_edge.size(); ++i) edge_edge(i);
  } else {
    tbb::task_arena arena(threads);
    arena.execute([&] {
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, out.vertex_face.size(), GRAIN),
                        [&](const auto& r) { for (std::size_t i = r.begin(); i < r.end(); ++i) vertex_face(i); });
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, out.edge_edge.size(), GRAIN),
                        [&](const auto& r) { for (std::size_t i = r.begin(); i < r.end(); ++i) edge_edge(i); });
    });
  }
  for (const Result& r : out.vertex_face) out.counters.add(r);
  for (const Result& r : out.edge_edge) out.counters.add(r);
  return out;
}

}  // namespace drape::ccd
