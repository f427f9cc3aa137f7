// ccd_bench: nanoseconds per elementary CCD test for drape's four methods and the peers (FCL,
// Bullet) on identical queries, side by side in one run, with the targets checked.
//
//   ccd_bench [--passes N] [--grid N] [--data DIR]
//
// Datasets: (a) the public ground-truth queries under tests/data/ccd-queries; (b) a cloth-like
// set from ccd/query_generator.h (a jittered grid and a sheet folded over it, moving a little).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <functional>

#include "ccd_peers.h"
#include "drape/ccd/batch.h"
#include "drape/ccd_eval/evaluation.h"
#include "drape/ccd_eval/query_file.h"
#include "drape/ccd_eval/query_generator.h"

using namespace drape;
using namespace drape::ccd;

namespace {

struct Contender {
  std::string name;
  bool vertex_face = true, edge_edge = true;
  std::function<bool(QueryKind, const Query&)> test;
};

struct KindSet {
  QueryKind kind;
  std::vector<Query> queries;
  std::vector<bool> truth;  // empty when there is no ground truth
};

struct Row {
  std::string contender, kind;
  std::size_t queries = 0, hits = 0, false_negatives = 0, false_positives = 0;
  double ns_per_query = 0;
  bool has_truth = false;
};

double seconds_for(const Contender& c, const KindSet& set, std::uint64_t& sink) {
  const auto begin = std::chrono::steady_clock::now();
  for (const Query& q : set.queries) sink += c.test(set.kind, q);
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
}

// The passes are interleaved: pass p times every contender on every set before pass p + 1
// starts, so that a burst of load from another job on this shared machine falls on all of
// them alike, not on one contender's passes (its median would move, and every ratio to it).
std::vector<Row> measure(const std::vector<Contender>& contenders, const std::vector<KindSet>& sets, int passes) {
  const auto covers = [](const Contender& c, const KindSet& set) {
    return set.kind == QueryKind::VertexFace ? c.vertex_face : c.edge_edge;
  };
  std::uint64_t sink = 0;
  // seconds[c][s][p]: contender c on set s in pass p (empty where c does not cover s).
  std::vector<std::vector<std::vector<double>>> seconds(contenders.size(), std::vector<std::vector<double>>(sets.size()));
  for (int p = 0; p < passes; ++p)
    for (std::size_t c = 0; c < contenders.size(); ++c)
      for (std::size_t s = 0; s < sets.size(); ++s)
        if (covers(contenders[c], sets[s])) seconds[c][s].push_back(seconds_for(contenders[c], sets[s], sink));

  std::vector<Row> rows;
  for (std::size_t c = 0; c < contenders.size(); ++c) {
    const Contender& contender = contenders[c];
    Row all{contender.name, "all"};
    std::vector<double> all_seconds(passes, 0.0);
    bool complete = true;
    for (std::size_t s = 0; s < sets.size(); ++s) {
      const KindSet& set = sets[s];
      if (!covers(contender, set)) {
        complete = false;
        continue;
      }
      Row row{contender.name, std::string(kind_name(set.kind))};
      row.queries = set.queries.size();
      row.has_truth = !set.truth.empty();
      for (std::size_t i = 0; i < set.queries.size(); ++i) {
        const bool hit = contender.test(set.kind, set.queries[i]);
        row.hits += hit;
        if (row.has_truth) {
          row.false_negatives += !hit && set.truth[i];
          row.false_positives += hit && !set.truth[i];
        }
      }
      for (int p = 0; p < passes; ++p) all_seconds[p] += seconds[c][s][p];
      row.ns_per_query = 1e9 * median(seconds[c][s]) / row.queries;
      all.queries += row.queries;
      all.hits += row.hits;
      all.false_negatives += row.false_negatives;
      all.false_positives += row.false_positives;
      all.has_truth = row.has_truth;
      rows.push_back(row);
    }
    if (complete) {
      all.ns_per_query = 1e9 * median(all_seconds) / all.queries;
      rows.push_back(all);
    }
  }
  if (sink == std::uint64_t(-1)) std::puts("");  // keeps the timed calls observable
  return rows;
}

const Row* find(const std::vector<Row>& rows, const std::string& contender, const std::string& kind) {
  for (const Row& r : rows)
    if (r.contender == contender && r.kind == kind) return &r;
  return nullptr;
}

void print(const std::string& title, const std::vector<Row>& rows) {
  std::printf("\n%s\n", title.c_str());
  std::printf("%-17s %-12s %8s %7s %9s %9s %10s %12s\n", "method", "kind", "queries", "hits", "false_neg", "false_pos",
              "ns/query", "vincent is");
  for (const Row& r : rows) {
    const Row* vincent = find(rows, "vincent", r.kind);
    char truth[2][16] = {"-", "-"};
    if (r.has_truth) {
      std::snprintf(truth[0], 16, "%zu", r.false_negatives);
      std::snprintf(truth[1], 16, "%zu", r.false_positives);
    }
    std::printf("%-17s %-12s %8zu %7zu %9s %9s %10.1f %11.2fx\n", r.contender.c_str(), r.kind.c_str(), r.queries,
                r.hits, truth[0], truth[1], r.ns_per_query, vincent ? r.ns_per_query / vincent->ns_per_query : 0.0);
  }
}

// The separation stage's depth for every run of vincent and conservative (--separation-depth).
int separation_depth = Options{}.separation_depth;

void target(bool met, const std::string& text) { std::printf("  [%s] %s\n", met ? "met" : "NOT MET", text.c_str()); }

// The slowest single query: the median of repeated runs of each query, maximised.
std::pair<double, std::string> slowest_query(const std::vector<QueryFile>& files, Method method) {
  Options options;
  options.method = method;
  options.separation_depth = separation_depth;
  double worst = 0;
  std::string where;
  for (const QueryFile& f : files) {
    for (std::size_t i = 0; i < f.queries.size(); ++i) {
      std::vector<double> ns;
      for (int rep = 0; rep < 5; ++rep) {
        const auto begin = std::chrono::steady_clock::now();
        volatile bool hit = elementary_ccd(f.kind, f.queries[i], options).hit;
        (void)hit;
        ns.push_back(std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - begin).count());
      }
      const double m = median(ns);
      if (m > worst) worst = m, where = f.path.string() + " query " + std::to_string(i);
    }
  }
  return {worst, where};
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Nanoseconds per elementary CCD test: drape's methods beside FCL and Bullet, on identical queries."};
  int passes = 15;
  int grid = 24;
  std::string data = DRAPE_TEST_DATA "/ccd-queries";
  app.add_option("--passes", passes, "Timed passes; medians are reported")->check(CLI::Range(1, 1000))->capture_default_str();
  app.add_option("--grid", grid, "Cloth-like set: grid cells per side")->check(CLI::Range(2, 200))->capture_default_str();
  app.add_option("--data", data, "Folder of ground-truth query files")->check(CLI::ExistingDirectory)->capture_default_str();
  app.add_option("--separation-depth", separation_depth,
                 "Levels of the filter's separation stage (vincent, conservative); 0: the paper's filter alone")
      ->check(CLI::Range(0, 6))
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  std::vector<Contender> contenders;
  for (Method m : ALL_METHODS) {
    // The options are prepared once, as a caller does, not rebuilt in the timed loop.
    Options options;
    options.method = m;
    options.separation_depth = separation_depth;
    contenders.push_back({std::string(method_name(m)), true, true, [options](QueryKind kind, const Query& q) {
                            return elementary_ccd(kind, q, options).hit;
                          }});
  }
  for (const auto& peer : bench::available_peers())
    contenders.push_back({peer.name, peer.vertex_face, peer.edge_edge, peer.test});

  // (a) The public queries with ground truth.
  std::vector<QueryFile> files;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(data))
    if (entry.path().extension() == ".csv") files.push_back(read_query_file(entry.path()));
  std::sort(files.begin(), files.end(), [](const auto& a, const auto& b) { return a.path < b.path; });
  std::vector<KindSet> shared{{QueryKind::VertexFace, {}, {}}, {QueryKind::EdgeEdge, {}, {}}};
  for (const QueryFile& f : files) {
    KindSet& set = shared[f.kind == QueryKind::VertexFace ? 0 : 1];
    set.queries.insert(set.queries.end(), f.queries.begin(), f.queries.end());
    set.truth.insert(set.truth.end(), f.truth.begin(), f.truth.end());
  }
  // (b) The cloth-like set.
  const ClothLikeSet cloth = cloth_like_set(grid, 2026);
  const std::vector<KindSet> cloth_sets{{QueryKind::VertexFace, gather_queries(cloth, QueryKind::VertexFace), {}},
                                        {QueryKind::EdgeEdge, gather_queries(cloth, QueryKind::EdgeEdge), {}}};

  std::printf("ccd_bench: %d timed passes per method, interleaved across methods, medians; one thread.\n", passes);
  const auto shared_rows = measure(contenders, shared, passes);
  print("(a) public ground-truth queries (" + data + ")", shared_rows);
  const auto cloth_rows = measure(contenders, cloth_sets, passes);
  print("(b) cloth-like set: " + std::to_string(grid) + "x" + std::to_string(grid) +
            " jittered grid and a folded sheet (" + std::to_string(cloth.start.size()) + " vertices)",
        cloth_rows);

  // (c) The cloth-like set through the batch entry point, the form the cloth pipeline calls:
  // pairs of indices into the vertex arrays, the cubics of a chunk computed together.
  std::vector<VertexFacePair> vf_pairs;
  std::vector<EdgeEdgePair> ee_pairs;
  for (const auto& p : cloth.vertex_face) vf_pairs.push_back({p[0], {p[1], p[2], p[3]}});
  for (const auto& p : cloth.edge_edge) ee_pairs.push_back({{p[0], p[1]}, {p[2], p[3]}});
  const BatchInput batch{cloth.start, cloth.end, vf_pairs, ee_pairs};
  const double batch_tests = double(vf_pairs.size() + ee_pairs.size());
  std::printf("\n(c) the same cloth-like set through the batch entry point (run_batch, one thread)\n");
  std::printf("%-17s %10s %10s %12s\n", "method", "tests", "ns/test", "vincent is");
  double batch_ns[4] = {0, 0, 0, 0};
  std::vector<double> batch_seconds[4];
  for (int p = 0; p < passes; ++p)  // interleaved, as in measure()
    for (int m = 0; m < 4; ++m) {
      Options options;
      options.method = ALL_METHODS[m];
      options.separation_depth = separation_depth;
      const auto begin = std::chrono::steady_clock::now();
      const BatchOutput out = run_batch(batch, options, 1);
      batch_seconds[m].push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count());
      if (out.counters.tests == 0) std::puts("");
    }
  for (int m = 0; m < 4; ++m) batch_ns[m] = 1e9 * median(batch_seconds[m]) / batch_tests;
  const int vincent_index = int(std::find(ALL_METHODS.begin(), ALL_METHODS.end(), Method::Vincent) - ALL_METHODS.begin());
  for (int m = 0; m < 4; ++m)
    std::printf("%-17s %10.0f %10.1f %11.2fx\n", std::string(method_name(ALL_METHODS[m])).c_str(), batch_tests, batch_ns[m],
                batch_ns[m] / batch_ns[vincent_index]);

  std::printf("\nTargets\n");
  const auto ns = [](const std::vector<Row>& rows, const std::string& name) {
    const Row* r = find(rows, name, "all");
    return r ? r->ns_per_query : 0.0;
  };
  const double vincent = ns(cloth_rows, "vincent");
  std::printf("  cloth-like: cubic/vincent = %.2fx, dnf/vincent = %.2fx, conservative/vincent = %.2fx\n",
              ns(cloth_rows, "cubic") / vincent, ns(cloth_rows, "dnf") / vincent,
              ns(cloth_rows, "conservative") / vincent);
  target(ns(cloth_rows, "cubic") >= 5 * vincent, "cloth-like: vincent at least 5x faster than cubic");
  target(ns(cloth_rows, "dnf") > vincent, "cloth-like: vincent faster than dnf");
  if (find(cloth_rows, "fcl-filtered", "all"))
    target(ns(cloth_rows, "fcl-filtered") > vincent, "cloth-like: vincent faster than FCL's filtered functions");
  target(ns(cloth_rows, "conservative") <= 2 * vincent, "cloth-like: conservative at most 2x vincent");
  const auto batch_of = [&](Method m) {
    return batch_ns[std::find(ALL_METHODS.begin(), ALL_METHODS.end(), m) - ALL_METHODS.begin()];
  };
  const double vincent_batch = batch_of(Method::Vincent);
  std::printf("  cloth-like, batch: cubic/vincent = %.2fx, dnf/vincent = %.2fx, conservative/vincent = %.2fx\n",
              batch_of(Method::Cubic) / vincent_batch, batch_of(Method::Dnf) / vincent_batch,
              batch_of(Method::Conservative) / vincent_batch);
  target(batch_of(Method::Cubic) >= 5 * vincent_batch, "cloth-like, batch: vincent at least 5x faster than cubic");
  target(batch_of(Method::Dnf) > vincent_batch, "cloth-like, batch: vincent faster than dnf");
  if (find(cloth_rows, "fcl-filtered", "all"))
    target(ns(cloth_rows, "fcl-filtered") > vincent_batch,
           "cloth-like: vincent through the batch faster than FCL's filtered functions");
  target(batch_of(Method::Conservative) <= 2 * vincent_batch, "cloth-like, batch: conservative at most 2x vincent");
  const Row* conservative = find(shared_rows, "conservative", "all");
  target(conservative->false_negatives == 0, "shared files: conservative misses no contact (" +
                                                 std::to_string(conservative->false_negatives) + " missed)");
  const double fp_rate = 100.0 * conservative->false_positives / conservative->queries;
  char text[160];
  std::snprintf(text, sizeof text, "shared files: conservative false positives %.2f%% of queries (Tight Inclusion: about 3%%)",
                fp_rate);
  target(fp_rate < 3.0, text);
  std::snprintf(text, sizeof text, "shared files: conservative mean %.0f ns a query (under 1000)", conservative->ns_per_query);
  target(conservative->ns_per_query < 1000, text);
  const auto [worst, where] = slowest_query(files, Method::Conservative);
  std::snprintf(text, sizeof text, "shared files: conservative slowest query %.1f us (under 100; %s)", worst / 1e3,
                where.c_str());
  target(worst < 100e3, text);
  return 0;
}
