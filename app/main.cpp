// drape: a cloth simulator built around a fast algebraic filter for continuous collision
// detection. This file only dispatches to the subcommands.
#include <iostream>

#include "commands.h"
#include "drape/core/version.h"

int main(int argc, char** argv) {
  CLI::App app{
      "drape: cloth simulation with continuous collision detection.\n"
      "Run 'drape <command> --help' for the options of a command.",
      "drape"};
  app.set_version_flag("--version", std::string(drape::version()));
  app.require_subcommand(1);
  app.footer(
      "Exit status: 0 success, 1 a check found a problem, 2 bad input (flag, scene, mesh or\n"
      "query file), 3 a simulation had to stop.\n\n"
      "Example:\n"
      "  drape ccd --method all tests/data/ccd-queries   compare the CCD methods on ground truth");

  const auto ccd = drape::app::add_ccd_command(app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int status = app.exit(e);
    return status == 0 ? drape::app::EXIT_OK : drape::app::EXIT_BAD_INPUT;
  }
  try {
    if (app.got_subcommand("ccd")) return ccd();
  } catch (const std::exception& e) {
    std::cerr << "drape: " << e.what() << "\n";
    return drape::app::EXIT_BAD_INPUT;
  }
  return drape::app::EXIT_OK;
}
