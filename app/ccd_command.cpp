// drape ccd: the CCD methods on query files with ground truth.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "drape/ccd_eval/evaluation.h"
#include "drape/ccd_eval/query_file.h"

namespace drape::app {
namespace {

namespace fs = std::filesystem;

struct CcdArguments {
  std::vector<std::string> inputs;
  std::string method = "all";
  std::string kind;
  bool json = false;
  ccd::EvaluationSettings settings;
};

// Files named on the command line; a folder stands for every .csv file below it, in name order.
std::vector<fs::path> expand_inputs(const std::vector<std::string>& inputs) {
  std::vector<fs::path> files;
  for (const auto& input : inputs) {
    const fs::path path(input);
    std::error_code error;
    if (fs::is_directory(path, error)) {
      std::vector<fs::path> found;
      try {
        for (const auto& entry : fs::recursive_directory_iterator(path))
          if (entry.is_regular_file() && entry.path().extension() == ".csv") found.push_back(entry.path());
      } catch (const fs::filesystem_error& e) {  // e.g. a subfolder that may not be read
        const fs::path where = e.path1().empty() ? path : e.path1();
        throw ccd::QueryFileError(where.string() + ": cannot list the folder: " + e.code().message());
      }
      if (found.empty()) throw ccd::QueryFileError(input + ": the folder holds no .csv query file");
      std::sort(found.begin(), found.end());
      files.insert(files.end(), found.begin(), found.end());
    } else {
      files.push_back(path);
    }
  }
  return files;
}

void print_table(const std::vector<ccd::EvaluationRow>& rows, int passes) {
  std::printf("%-13s %-12s %8s %9s %8s %8s %8s %8s %9s %11s\n", "method", "kind", "queries", "positives", "true_pos",
              "false_neg", "false_pos", "culled", "separated", "ns/query");
  for (const auto& r : rows) {
    std::printf("%-13s %-12s %8llu %9llu %8llu %8llu %8llu %8llu %9llu %11.1f\n",
                std::string(ccd::method_name(r.method)).c_str(), r.kind.c_str(),
                static_cast<unsigned long long>(r.queries), static_cast<unsigned long long>(r.positives),
                static_cast<unsigned long long>(r.true_positives), static_cast<unsigned long long>(r.false_negatives),
                static_cast<unsigned long long>(r.false_positives), static_cast<unsigned long long>(r.culled),
                static_cast<unsigned long long>(r.separated), r.ns_per_query);
  }
  std::printf(
      "\nfalse_neg: contacts missed; false_pos: contacts reported that are not there; culled: decided by the\n"
      "filter with no root finding; separated: of those, by the separation stage (the cubic has roots, the\n"
      "features are apart around them); ns/query: median over %d timed passes on one thread.\n",
      passes);
}

void print_json(const std::vector<ccd::EvaluationRow>& rows) {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& r : rows) {
    out.push_back({{"method", ccd::method_name(r.method)},
                   {"kind", r.kind},
                   {"queries", r.queries},
                   {"positives", r.positives},
                   {"true_positives", r.true_positives},
                   {"false_negatives", r.false_negatives},
                   {"false_positives", r.false_positives},
                   {"culled", r.culled},
                   {"ns_per_query", r.ns_per_query}});
  }
  std::cout << out.dump(2) << "\n";
}

int run_ccd(const CcdArguments& args) {
  ccd::EvaluationSettings settings = args.settings;
  if (args.method != "all") settings.methods = {*ccd::parse_method(args.method)};
  std::optional<ccd::QueryKind> kind;
  if (args.kind == "vertex-face") kind = ccd::QueryKind::VertexFace;
  if (args.kind == "edge-edge") kind = ccd::QueryKind::EdgeEdge;

  std::vector<ccd::QueryFile> files;
  try {
    for (const auto& path : expand_inputs(args.inputs)) files.push_back(ccd::read_query_file(path, kind));
  } catch (const ccd::QueryFileError& e) {
    std::cerr << "drape ccd: " << e.what() << "\n";
    return EXIT_BAD_INPUT;
  }
  const auto rows = ccd::evaluate_methods(files, settings);
  if (args.json) print_json(rows);
  else print_table(rows, settings.passes);
  return EXIT_OK;
}

}  // namespace

Command add_ccd_command(CLI::App& app) {
  auto args = std::make_shared<CcdArguments>();
  CLI::App* cmd = app.add_subcommand(
      "ccd",
      "Run the CCD methods on query files with ground truth and report misses, false alarms and speed.");
  cmd->footer(
      "Query files: the CSV format of the public CCD benchmark (tests/data/ccd-queries/FORMAT.md),\n"
      "8 rows a query, 7 integer columns. A file's kind comes from a parent folder named\n"
      "'vertex-face' or 'edge-edge', or from --kind. A folder argument means every .csv file below it.\n"
      "Results are summed over all files, per method and per kind.\n\n"
      "Methods:\n"
      "  cubic         all roots of the coplanarity cubic by a closed-form solver, no filter\n"
      "  dnf           cull when the Bernstein coefficients share one strict sign, else cubic\n"
      "  vincent       the algebraic filter: sign variations, bracketed root, subdivision\n"
      "  conservative  error-bounded; never misses a contact (may report near misses)\n\n"
      "Examples:\n"
      "  drape ccd tests/data/ccd-queries\n"
      "  drape ccd --method vincent --json tests/data/ccd-queries/unit-tests/edge-edge/data_0_0.csv\n"
      "  drape ccd --kind vertex-face my_queries.csv");
  cmd->add_option("files", args->inputs, "Query files or folders of them")->required()->check(CLI::ExistingPath);
  cmd->add_option("-m,--method", args->method, "Method to run, or 'all'")
      ->check(CLI::IsMember({"cubic", "dnf", "vincent", "conservative", "all"}))
      ->capture_default_str();
  cmd->add_option("-k,--kind", args->kind, "Kind of every file, overriding the folder names")
      ->check(CLI::IsMember({"vertex-face", "edge-edge"}));
  cmd->add_flag("--json", args->json,
                "Print one JSON array of objects with the keys method, kind, queries, positives, "
                "true_positives, false_negatives, false_positives, culled, ns_per_query");
  cmd->add_option("--passes", args->settings.passes, "Timed passes; the median is reported")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  auto& o = args->settings.options;
  cmd->add_option("--thickness", o.thickness, "Minimum separation counted as contact (scene units)")
      ->check(FINITE_NUMBER)
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--contact-tolerance", o.contact_tolerance,
                  "cubic/dnf/vincent: distance at a root counted as contact, relative to the query's extent")
      ->check(FINITE_NUMBER)
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--root-tolerance", o.root_tolerance, "Width at which a root bracket is final (step units)")
      ->check(FINITE_NUMBER)
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--max-subdivision-depth", o.max_subdivision_depth,
                  "vincent: subdivision levels before a tangential root is tested at its midpoint")
      ->check(CLI::Range(1, 60))
      ->capture_default_str();
  cmd->add_option("--separation-depth", o.separation_depth,
                  "vincent, conservative: halvings towards the cubic's roots before the separating-axis test "
                  "(0: the paper's filter alone; changes no answer, only the time)")
      ->check(CLI::Range(0, 6))
      ->capture_default_str();
  cmd->add_option("--time-tolerance", o.time_tolerance,
                  "conservative: interval width reported as contact when nothing excludes it (step units)")
      ->check(FINITE_NUMBER)
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--max-intervals", o.max_intervals,
                  "conservative: intervals examined before reporting a contact at the earliest left")
      ->check(CLI::Range(1, 1 << 24))
      ->capture_default_str();
  return [args] { return run_ccd(*args); };
}

}  // namespace drape::app
