#include "drape/ccd_eval/evaluation.h"

#include <algorithm>
#include <chrono>

namespace drape::ccd {

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

namespace {

struct KindSet {
  QueryKind kind;
  std::vector<Query> queries;
  std::vector<bool> truth;
};

// Seconds to run every query of the set once; the hits go to sink so nothing is optimised away.
double time_pass(const KindSet& set, const Options& options, std::uint64_t& sink) {
  const auto begin = std::chrono::steady_clock::now();
  for (const Query& q : set.queries) sink += elementary_ccd(set.kind, q, options).hit;
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
}

}  // namespace

std::vector<EvaluationRow> evaluate_methods(const std::vector<QueryFile>& files, const EvaluationSettings& settings) {
  std::array<KindSet, 2> sets{KindSet{QueryKind::VertexFace, {}, {}}, KindSet{QueryKind::EdgeEdge, {}, {}}};
  for (const QueryFile& file : files) {
    KindSet& set = sets[file.kind == QueryKind::VertexFace ? 0 : 1];
    set.queries.insert(set.queries.end(), file.queries.begin(), file.queries.end());
    set.truth.insert(set.truth.end(), file.truth.begin(), file.truth.end());
  }

  std::vector<EvaluationRow> rows;
  std::uint64_t sink = 0;
  for (Method method : settings.methods) {
    Options options = settings.options;
    options.method = method;
    EvaluationRow all{method, "all"};
    std::vector<double> all_seconds(std::max(settings.passes, 1), 0.0);
    for (const KindSet& set : sets) {
      if (set.queries.empty()) continue;
      EvaluationRow row{method, std::string(kind_name(set.kind))};
      row.queries = set.queries.size();
      for (std::size_t i = 0; i < set.queries.size(); ++i) {
        const Result r = elementary_ccd(set.kind, set.queries[i], options);
        row.positives += set.truth[i];
        row.true_positives += r.hit && set.truth[i];
        row.false_negatives += !r.hit && set.truth[i];
        row.false_positives += r.hit && !set.truth[i];
        row.culled += r.path == Path::Culled || r.path == Path::Separated;
        row.separated += r.path == Path::Separated;
      }
      time_pass(set, options, sink);  // warm-up: caches and clock frequency
      std::vector<double> seconds;
      for (int pass = 0; pass < std::max(settings.passes, 1); ++pass) {
        seconds.push_back(time_pass(set, options, sink));
        all_seconds[pass] += seconds.back();
      }
      row.ns_per_query = 1e9 * median(seconds) / static_cast<double>(row.queries);
      all.queries += row.queries;
      all.positives += row.positives;
      all.true_positives += row.true_positives;
      all.false_negatives += row.false_negatives;
      all.false_positives += row.false_positives;
      all.culled += row.culled;
      all.separated += row.separated;
      rows.push_back(row);
    }
    all.ns_per_query = all.queries ? 1e9 * median(all_seconds) / static_cast<double>(all.queries) : 0.0;
    rows.push_back(all);
  }
  // Keep sink observable so the timed calls cannot be removed.
  if (sink == std::uint64_t(-1)) rows.clear();
  return rows;
}

}  // namespace drape::ccd
