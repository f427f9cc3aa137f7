#include "drape/ccd/batch.h"

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

#include "drape/ccd/coplanarity.h"

namespace drape::ccd {

namespace {
// Tests per TBB task: a few microseconds of work, enough to amortise the scheduling.
constexpr std::size_t GRAIN = 256;
}  // namespace

void BatchCounters::add(const Result& result) {
  ++tests;
  culled += result.path == Path::Culled || result.path == Path::Separated;
  separated += result.path == Path::Separated;
  degenerate += result.path == Path::Degenerate;
  root_solves += result.root_solves;
  hits += result.hit;
}

BatchCounters& BatchCounters::operator+=(const BatchCounters& other) {
  tests += other.tests;
  culled += other.culled;
  separated += other.separated;
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

namespace {

// Tests whose cubics are computed together: the coordinates of a chunk are gathered into one
// array per coordinate so that the arithmetic runs on several tests at once (SIMD).
constexpr std::size_t CHUNK = 64;

struct ChunkCubics {
  // The differences x2 - x1, x3 - x1, x4 - x1 (A, B, C) at t = 0 and t = 1, per coordinate.
  alignas(64) Scalar a0[3][CHUNK], a1[3][CHUNK], b0[3][CHUNK], b1[3][CHUNK], c0[3][CHUNK], c1[3][CHUNK];
  alignas(64) Scalar coefficient[4][CHUNK], error[CHUNK], extent[CHUNK];
  alignas(64) std::int64_t culled[CHUNK];  // filter_culls of each cubic (64 bits: the SIMD lanes of the doubles)
  // The conservative method's first question at zero thickness: resolved, and every
  // coefficient beyond its error with one sign (certainly_nonzero on the whole step).
  alignas(64) std::int64_t certainly_apart[CHUNK];
};

std::array<std::int32_t, 4> points(const VertexFacePair& p) { return {p.vertex, p.face[0], p.face[1], p.face[2]}; }
std::array<std::int32_t, 4> points(const EdgeEdgePair& p) { return {p.edge_a[0], p.edge_a[1], p.edge_b[0], p.edge_b[1]}; }

// coplanarity_cubic_in<Scalar> for n tests at once, operation for operation (the results are the
// same bits; the batch test compares them with the one-query entry points).
__attribute__((target_clones("avx2", "default"))) void compute_cubics(ChunkCubics& c, std::size_t n) {
  constexpr Scalar unit_roundoff = std::numeric_limits<Scalar>::epsilon() / 2;
  for (std::size_t i = 0; i < n; ++i) {
    const auto cross = [&](const Scalar (*u)[CHUNK], const Scalar (*v)[CHUNK], Scalar out[3]) {
      out[0] = u[1][i] * v[2][i] - u[2][i] * v[1][i];
      out[1] = u[2][i] * v[0][i] - u[0][i] * v[2][i];
      out[2] = u[0][i] * v[1][i] - u[1][i] * v[0][i];
    };
    const auto dot = [&](const Scalar (*u)[CHUNK], const Scalar w[3]) { return u[0][i] * w[0] + u[1][i] * w[1] + u[2][i] * w[2]; };
    Scalar b0c0[3], b1c0[3], b0c1[3], b1c1[3];
    cross(c.b0, c.c0, b0c0);
    cross(c.b1, c.c0, b1c0);
    cross(c.b0, c.c1, b0c1);
    cross(c.b1, c.c1, b1c1);
    c.coefficient[0][i] = dot(c.a0, b0c0);
    c.coefficient[1][i] = (dot(c.a1, b0c0) + dot(c.a0, b1c0) + dot(c.a0, b0c1)) / Scalar(3);
    c.coefficient[2][i] = (dot(c.a1, b1c0) + dot(c.a1, b0c1) + dot(c.a0, b1c1)) / Scalar(3);
    c.coefficient[3][i] = dot(c.a1, b1c1);
    const auto l1 = [&](const Scalar (*s)[CHUNK], const Scalar (*e)[CHUNK]) {
      return std::max(std::abs(s[0][i]) + std::abs(s[1][i]) + std::abs(s[2][i]),
                      std::abs(e[0][i]) + std::abs(e[1][i]) + std::abs(e[2][i]));
    };
    const Scalar a = l1(c.a0, c.a1), b = l1(c.b0, c.b1), cc = l1(c.c0, c.c1);
    c.error[i] = Scalar(COPLANARITY_ERROR_FACTOR) * unit_roundoff * a * b * cc;
    c.extent[i] = std::max(std::max(a, b), cc);
    // filter_culls, written out on the arrays.
    const Scalar k0 = c.coefficient[0][i], k1 = c.coefficient[1][i], k2 = c.coefficient[2][i], k3 = c.coefficient[3][i];
    const Scalar largest = std::max(std::max(std::abs(k0), std::abs(k1)), std::max(std::abs(k2), std::abs(k3)));
    const Scalar lo = std::min(std::min(k0, k1), std::min(k2, k3)), hi = std::max(std::max(k0, k1), std::max(k2, k3));
    const bool resolved = !(largest <= POORLY_RESOLVED_RATIO * c.error[i]);
    const bool one_sign = (lo > 0) | (hi < 0);
    const bool ends_clear = std::min(std::abs(k0), std::abs(k3)) > c.error[i];
    c.culled[i] = std::int64_t(resolved & one_sign & ends_clear);
    const Scalar e = c.error[i];
    const bool all_above = (k0 > e) & (k1 > e) & (k2 > e) & (k3 > e), all_below = (k0 < -e) & (k1 < -e) & (k2 < -e) & (k3 < -e);
    c.certainly_apart[i] = std::int64_t(resolved & (all_above | all_below));
  }
}

// The tests [begin, end) of one kind: cubics a chunk at a time; dnf and vincent decide the
// culled ones from the cubic alone, everything else runs the full method on the gathered query.
// Appends the hits to hits and returns the counters of the range.
template <QueryKind kind, class Pair>
BatchCounters run_range(const BatchInput& input, std::span<const Pair> pairs, const Options& options, std::size_t begin,
                        std::size_t end, std::vector<BatchHit>& hits) {
  BatchCounters counters;
  constexpr std::array<int, 4> order = kind == QueryKind::VertexFace ? std::array<int, 4>{1, 2, 3, 0}
                                                                     : std::array<int, 4>{0, 1, 2, 3};
  static_assert(kind != QueryKind::VertexFace || order[3] == 0, "coplanarity_order");
  const bool filter = options.method == Method::Dnf || options.method == Method::Vincent;
  // The conservative method ends a test at its first question when, at zero thickness, the
  // cubic is certainly nonzero on the whole step: the result it returns then is written here.
  const bool conservative_first = options.method == Method::Conservative && options.thickness == 0;
  ChunkCubics c;
  for (std::size_t first = begin; first < end; first += CHUNK) {
    const std::size_t n = std::min(CHUNK, end - first);
    for (std::size_t i = 0; i < n; ++i) {
      const auto index = points(pairs[first + i]);
      const Vec3 &s1 = input.start[index[order[0]]], &e1 = input.end[index[order[0]]];
      const Vec3 &s2 = input.start[index[order[1]]], &e2 = input.end[index[order[1]]];
      const Vec3 &s3 = input.start[index[order[2]]], &e3 = input.end[index[order[2]]];
      const Vec3 &s4 = input.start[index[order[3]]], &e4 = input.end[index[order[3]]];
      for (int k = 0; k < 3; ++k) {
        c.a0[k][i] = s2[k] - s1[k];
        c.a1[k][i] = e2[k] - e1[k];
        c.b0[k][i] = s3[k] - s1[k];
        c.b1[k][i] = e3[k] - e1[k];
        c.c0[k][i] = s4[k] - s1[k];
        c.c1[k][i] = e4[k] - e1[k];
      }
    }
    compute_cubics(c, n);
    for (std::size_t i = 0; i < n; ++i) {
      if (filter && c.culled[i]) {
        ++counters.tests;
        ++counters.culled;
        continue;
      }
      if (conservative_first && c.certainly_apart[i]) {  // a miss, one interval examined
        ++counters.tests;
        ++counters.culled;
        ++counters.root_solves;
        continue;
      }
      CoplanarityCubic cubic;
      for (int k = 0; k < 4; ++k) cubic.b[k] = c.coefficient[k][i];
      cubic.error = c.error[i];
      cubic.extent = c.extent[i];
      assert(bool(c.culled[i]) == filter_culls(cubic));
      const Result result = elementary_ccd(kind, gather(input, pairs[first + i]), options, cubic);
      counters.add(result);
      if (result.hit) hits.push_back({first + i, result});
    }
  }
  return counters;
}

}  // namespace

BatchOutput run_batch(const BatchInput& input, const Options& options, int threads) {
  assert(input.start.size() == input.end.size());
  assert(coplanarity_order(QueryKind::VertexFace) == (std::array<int, 4>{1, 2, 3, 0}));
  assert(coplanarity_order(QueryKind::EdgeEdge) == (std::array<int, 4>{0, 1, 2, 3}));
  BatchOutput out;
  const std::size_t vf = input.vertex_face.size(), ee = input.edge_edge.size();
  if (threads <= 1) {
    out.counters += run_range<QueryKind::VertexFace>(input, input.vertex_face, options, 0, vf, out.vertex_face);
    out.counters += run_range<QueryKind::EdgeEdge>(input, input.edge_edge, options, 0, ee, out.edge_edge);
    return out;
  }
  // Counters are integer sums and the hits are sorted afterwards: the same whatever the split
  // and the order in which the ranges finish.
  struct Partial {
    BatchCounters counters;
    std::vector<BatchHit> vertex_face, edge_edge;
  };
  tbb::combinable<Partial> partial;
  tbb::task_arena arena(threads);
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, vf, GRAIN), [&](const auto& r) {
      Partial& p = partial.local();
      p.counters += run_range<QueryKind::VertexFace>(input, input.vertex_face, options, r.begin(), r.end(), p.vertex_face);
    });
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, ee, GRAIN), [&](const auto& r) {
      Partial& p = partial.local();
      p.counters += run_range<QueryKind::EdgeEdge>(input, input.edge_edge, options, r.begin(), r.end(), p.edge_edge);
    });
  });
  partial.combine_each([&](const Partial& p) {
    out.counters += p.counters;
    out.vertex_face.insert(out.vertex_face.end(), p.vertex_face.begin(), p.vertex_face.end());
    out.edge_edge.insert(out.edge_edge.end(), p.edge_edge.begin(), p.edge_edge.end());
  });
  const auto by_index = [](const BatchHit& a, const BatchHit& b) { return a.index < b.index; };
  std::sort(out.vertex_face.begin(), out.vertex_face.end(), by_index);
  std::sort(out.edge_edge.begin(), out.edge_edge.end(), by_index);
  return out;
}

}  // namespace drape::ccd
