// The filter's separation stage (ccd/src/separation.cpp): the axis test never claims a gap that
// is not there, and the stage changes no answer of vincent, only how it is reached.
#include <gtest/gtest.h>

#include <filesystem>
#include <limits>
#include <random>

#include "drape/ccd_eval/query_file.h"
#include "drape/ccd_eval/query_generator.h"
#include "kernel_targets.h"
#include "methods.h"

using namespace drape;
using namespace drape::ccd;

namespace {

// The exact distance between the features at time t is at most the long double estimate plus
// its error bound.
long double distance_upper_bound(QueryKind kind, const Query& q, long double t) {
  const auto p = detail::proximity_at<long double>(kind, q, t);
  return p.distance + p.error;
}

}  // namespace

TEST(Separation, AnAxisGapHoldsAtEveryTimeOfTheInterval) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<Scalar> unit(0, 1);
  std::size_t apart = 0, near = 0;
  for (QueryKind kind : {QueryKind::VertexFace, QueryKind::EdgeEdge}) {
    for (QueryFamily family : {QueryFamily::Random, QueryFamily::Contact, QueryFamily::ParallelEdges}) {
      const auto queries = generate_queries(family, kind, 20'000, 11 + int(family));
      for (std::size_t i = 0; i < queries.size(); ++i) {
        Scalar lo = unit(rng), hi = unit(rng);
        if (lo > hi) std::swap(lo, hi);
        const Scalar gap = 0.05 * unit(rng);
        if (!detail::apart_over(kind, queries[i], lo, hi, gap)) {
          ++near;
          continue;
        }
        ++apart;
        for (int k = 0; k <= 16; ++k) {
          const long double t = lo + (hi - lo) * k / 16.0L;
          ASSERT_GT(distance_upper_bound(kind, queries[i], t), gap)
              << kind_name(kind) << " " << family_name(family) << " #" << i << " t=" << double(t);
        }
      }
    }
  }
  // Both answers occur: the check above is not vacuous.
  EXPECT_GT(apart, 10'000u);
  EXPECT_GT(near, 10'000u);
}

TEST(Separation, EveryKernelTargetsAxisTestDecidesAsThePortableOne) {
  // The coordinate-axis test on every kernel target against the portable one-lane code, on the
  // same queries and intervals, every family and scale: the same answers and the same margin.
  struct Case {
    QueryKind kind;
    Query q;
    Scalar lo, hi, gap;
  };
  std::vector<Case> cases;
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<Scalar> unit(0, 1);
  for (QueryKind kind : {QueryKind::VertexFace, QueryKind::EdgeEdge})
    for (QueryFamily family : ALL_FAMILIES)
      for (Scalar scale : {1e-8, 1.0, 1e8})
        for (const Query& q : generate_queries(family, kind, 1'000, 21 + int(family), scale)) {
          Scalar lo = unit(rng), hi = unit(rng);
          if (lo > hi) std::swap(lo, hi);
          cases.push_back({kind, q, lo, hi, 0.05 * scale * unit(rng)});
        }
  const auto answers = [&](std::vector<bool>& apart, std::vector<Scalar>& need) {
    for (const Case& c : cases) {
      Scalar n = 0;
      apart.push_back(detail::coordinate_axes_apart(c.kind, c.q, c.lo, c.hi, c.gap, n));
      need.push_back(n);
    }
  };
  std::vector<bool> portable;
  std::vector<Scalar> portable_need;
  detail::use_kernel_target(kernel_testing::portable_kernel_target());
  answers(portable, portable_need);
  detail::use_kernel_target(0);
  kernel_testing::on_every_kernel_target([&] {
    std::vector<bool> apart;
    std::vector<Scalar> need;
    answers(apart, need);
    std::size_t differences = 0;
    for (std::size_t i = 0; i < cases.size(); ++i)
      differences += apart[i] != portable[i] || !(need[i] == portable_need[i]);
    EXPECT_EQ(differences, 0u) << "of " << cases.size();
  });
  std::size_t apart = 0;
  for (const bool a : portable) apart += a;
  EXPECT_GT(apart, cases.size() / 10);
  EXPECT_LT(apart, cases.size() - cases.size() / 10);
}

TEST(Separation, TreeOfHalvingsMatchesPlainSubdivision) {
  // kept_sub_intervals (the unrolled recursion) against each leaf computed by
  // repeated split_half and tested with certainly_nonzero: the same mask, at every depth.
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<Scalar> coefficient(-1, 1), scale(0, 0.3);
  std::size_t mixed = 0;
  for (int trial = 0; trial < 20'000; ++trial) {
    Bernstein3 b{coefficient(rng), coefficient(rng), coefficient(rng), coefficient(rng)};
    if (trial % 7 == 0) b[trial % 4] = std::numeric_limits<Scalar>::quiet_NaN();
    const Scalar margin = scale(rng) * scale(rng);
    for (int depth = 1; depth <= 6; ++depth) {
      std::uint64_t expected = 0;
      for (int leaf = 0; leaf < (1 << depth); ++leaf) {
        Bernstein3 c = b, left, right;
        for (int level = depth - 1; level >= 0; --level) {
          split_half(c, left, right);
          c = (leaf >> level) & 1 ? right : left;
        }
        expected |= std::uint64_t(!certainly_nonzero(c, margin)) << leaf;
      }
      ASSERT_EQ(detail::kept_sub_intervals(b, margin, depth), expected) << "trial " << trial << " depth " << depth;
      const std::uint64_t all = depth == 6 ? ~std::uint64_t(0) : (std::uint64_t(1) << (1 << depth)) - 1;
      mixed += expected != 0 && expected != all;
    }
  }
  EXPECT_GT(mixed, 10'000u);  // masks with kept and dropped leaves both occur
}

TEST(Separation, ATouchingIntervalIsNeverSeparated) {
  // Built contacts: at their contact time the features touch, so no interval around it is apart.
  std::size_t checked = 0;
  for (QueryKind kind : {QueryKind::VertexFace, QueryKind::EdgeEdge}) {
    const auto queries = generate_queries(QueryFamily::Contact, kind, 20'000, 99);
    Options conservative;
    conservative.method = Method::Conservative;
    for (const Query& q : queries) {
      const Result r = elementary_ccd(kind, q, conservative);
      if (!r.hit) continue;
      ++checked;
      EXPECT_FALSE(detail::apart_over(kind, q, std::max(0.0, r.toc - 1e-3), std::min(1.0, r.toc + 1e-3), 0.0));
    }
  }
  EXPECT_GT(checked, 10'000u);
}

namespace {

struct StageTally {
  std::size_t queries = 0, separated = 0, differences = 0;
};

// Vincent with the stage and without it: the same hit, time and parameters; and cubic never
// finds a contact in a test the stage separated.
void compare_vincent(QueryKind kind, const Query& q, Scalar thickness, StageTally& tally, const std::string& where) {
  Options with, without, cubic;
  with.method = without.method = Method::Vincent;
  cubic.method = Method::Cubic;
  with.thickness = without.thickness = cubic.thickness = thickness;
  without.separation_depth = 0;
  const Result a = elementary_ccd(kind, q, with), b = elementary_ccd(kind, q, without);
  ++tally.queries;
  tally.separated += a.path == Path::Separated;
  const bool same = a.hit == b.hit && (!a.hit || (a.toc == b.toc && a.params == b.params));
  if (!same || (a.path == Path::Separated && elementary_ccd(kind, q, cubic).hit)) {
    ++tally.differences;
    ADD_FAILURE() << where << ": with the stage hit=" << a.hit << " toc=" << a.toc << ", without hit=" << b.hit
                  << " toc=" << b.toc;
  }
}

}  // namespace

TEST(Separation, ChangesNoAnswerOfVincent) {
  for (const Scalar thickness : {0.0, 1e-3}) {
    StageTally tally;
    for (const auto& entry : std::filesystem::recursive_directory_iterator(DRAPE_TEST_DATA "/ccd-queries")) {
      if (entry.path().extension() != ".csv") continue;
      const QueryFile file = read_query_file(entry.path());
      for (std::size_t i = 0; i < file.queries.size() && tally.differences < 10; ++i)
        compare_vincent(file.kind, file.queries[i], thickness, tally, entry.path().string() + " #" + std::to_string(i));
    }
    std::uint64_t seed = 31;
    for (QueryKind kind : {QueryKind::VertexFace, QueryKind::EdgeEdge}) {
      for (QueryFamily family : ALL_FAMILIES) {
        const auto queries = generate_queries(family, kind, 10'000, seed++);
        for (std::size_t i = 0; i < queries.size() && tally.differences < 10; ++i)
          compare_vincent(kind, queries[i], thickness, tally,
                          std::string(kind_name(kind)) + "/" + family_name(family) + " #" + std::to_string(i));
      }
      for (const Query& q : gather_queries(cloth_like_set(12, 5), kind))
        compare_vincent(kind, q, thickness, tally, "cloth-like");
    }
    std::printf("thickness %g: %zu queries, %zu separated by the stage, %zu differences\n", thickness, tally.queries,
                tally.separated, tally.differences);
    EXPECT_EQ(tally.differences, 0u);
    EXPECT_GT(tally.separated, 1'000u);  // the stage does decide tests here
  }
}

TEST(Separation, ConservativeKeepsEveryBuiltContact) {
  // The families built to touch, at zero thickness and with a thickness (where the stage must
  // also keep times the features come within the thickness without being coplanar): the
  // conservative method finds the same contacts with the stage as without it (the exact
  // references of test_exact_extremes run with it too).
  for (const Scalar thickness : {0.0, 0.02}) {
    std::size_t separated = 0;
    for (QueryKind kind : {QueryKind::VertexFace, QueryKind::EdgeEdge}) {
      for (QueryFamily family : {QueryFamily::Contact, QueryFamily::TouchAtStart, QueryFamily::TouchAtEnd,
                                 QueryFamily::FarFromOrigin, QueryFamily::TinyMotion, QueryFamily::Random}) {
        const auto queries = generate_queries(family, kind, 5'000, 77 + int(family));
        Options with, without;
        with.method = without.method = Method::Conservative;
        with.thickness = without.thickness = thickness;
        without.separation_depth = 0;
        std::size_t hits = 0;
        for (std::size_t i = 0; i < queries.size(); ++i) {
          const Result b = elementary_ccd(kind, queries[i], without);
          const Result a = elementary_ccd(kind, queries[i], with);
          hits += b.hit;
          separated += a.path == Path::Separated;
          if (b.hit) {
            EXPECT_TRUE(a.hit) << kind_name(kind) << " " << family_name(family) << " #" << i << " thickness "
                               << thickness;
          }
        }
        // With a thickness, the random family's contacts are features passing within it
        // without touching: where the stage's thickness margin matters.
        if (family != QueryFamily::Random || thickness > 0) {
          EXPECT_GT(hits, 0u) << kind_name(kind) << " " << family_name(family) << " thickness " << thickness;
        }
      }
    }
    EXPECT_GT(separated, 1'000u) << "thickness " << thickness;  // the stage does decide tests here
  }
}

TEST(Separation, FeaturesApartOverTheWholeStepNeedNoTree) {
  // A vertex sliding in the plane of a triangle, far outside it: the cubic is zero over the
  // whole step, so every sub-interval of the tree is kept, and only the whole step's boxes
  // show the features apart. Move the vertex onto the triangle and they are not.
  Query q;
  q.start = {Vec3(5, 0, 0), Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  q.end = {Vec3(6, 0.5, 0), Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  const CoplanarityCubic cubic = coplanarity_cubic(QueryKind::VertexFace, q);
  const std::uint64_t all = (std::uint64_t(1) << 4) - 1;
  ASSERT_EQ(detail::kept_sub_intervals(cubic.b, 2 * cubic.error, 2), all);
  EXPECT_TRUE(detail::roots_apart(QueryKind::VertexFace, q, cubic, 0.0, 2));
  EXPECT_FALSE(detail::roots_apart(QueryKind::VertexFace, q, cubic, 0.0, 0));  // depth 0: no stage
  EXPECT_FALSE(detail::roots_apart(QueryKind::VertexFace, q, cubic, 4.5, 2));  // the gap is wider than the boxes' distance
  q.end[0] = Vec3(0.2, 0.2, 0);
  EXPECT_FALSE(detail::roots_apart(QueryKind::VertexFace, q, coplanarity_cubic(QueryKind::VertexFace, q), 0.0, 2));
}

TEST(Separation, EveryKernelTargetsStageDecidesAsThePortableOne) {
  // The whole stage (roots_apart: the whole step's boxes, the tree, the runs' boxes with the
  // margin computed once) on every kernel target against the portable one-lane code, on every
  // family and scale, at two thicknesses, and with a NaN or an infinity in one coordinate
  // (nothing is apart there); and apart_over, whose coordinates must be finite, on the finite
  // queries.
  struct Case {
    QueryKind kind;
    Query q;
    CoplanarityCubic cubic;
    Scalar gap;
    bool finite;
  };
  std::vector<Case> cases;
  for (QueryKind kind : {QueryKind::VertexFace, QueryKind::EdgeEdge})
    for (QueryFamily family : ALL_FAMILIES)
      for (Scalar scale : {1e-8, 1.0, 1e8}) {
        int n = 0;
        for (Query q : generate_queries(family, kind, 500, 41 + int(family), scale)) {
          const int poisoned = n++ % 8;  // 0: a NaN, 1: +inf, 2: -inf, else finite
          if (poisoned < 3) {
            const Scalar bad = poisoned == 0 ? std::numeric_limits<Scalar>::quiet_NaN()
                                             : (poisoned == 1 ? 1 : -1) * std::numeric_limits<Scalar>::infinity();
            (n % 2 ? q.start : q.end)[n % 4][n % 3] = bad;
          }
          for (const Scalar gap : {0.0, 0.01 * scale}) cases.push_back({kind, q, coplanarity_cubic(kind, q), gap, poisoned >= 3});
        }
      }
  const auto answers = [&](std::vector<bool>& stage, std::vector<bool>& over) {
    for (const Case& c : cases) {
      stage.push_back(detail::roots_apart(c.kind, c.q, c.cubic, c.gap, 2, c.gap));
      over.push_back(c.finite && detail::apart_over(c.kind, c.q, 0.25, 0.5, c.gap));
    }
  };
  std::vector<bool> portable, portable_over;
  detail::use_kernel_target(kernel_testing::portable_kernel_target());
  answers(portable, portable_over);
  detail::use_kernel_target(0);
  kernel_testing::on_every_kernel_target([&] {
    std::vector<bool> stage, over;
    answers(stage, over);
    std::size_t differences = 0, nonfinite_apart = 0;
    for (std::size_t i = 0; i < cases.size(); ++i) {
      differences += stage[i] != portable[i] || over[i] != portable_over[i];
      nonfinite_apart += !cases[i].finite && stage[i];
    }
    EXPECT_EQ(differences, 0u) << "of " << cases.size();
    EXPECT_EQ(nonfinite_apart, 0u);
  });
  std::size_t finite = 0, finite_apart = 0;
  for (std::size_t i = 0; i < cases.size(); ++i) finite += cases[i].finite, finite_apart += cases[i].finite && portable[i];
  EXPECT_GT(finite_apart, finite / 10);  // the stage does separate here
}

// Coordinates beyond STAGE_COORDINATE_LIMIT with a finite cubic (small differences far from the
// origin): the shape axes' projections could overflow there, so the stage answers nothing, on
// every target, even for features whose boxes are far apart; within the limit it still does.
TEST(Separation, CoordinatesBeyondTheLimitAreNeverSeparated) {
  const auto query = [](Scalar offset, Scalar size) {
    Query q;
    // A triangle in the plane z = offset, and a vertex crossing that plane far outside it.
    q.start[1] = Vec3(offset, offset, offset);
    q.start[2] = Vec3(offset + size, offset, offset);
    q.start[3] = Vec3(offset, offset + size, offset);
    for (int i = 1; i < 4; ++i) q.end[i] = q.start[i];
    q.start[0] = Vec3(offset + 8 * size, offset + 8 * size, offset + size);
    q.end[0] = Vec3(offset + 8 * size, offset + 8 * size, offset - size);
    return q;
  };
  kernel_testing::on_every_kernel_target([&] {
    for (const Scalar offset : {1e101, 1e110}) {
      const Query q = query(offset, offset * 1e-8);
      const CoplanarityCubic cubic = coplanarity_cubic(QueryKind::VertexFace, q);
      ASSERT_TRUE(detail::stage_runs(cubic, 2)) << offset;  // a finite cubic
      EXPECT_FALSE(detail::stage_runs(q, cubic, 2)) << offset;
      EXPECT_FALSE(detail::roots_apart(QueryKind::VertexFace, q, cubic, 0.0, 2)) << offset;
    }
    const Query q = query(1e99, 1e91);
    EXPECT_TRUE(detail::roots_apart(QueryKind::VertexFace, q, coplanarity_cubic(QueryKind::VertexFace, q), 0.0, 2));
  });
}
