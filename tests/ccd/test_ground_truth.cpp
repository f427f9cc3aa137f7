// The conservative method against the exact ground truth of every bundled query file: zero
// false negatives. The other methods' misses and every method's false alarms are printed only.
#include <gtest/gtest.h>

#include <filesystem>

#include "drape/ccd_eval/evaluation.h"

using namespace drape;
using namespace drape::ccd;

namespace {

std::vector<std::filesystem::path> bundled_files() {
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(DRAPE_TEST_DATA "/ccd-queries"))
    if (entry.path().extension() == ".csv") files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace

TEST(GroundTruth, ConservativeMissesNoContactInAnyBundledFile) {
  const auto files = bundled_files();
  ASSERT_GE(files.size(), 16u);
  Options options;
  options.method = Method::Conservative;
  std::size_t positives = 0;
  for (const auto& path : files) {
    const QueryFile file = read_query_file(path);
    for (std::size_t i = 0; i < file.queries.size(); ++i) {
      if (!file.truth[i]) continue;
      ++positives;
      EXPECT_TRUE(elementary_ccd(file.kind, file.queries[i], options).hit) << path.string() << " query " << i;
    }
  }
  EXPECT_EQ(positives, 298u);  // the counts of the README beside the data
}

TEST(GroundTruth, ReportEveryMethod) {
  std::vector<QueryFile> files;
  for (const auto& path : bundled_files()) files.push_back(read_query_file(path));
  EvaluationSettings settings;
  settings.passes = 1;
  for (const auto& row : evaluate_methods(files, settings)) {
    std::printf("%-13s %-12s queries %5llu positives %4llu false negatives %3llu false positives %4llu\n",
                std::string(method_name(row.method)).c_str(), row.kind.c_str(),
                static_cast<unsigned long long>(row.queries), static_cast<unsigned long long>(row.positives),
                static_cast<unsigned long long>(row.false_negatives),
                static_cast<unsigned long long>(row.false_positives));
    if (row.method == Method::Conservative) {
      EXPECT_EQ(row.false_negatives, 0u) << row.kind;
    }
  }
}
