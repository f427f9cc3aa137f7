#pragma once
/// \file
/// Compares a run's stats.csv with a golden one, column by column.
///
/// Compares a run's stats.csv with a golden one, column by column, with per-column tolerances.

#include <filesystem>
#include <map>
#include <optional>
#include <string>

#include "drape/core/stats_columns.h"

namespace drape {

/// The tolerances of stats_columns() other than the default, by column name; columns not
/// listed get default_tolerance().
const std::map<std::string, ColumnTolerance>& stats_tolerances();
ColumnTolerance default_tolerance();

struct StatsDifference {
  int row = 0;  ///< data row (0 = first frame row); -1 for a header or row-count difference
  std::string frame;
  std::string column;
  std::string run_value, golden_value;
  std::string message;  ///< a sentence saying what differs and the tolerance
};

/// The first difference beyond tolerance, or nullopt when the files agree. Throws
/// std::runtime_error naming the file (and line) when a file cannot be read, is empty, or has a
/// row whose cell count differs from its header.
std::optional<StatsDifference> compare_stats(const std::filesystem::path& run, const std::filesystem::path& golden);

}  // namespace drape
