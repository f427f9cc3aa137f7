#pragma once
/// \file
/// The columns of stats.csv in one table: name, format and golden tolerance.
///
/// The columns of stats.csv in one table: each column's name, how a frame's value is written
/// and the tolerance the golden comparison allows it.

#include <string>
#include <vector>

#include "drape/core/run.h"

namespace drape {

/// |a - b| <= absolute + relative * max(|a|, |b|); ignore skips the column (timings).
struct ColumnTolerance {
  double absolute = 0;
  double relative = 0;
  bool ignore = false;
};

/// The tolerance of a column the table gives none.
inline constexpr ColumnTolerance DEFAULT_TOLERANCE{1e-9, 1e-6};

struct StatsColumn {
  const char* name;
  std::string (*value)(const FrameStats&);  ///< the cell as written
  ColumnTolerance tolerance = DEFAULT_TOLERANCE;
};

/// Every column, in the file's order.
const std::vector<StatsColumn>& stats_columns();

}  // namespace drape
