#pragma once
/// \file
/// Runs CCD methods over query files with ground truth: accuracy counts and timing.

#include <string>
#include <vector>

#include "drape/ccd_eval/query_file.h"

namespace drape::ccd {

/// One method on one kind of query ("vertex-face", "edge-edge" or "all").
struct EvaluationRow {
  Method method = Method::Vincent;
  std::string kind;
  std::uint64_t queries = 0;
  std::uint64_t positives = 0;        ///< ground truth says contact
  std::uint64_t true_positives = 0;
  std::uint64_t false_negatives = 0;  ///< contacts the method missed
  std::uint64_t false_positives = 0;  ///< contacts the method reported that are not there
  std::uint64_t culled = 0;           ///< decided by the filter alone (signs or separation)
  std::uint64_t separated = 0;        ///< of those, by the separation stage
  double ns_per_query = 0.0;          ///< median over the timed passes
};

struct EvaluationSettings {
  std::vector<Method> methods{ALL_METHODS.begin(), ALL_METHODS.end()};
  Options options;     ///< method is overridden by each of methods
  int passes = 15;     ///< timed passes over all queries; the median is reported
};

/// Rows ordered by method, then vertex-face, edge-edge, all (kinds with no query are skipped,
/// except "all").
std::vector<EvaluationRow> evaluate_methods(const std::vector<QueryFile>& files, const EvaluationSettings& settings);

/// Median of a non-empty list (the mean of the two middle values for an even count).
double median(std::vector<double> values);

}  // namespace drape::ccd
