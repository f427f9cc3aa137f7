// The exact reference against the public ground truth and hand-made queries, then the
// conservative method against the exact reference on every degenerate family (docs/ccd.md,
// "Degenerate families") at scales 2^-27 (about 1e-8) to 2^27 (about 1e8): zero false
// negatives asserted. The other methods' disagreements with the exact answer are printed only.
#include <gtest/gtest.h>

#include <filesystem>

#include "drape/ccd_eval/degenerate_families.h"
#include "drape/ccd_eval/exact_reference.h"
#include "drape/ccd_eval/query_file.h"

using namespace drape;
using namespace drape::ccd;

namespace {

// CI's share of the families: queries per case and scale, and the scales (2^e). The benchmark
// (bench/degenerate_bench) runs millions.
constexpr std::size_t QUERIES_PER_CASE_AND_SCALE = 12;
constexpr int SCALE_EXPONENTS[] = {-27, -9, 0, 9, 27};

Query motion(const std::array<Vec3, 4>& start, const std::array<Vec3, 4>& end) { return Query{start, end}; }

}  // namespace

TEST(ExactReference, AgreesWithEveryBundledGroundTruth) {
  std::size_t queries = 0, positives = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(DRAPE_TEST_DATA "/ccd-queries")) {
    if (entry.path().extension() != ".csv") continue;
    const QueryFile file = read_query_file(entry.path());
    for (std::size_t i = 0; i < file.queries.size(); ++i) {
      ++queries;
      positives += file.truth[i];
      EXPECT_EQ(exact_contact(file.kind, file.queries[i]), bool(file.truth[i])) << entry.path().string() << " query " << i;
    }
  }
  EXPECT_GT(queries, 1500u);
  EXPECT_EQ(positives, 298u);
}

TEST(ExactReference, HandMadeQueries) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  // A vertex through the face's interior, beside it, and stopping 2^-50 short of it.
  EXPECT_TRUE(exact_contact(QueryKind::VertexFace, motion({Vec3(0.25, 0.25, 1), a, b, c}, {Vec3(0.25, 0.25, -1), a, b, c})));
  EXPECT_FALSE(exact_contact(QueryKind::VertexFace, motion({Vec3(0.75, 0.75, 1), a, b, c}, {Vec3(0.75, 0.75, -1), a, b, c})));
  EXPECT_FALSE(exact_contact(QueryKind::VertexFace,
                             motion({Vec3(0.25, 0.25, 1), a, b, c}, {Vec3(0.25, 0.25, std::ldexp(1.0, -50)), a, b, c})));
  // Exactly on the edge at the end of the step, and at a corner.
  EXPECT_TRUE(exact_contact(QueryKind::VertexFace, motion({Vec3(0.5, 0.5, 1), a, b, c}, {Vec3(0.5, 0.5, 0), a, b, c})));
  EXPECT_TRUE(exact_contact(QueryKind::VertexFace, motion({Vec3(1, 0, 1), a, b, c}, {Vec3(1, 0, 0), a, b, c})));
  // Coplanar motion (the cubic vanishes): sliding into the face, and past it.
  EXPECT_TRUE(exact_contact(QueryKind::VertexFace, motion({Vec3(1, 0.5, 0), a, b, c}, {Vec3(-1, 0.5, 0), a, b, c})));
  EXPECT_FALSE(exact_contact(QueryKind::VertexFace, motion({Vec3(2, 1.5, 0), a, b, c}, {Vec3(1, 1.5, 0), a, b, c})));
  // A triangle that collapses onto a segment at t = 1 with the vertex on that segment then; and
  // the vertex on the segment's line, outside it.
  const std::array<Vec3, 4> collapsed_on{Vec3(0.25, 0, 0), a, b, Vec3(0.5, 0, 0)};
  EXPECT_TRUE(exact_contact(QueryKind::VertexFace, motion({Vec3(0.25, 0, 1), a, b, Vec3(0, 1, 1)}, collapsed_on)));
  EXPECT_FALSE(exact_contact(QueryKind::VertexFace,
                             motion({Vec3(2, 0, 1), a, b, Vec3(0, 1, 1)}, {Vec3(2, 0, 0), a, b, Vec3(0.5, 0, 0)})));
  // Edges crossing, passing, parallel and sliding along one line into each other.
  EXPECT_TRUE(exact_contact(QueryKind::EdgeEdge, motion({Vec3(-1, 0, 1), Vec3(1, 0, 1), Vec3(0, -1, 0), Vec3(0, 1, 0)},
                                                        {Vec3(-1, 0, -1), Vec3(1, 0, -1), Vec3(0, -1, 0), Vec3(0, 1, 0)})));
  EXPECT_FALSE(exact_contact(QueryKind::EdgeEdge, motion({Vec3(2, 0, 1), Vec3(3, 0, 1), Vec3(0, -1, 0), Vec3(0, 1, 0)},
                                                         {Vec3(2, 0, -1), Vec3(3, 0, -1), Vec3(0, -1, 0), Vec3(0, 1, 0)})));
  EXPECT_TRUE(exact_contact(QueryKind::EdgeEdge, motion({Vec3(2, 0, 0), Vec3(3, 0, 0), Vec3(0, 0, 0), Vec3(1, 0, 0)},
                                                        {Vec3(1, 0, 0), Vec3(2, 0, 0), Vec3(0, 0, 0), Vec3(1, 0, 0)})));
  EXPECT_FALSE(exact_contact(QueryKind::EdgeEdge, motion({Vec3(3, 0, 0), Vec3(4, 0, 0), Vec3(0, 0, 0), Vec3(1, 0, 0)},
                                                         {Vec3(2, 0, 0), Vec3(3, 0, 0), Vec3(0, 0, 0), Vec3(1, 0, 0)})));
  // A zero-length edge (a point) meeting the other edge's interior mid-step.
  EXPECT_TRUE(exact_contact(QueryKind::EdgeEdge, motion({Vec3(0.5, 1, 0), Vec3(0.5, 1, 0), a, b},
                                                        {Vec3(0.5, -1, 0), Vec3(0.5, -1, 0), a, b})));
}

TEST(ExactReference, EveryCaseOfTheTableIsGenerated) {
  const auto cases = degenerate_cases();
  EXPECT_EQ(cases.size(), 88u);  // 6 shapes x 4 times x 4 placements, less a point's interior (2 x 4)
  for (const auto& c : cases) {
    const auto queries = generate_degenerate_queries(c, 4, 7, 0);
    ASSERT_EQ(queries.size(), 4u) << describe(c);
    for (const Query& q : queries)
      for (int i = 0; i < 4; ++i) EXPECT_TRUE(q.start[std::size_t(i)].allFinite() && q.end[std::size_t(i)].allFinite());
    // Interior and boundary placements touch by construction.
    if (c.placement == DegeneratePlacement::Interior || c.placement == DegeneratePlacement::Boundary) {
      for (const Query& q : queries) EXPECT_TRUE(exact_contact(c.kind, q)) << describe(c);
    }
  }
}

TEST(ExactReference, ConservativeMissesNoDegenerateContact) {
  std::size_t contacts = 0, queries = 0;
  for (const auto& c : degenerate_cases()) {
    std::size_t method_misses[4] = {}, method_false_alarms[4] = {}, case_contacts = 0;
    for (const int e : SCALE_EXPONENTS) {
      for (const Query& q : generate_degenerate_queries(c, QUERIES_PER_CASE_AND_SCALE, 1000 + std::uint64_t(e + 100), e)) {
        ++queries;
        const bool truth = exact_contact(c.kind, q);
        case_contacts += truth;
        for (std::size_t m = 0; m < ALL_METHODS.size(); ++m) {
          Options options;
          options.method = ALL_METHODS[m];
          const bool hit = elementary_ccd(c.kind, q, options).hit;
          method_misses[m] += truth && !hit;
          method_false_alarms[m] += !truth && hit;
          if (ALL_METHODS[m] == Method::Conservative) {
            EXPECT_TRUE(hit || !truth) << describe(c) << " at scale 2^" << e;
          }
        }
      }
    }
    contacts += case_contacts;
    for (std::size_t m = 0; m < ALL_METHODS.size(); ++m)
      if (method_misses[m] || method_false_alarms[m])
        std::printf("%-48s %-12s misses %3zu of %3zu contacts, false alarms %3zu\n", describe(c).c_str(),
                    std::string(method_name(ALL_METHODS[m])).c_str(), method_misses[m], case_contacts,
                    method_false_alarms[m]);
  }
  std::printf("%zu degenerate queries, %zu contacts\n", queries, contacts);
  EXPECT_GT(contacts, queries / 3);
}
