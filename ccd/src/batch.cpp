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
#include "kernels.h"
#include "methods.h"

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

namespace {

template <class QueryType, class Pair>
QueryType gather_points(const BatchInput& input, const Pair& pair) {
  QueryType q;
  const std::array<std::int32_t, 4> index = detail::points(pair);
  for (int i = 0; i < 4; ++i) {
    q.start[i] = input.start[index[i]];
    q.end[i] = input.end[index[i]];
  }
  return q;
}

}  // namespace

VertexFaceQuery gather(const BatchInput& input, const VertexFacePair& pair) {
  return gather_points<VertexFaceQuery>(input, pair);
}

EdgeEdgeQuery gather(const BatchInput& input, const EdgeEdgePair& pair) {
  return gather_points<EdgeEdgeQuery>(input, pair);
}

namespace {

using detail::Apart;
using detail::CHUNK;
using detail::chunk_bits;
using detail::ChunkCubics;
using detail::LEFT_MAX;
using detail::Left;

// The tests the chunks' decisions left, in order: the full method on the gathered query. For
// vincent, and conservative at zero thickness, the separation stage is asked here a SIMD vector
// of tests at a time (the whole step's boxes, then the rest of it for the tests those do not
// separate), and the tests it separates need nothing else; the others take what it decided to
// the method.
template <QueryKind kind, class Pair>
void run_left(const BatchInput& input, std::span<const Pair> pairs, const Options& options, const Left* left,
              int count, BatchCounters& counters, std::vector<BatchHit>& hits) {
  const bool stage = options.separation_depth > 0;
  const bool vincent = options.method == Method::Vincent && stage;
  const bool conservative = options.method == Method::Conservative && options.thickness == 0 && stage;
  // Bits of left: the tests that go on to the separation stage (as vincent_method and
  // conservative_search decide it), and what the stage decided of them here.
  detail::StageBits s;
  if (vincent || conservative)
    s = detail::separation_stage(input, pairs.data(), left, count, vincent, vincent ? options.thickness : 0,
                                 vincent ? options.contact_tolerance : 0, options.separation_depth);
  const std::uint64_t within = s.stage, whole_step_apart = s.whole_step_apart, decided = s.decided, apart = s.apart;
#ifndef NDEBUG
  for (int j = 0; j < count; ++j)
    assert(!(vincent || conservative) ||
           bool((within >> j) & 1) ==
               (detail::stage_runs(gather(input, pairs[left[j].index]), left[j].cubic, options.separation_depth) &&
                (vincent ? detail::vincent_entry(left[j].cubic) == detail::VincentEntry::Stage
                         : detail::conservative_entry(left[j].cubic, 0) == detail::ConservativeEntry::Stage)));
#endif
  // The tests the stage separated here, counted at once as roots_apart's answer (Separated).
  const std::uint64_t separated = within & (whole_step_apart | apart);
  const auto separated_count = static_cast<std::uint64_t>(__builtin_popcountll(separated));
  counters.tests += separated_count;
  counters.culled += separated_count;
  counters.separated += separated_count;
  // The others, in order, through the method with what the stage decided of them.
  for (std::uint64_t rest = chunk_bits(std::size_t(count)) & ~separated; rest != 0; rest &= rest - 1) {
    const int j = __builtin_ctzll(rest);
    const std::uint64_t bit = std::uint64_t(1) << j;
    const Query query = gather(input, pairs[left[j].index]);
    // The stage's answer: the kernel's (not apart), or for a test with two runs of kept
    // sub-intervals or more, the rest of the stage after the whole step's boxes.
    std::optional<bool> stage_separated;
    if (within & bit)
      stage_separated = (decided & bit) ? false
                                        : detail::roots_apart_within(kind, query, left[j].cubic, s.need[j],
                                                                     options.separation_depth);
    const Result result = detail::run_unculled(kind, query, options, left[j].cubic, stage_separated);
    counters.add(result);
    if (result.hit) hits.push_back({left[j].index, result});
  }
}

// The tests [begin, end) of one kind: cubics a chunk at a time; dnf and vincent decide the
// culled ones from the cubic alone, everything else runs the full method on the gathered query.
// Appends the hits to hits and returns the counters of the range.
template <QueryKind kind, class Pair>
BatchCounters run_range(const BatchInput& input, std::span<const Pair> pairs, const Options& options, std::size_t begin,
                        std::size_t end, std::vector<BatchHit>& hits) {
  BatchCounters counters;
  const bool filter = options.method == Method::Dnf || options.method == Method::Vincent;
  // The conservative method ends a test at its first question when the cubic is certainly
  // farther from zero over the whole step than the thickness lets it come: a miss, counted here
  // as the method counts it.
  const bool conservative_first = options.method == Method::Conservative;
  // (A thickness that is not a number takes its share, NaN, as thickness_to_cubic does.)
  const Apart apart = !conservative_first ? Apart::No
                      : options.thickness == 0 ? Apart::AtZeroThickness
                                               : Apart::WithThickness;
  ChunkCubics c;
  Left left[LEFT_MAX];
  int left_count = 0;
  for (std::size_t first = begin; first < end; first += CHUNK) {
    const std::size_t n = std::min(CHUNK, end - first);
    detail::chunk_cubics(input, pairs.data() + first, n, apart, options.thickness, c);
    // The tests that end with the chunk's decisions, counted at once; the others kept, in
    // order, and run when a chunk's worth are waiting.
    const std::uint64_t ended = filter ? c.culled : (conservative_first ? c.certainly_apart : 0);
    const auto ended_count = static_cast<std::uint64_t>(__builtin_popcountll(ended));
    counters.tests += ended_count;
    counters.culled += ended_count;
    if (conservative_first) counters.root_solves += ended_count;  // a miss, one interval examined
    for (std::uint64_t rest = chunk_bits(n) & ~ended; rest != 0; rest &= rest - 1) {
      const int i = __builtin_ctzll(rest);
      Left& l = left[left_count++];
      l.index = first + i;
      for (int k = 0; k < 4; ++k) l.cubic.b[k] = c.coefficient[k][i];
      l.cubic.error = c.error[i];
      l.cubic.extent = c.extent[i];
      assert(bool((c.culled >> i) & 1) == filter_culls(l.cubic));
      if (left_count == LEFT_MAX) {
        run_left<kind>(input, pairs, options, left, left_count, counters, hits);
        left_count = 0;
      }
    }
  }
  if (left_count > 0) run_left<kind>(input, pairs, options, left, left_count, counters, hits);
  return counters;
}

}  // namespace

BatchOutput run_batch(const BatchInput& input, const Options& options, int threads) {
  assert(input.start.size() == input.end.size());
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
