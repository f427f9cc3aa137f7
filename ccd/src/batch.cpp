#include "drape/ccd/batch.h"

#include <cassert>

namespace drape::ccd {

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

BatchOutput run_batch(const BatchInput& input, const Options& options) {
  assert(input.start.size() == input.end.size());
  BatchOutput out;
  out.vertex_face.reserve(input.vertex_face.size());
  out.edge_edge.reserve(input.edge_edge.size());
  for (const VertexFacePair& pair : input.vertex_face) {
    out.vertex_face.push_back(vertex_face_ccd(gather(input, pair), options));
    out.counters.add(out.vertex_face.back());
  }
  for (const EdgeEdgePair& pair : input.edge_edge) {
    out.edge_edge.push_back(edge_edge_ccd(gather(input, pair), options));
    out.counters.add(out.edge_edge.back());
  }
  return out;
}

}  // namespace drape::ccd
