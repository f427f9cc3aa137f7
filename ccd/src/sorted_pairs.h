#pragma once
/// \file
/// Index pairs put in order (internal to ccd): the broad phase's triangle pairs are listed in
/// an order that depends on the trees' shapes and the threads, and sorted so that what comes
/// after does not.

#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

namespace drape::ccd {

/// Below this many pairs std::sort is as quick as the counting sort.
inline constexpr std::size_t COUNTING_SORT_PAIRS = 4096;

/// Sorts pairs by first index, then second (std::sort's order): a counting sort by the first
/// index (a triangle's, bounded by the mesh), then each triangle's few partners sorted. A
/// Cusick drape's frames sorted 1-4 million pairs each with std::sort, 8 % of the run.
inline void sort_pairs(std::vector<std::pair<std::int32_t, std::int32_t>>& pairs) {
  if (pairs.size() < COUNTING_SORT_PAIRS) {
    std::sort(pairs.begin(), pairs.end());
    return;
  }
  std::int32_t highest = 0;
  for (const auto& p : pairs) highest = std::max(highest, p.first);
  std::vector<std::size_t> begin(std::size_t(highest) + 2, 0);
  for (const auto& p : pairs) ++begin[std::size_t(p.first) + 1];
  for (std::size_t i = 1; i < begin.size(); ++i) begin[i] += begin[i - 1];
  std::vector<std::pair<std::int32_t, std::int32_t>> sorted(pairs.size());
  std::vector<std::size_t> next(begin.begin(), begin.end() - 1);
  for (const auto& p : pairs) sorted[next[std::size_t(p.first)]++] = p;
  for (std::size_t i = 0; i + 1 < begin.size(); ++i)
    if (begin[i + 1] - begin[i] > 1) std::sort(sorted.begin() + std::ptrdiff_t(begin[i]), sorted.begin() + std::ptrdiff_t(begin[i + 1]));
  pairs.swap(sorted);
}

}  // namespace drape::ccd
