// The coplanarity cubic: its coefficients against direct evaluation of d(t), and its error bound.
#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <random>

#include "drape/ccd/coplanarity.h"
#include "drape/ccd_eval/query_generator.h"
#include "kernel_targets.h"
#include "methods.h"

using namespace drape;
using namespace drape::ccd;

namespace {

// d(t) = (x2 - x1) x (x3 - x1) . (x4 - x1) at the positions of time t, straight from the definition.
Scalar direct(QueryKind kind, const Query& q, Scalar t) {
  const auto order = coplanarity_order(kind);
  std::array<Vec3, 4> x;
  for (int i = 0; i < 4; ++i) x[i] = q.start[order[i]] + t * (q.end[order[i]] - q.start[order[i]]);
  return (x[1] - x[0]).cross(x[2] - x[0]).dot(x[3] - x[0]);
}

// A test oracle: the power-basis coefficients a0..a3 by the paper's formulas (Provot's form),
// written apart from the library's Bernstein form to check it.
Power3 coplanarity_power(QueryKind kind, const Query& query) {
  const auto order = coplanarity_order(kind);
  const auto x = [&](int i) -> const Vec3& { return query.start[order[i - 1]]; };
  const auto v = [&](int i) -> Vec3 { return query.end[order[i - 1]] - query.start[order[i - 1]]; };
  const Vec3 x21 = x(2) - x(1), x31 = x(3) - x(1), x41 = x(4) - x(1);
  const Vec3 v21 = v(2) - v(1), v31 = v(3) - v(1), v41 = v(4) - v(1);
  const Vec3 mixed = v21.cross(x31) + x21.cross(v31);
  return {x21.cross(x31).dot(x41), mixed.dot(x41) + x21.cross(x31).dot(v41),
          v21.cross(v31).dot(x41) + mixed.dot(v41), v21.cross(v31).dot(v41)};
}

Query random_query(std::mt19937_64& rng) {
  std::uniform_real_distribution<Scalar> u(-1, 1);
  Query q;
  for (int i = 0; i < 4; ++i) {
    q.start[i] = Vec3(u(rng), u(rng), u(rng));
    q.end[i] = q.start[i] + Vec3(u(rng), u(rng), u(rng));
  }
  return q;
}

}  // namespace

TEST(Coplanarity, BernsteinAndPowerFormsMatchDirectEvaluation) {
  std::mt19937_64 rng(11);
  for (QueryKind kind : {QueryKind::VertexFace, QueryKind::EdgeEdge}) {
    for (int trial = 0; trial < 2000; ++trial) {
      const Query q = random_query(rng);
      const auto cubic = coplanarity_cubic(kind, q);
      const Power3 a = coplanarity_power(kind, q);
      for (Scalar t : {0.0, 0.2, 0.5, 0.77, 1.0}) {
        const Scalar d = direct(kind, q, t);
        EXPECT_NEAR(evaluate_bernstein(cubic.b, t), d, 1e-12);
        EXPECT_NEAR(evaluate_power(a, t), d, 1e-12);
      }
    }
  }
}

TEST(Coplanarity, VertexFaceUsesTheFaceAsX1X2X3) {
  // Vertex above the triangle (0,0,0), (1,0,0), (0,1,0): d = +height (right-handed triangle).
  Query q;
  q.start = {Vec3(0.2, 0.2, 0.5), Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  q.end = {Vec3(0.2, 0.2, -0.5), Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  const auto cubic = coplanarity_cubic(QueryKind::VertexFace, q);
  EXPECT_DOUBLE_EQ(cubic.b[0], 0.5);
  EXPECT_DOUBLE_EQ(cubic.b[3], -0.5);
}

TEST(Coplanarity, ErrorBoundCoversTheRoundingAtLargeOffsets) {
  // The same configuration translated far from the origin: the computed coefficients must stay
  // within the stated bound of the untranslated (here exactly representable) ones.
  std::mt19937_64 rng(3);
  std::uniform_int_distribution<int> small(-64, 64);
  for (int trial = 0; trial < 2000; ++trial) {
    Query q;
    for (int i = 0; i < 4; ++i) {
      q.start[i] = Vec3(small(rng), small(rng), small(rng)) / 64.0;
      q.end[i] = q.start[i] + Vec3(small(rng), small(rng), small(rng)) / 64.0;
    }
    const auto exact = coplanarity_cubic(QueryKind::EdgeEdge, q);  // dyadic: computed exactly
    Query moved = q;
    const Vec3 offset(1e6 + 0.1, -3e5 - 0.3, 7e5 + 0.7);
    for (int i = 0; i < 4; ++i) moved.start[i] += offset, moved.end[i] += offset;
    const auto cubic = coplanarity_cubic(QueryKind::EdgeEdge, moved);
    // The translation itself rounds each coordinate by up to u * 1e6: that moves the exact cubic
    // by about 1e6 u |A||B| per unit |C| change; allow it, and check the computed bound is honest.
    for (int i = 0; i < 4; ++i) EXPECT_LE(std::abs(cubic.b[i] - exact.b[i]), cubic.error + 1e-7) << i;
  }
}

// The one-query entry points' cubic on every kernel target against the reference template, bit
// for bit: every family and scale of the generator, a cloth-like set, signed zeros, and
// non-finite coordinates (NaN and infinities must come out the same way too).
TEST(Coplanarity, OneQueryKernelMatchesTheReferenceBitForBit) {
  std::vector<std::pair<QueryKind, Query>> queries;
  std::uint64_t seed = 11;
  for (QueryKind kind : {QueryKind::VertexFace, QueryKind::EdgeEdge}) {
    for (QueryFamily family : ALL_FAMILIES)
      for (Scalar scale : {1e-8, 1.0, 1e8})
        for (const Query& q : generate_queries(family, kind, 2000, ++seed, scale)) queries.push_back({kind, q});
    for (const Query& q : gather_queries(cloth_like_set(6, 5), kind)) queries.push_back({kind, q});
  }
  // Special values in one coordinate of otherwise ordinary queries.
  const Scalar specials[] = {0.0, -0.0, std::numeric_limits<Scalar>::quiet_NaN(),
                             std::numeric_limits<Scalar>::infinity(), -std::numeric_limits<Scalar>::infinity(),
                             std::numeric_limits<Scalar>::denorm_min(), 1e300};
  std::mt19937_64 rng(12);
  for (int trial = 0; trial < 2000; ++trial) {
    Query q = random_query(rng);
    q.start[trial % 4][trial % 3] = specials[trial % 7];
    if (trial % 5 == 0) q.end[(trial / 4) % 4] = q.start[(trial / 4) % 4];  // a point at rest
    queries.push_back({trial % 2 ? QueryKind::EdgeEdge : QueryKind::VertexFace, q});
  }
  const auto same_bits = [](Scalar a, Scalar b) { return std::memcmp(&a, &b, sizeof a) == 0; };
  const auto same_cubic = [&](const CoplanarityCubic& x, const CoplanarityCubic& y) {
    bool same = same_bits(x.error, y.error) && same_bits(x.extent, y.extent);
    for (int i = 0; i < 4; ++i) same = same && same_bits(x.b[i], y.b[i]);
    return same;
  };
  // The cubic alone, and the filter's decision with it (the cubic written when not culled).
  kernel_testing::on_every_kernel_target([&] {
    std::size_t differences = 0, decisions = 0, culled = 0;
    for (const auto& [kind, q] : queries) {
      const CoplanarityCubic reference = coplanarity_cubic(kind, q);
      differences += !same_cubic(reference, detail::query_cubic(kind, q));
      CoplanarityCubic fast;
      const bool fast_culls = detail::query_culled(kind, q, fast);
      decisions += fast_culls != filter_culls(reference) || (!fast_culls && !same_cubic(reference, fast));
      culled += fast_culls;
    }
    EXPECT_EQ(differences, 0u) << "of " << queries.size();
    EXPECT_EQ(decisions, 0u) << "of " << queries.size();
    EXPECT_GT(culled, queries.size() / 10);  // both decisions occur
    EXPECT_LT(culled, queries.size() - queries.size() / 10);
  });
}
