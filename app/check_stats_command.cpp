// drape check-stats: a run's frame statistics against a golden file.
#include <iostream>

#include "commands.h"
#include "drape/core/run.h"
#include "drape/core/stats_compare.h"

namespace drape::app {

Command add_check_stats_command(CLI::App& app) {
  auto paths = std::make_shared<std::pair<std::string, std::string>>();
  CLI::App* cmd = app.add_subcommand("check-stats", "Compare a run's stats.csv with a golden one, column by column.");
  std::string footer = "Prints the first frame and column that differ beyond tolerance; exit status 1 then.\nTolerances:\n";
  for (const auto& [column, t] : stats_tolerances()) {
    char line[160];
    if (t.ignore) std::snprintf(line, sizeof line, "  %-22s ignored (a timing)\n", column.c_str());
    else std::snprintf(line, sizeof line, "  %-22s %g absolute + %g relative\n", column.c_str(), t.absolute, t.relative);
    footer += line;
  }
  char line[160];
  std::snprintf(line, sizeof line, "  %-22s %g absolute + %g relative\n", "(any other)", default_tolerance().absolute,
                default_tolerance().relative);
  cmd->footer(footer + line);
  cmd->add_option("run", paths->first, "A run's stats.csv, or its output folder")->required()->check(CLI::ExistingPath);
  cmd->add_option("golden", paths->second, "The golden stats.csv, or a folder holding one")->required()->check(CLI::ExistingPath);
  return [paths] {
    const auto resolve = [](const std::filesystem::path& p) {
      return std::filesystem::is_directory(p) ? stats_path(p) : p;
    };
    try {
      const auto difference = compare_stats(resolve(paths->first), resolve(paths->second));
      if (difference) {
        std::cout << "differs: " << difference->message << "\n";
        return EXIT_CHECK_FAILED;
      }
    } catch (const std::exception& e) {
      std::cerr << "drape check-stats: " << e.what() << "\n";
      return EXIT_BAD_INPUT;
    }
    std::cout << "same within tolerance\n";
    return EXIT_OK;
  };
}

}  // namespace drape::app
