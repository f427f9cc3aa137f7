// The filter only removes tests that have no root: wherever `cubic` reports a contact, `dnf`
// and `vincent` report it too, at the same time of contact. Checked on the shared query files
// and on a million generated queries (fixed seeds) including the near-degenerate families.
#include <gtest/gtest.h>

#include <filesystem>

#include "drape/ccd_eval/query_file.h"
#include "drape/ccd_eval/query_generator.h"

using namespace drape;
using namespace drape::ccd;

namespace {

// Time-of-contact agreement. Each method refines its root to about 1e-13 of the step, but a
// tangential (double) root is only determined to about the square root of the rounding error.
constexpr Scalar TOC_AGREEMENT_TOLERANCE = 1e-6;
constexpr std::size_t GENERATED_QUERIES = 1'000'000;

struct Tally {
  std::size_t queries = 0, cubic_hits = 0, disagreements = 0, filter_only_hits = 0;
};

void compare(QueryKind kind, const Query& q, Tally& tally, const std::string& where) {
  Options options;
  options.method = Method::Cubic;
  const Result cubic = elementary_ccd(kind, q, options);
  ++tally.queries;
  for (Method filtered : {Method::Dnf, Method::Vincent}) {
    options.method = filtered;
    const Result r = elementary_ccd(kind, q, options);
    if (cubic.hit) {
      const bool agree = r.hit && std::abs(r.toc - cubic.toc) <= TOC_AGREEMENT_TOLERANCE;
      if (!agree) {
        ++tally.disagreements;
        ADD_FAILURE() << where << ": " << method_name(filtered) << " hit=" << r.hit << " toc=" << r.toc
                      << " but cubic toc=" << cubic.toc;
      }
    } else if (r.hit) {
      ++tally.filter_only_hits;
    }
  }
  tally.cubic_hits += cubic.hit;
}

}  // namespace

TEST(Agreement, SharedQueryFiles) {
  Tally tally;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(DRAPE_TEST_DATA "/ccd-queries")) {
    if (entry.path().extension() != ".csv") continue;
    const QueryFile file = read_query_file(entry.path());
    for (std::size_t i = 0; i < file.queries.size(); ++i)
      compare(file.kind, file.queries[i], tally, entry.path().string() + " query " + std::to_string(i));
  }
  EXPECT_GT(tally.cubic_hits, 0u);
  EXPECT_EQ(tally.disagreements, 0u);
  std::printf("shared files: %zu queries, %zu cubic hits, %zu hits found only with a filter\n", tally.queries,
              tally.cubic_hits, tally.filter_only_hits);
}

TEST(Agreement, AMillionGeneratedQueries) {
  Tally tally;
  const std::size_t per_set = GENERATED_QUERIES / (2 * std::size(ALL_FAMILIES));
  std::uint64_t seed = 20261122;
  for (QueryKind kind : {QueryKind::VertexFace, QueryKind::EdgeEdge}) {
    for (QueryFamily family : ALL_FAMILIES) {
      const auto queries = generate_queries(family, kind, per_set, seed++);
      Tally set;
      for (std::size_t i = 0; i < queries.size() && set.disagreements < 10; ++i)
        compare(kind, queries[i], set, std::string(kind_name(kind)) + "/" + family_name(family) + " #" + std::to_string(i));
      std::printf("%-12s %-16s %7zu queries %7zu cubic hits %5zu disagreements %5zu filter-only hits\n",
                  std::string(kind_name(kind)).c_str(), family_name(family), set.queries, set.cubic_hits,
                  set.disagreements, set.filter_only_hits);
      tally.queries += set.queries;
      tally.cubic_hits += set.cubic_hits;
      tally.disagreements += set.disagreements;
    }
  }
  EXPECT_GE(tally.queries, GENERATED_QUERIES - 2 * std::size(ALL_FAMILIES));
  EXPECT_GT(tally.cubic_hits, tally.queries / 20);  // the contact families do produce contacts
  EXPECT_EQ(tally.disagreements, 0u);
}
