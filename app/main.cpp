// drape: a cloth simulator built around a fast algebraic filter for continuous collision
// detection. This file only dispatches to the subcommands.
#include <iostream>
#include <map>

#include "commands.h"
#include "drape/core/linear_solver.h"

int main(int argc, char** argv) {
  drape::keep_freed_memory();
  CLI::App app{
      "drape: cloth simulation with continuous collision detection.\n"
      "Run 'drape <command> --help' for the options of a command.",
      "drape"};
  app.set_version_flag("--version", DRAPE_VERSION);
  app.require_subcommand(1);
  app.footer(
      "Exit status: 0 success, 1 a check found a problem, 2 bad input (flag, scene, mesh or\n"
      "query file), 3 a simulation had to stop or was interrupted (what it wrote is kept).\n\n"
      "Examples:\n"
      "  drape run scenes/drape_sphere.json             simulate; frames and stats.csv in out/drape_sphere\n"
      "  drape validate scenes/flag.json                check a scene without running it\n"
      "  drape check out/drape_sphere                   look for intersecting triangles in a run\n"
      "  drape render out/drape_sphere                  PNG frames and an MP4 of a finished run\n"
      "  drape check-stats out/flag/stats.csv golden.csv compare frame statistics\n"
      "  drape ccd tests/data/ccd-queries               compare the CCD methods on ground truth\n"
      "  drape sweep scenes/cloth_fold.json             time against accuracy over a grid of settings\n"
      "  drape batch runs.json                          a list of scene runs (mpirun -np 4 drape batch ...)\n"
      "  drape measure cusick out/cusick_drape          the Cusick drape coefficient and folds of a run");

  std::map<std::string, drape::app::Command> commands;
  commands["run"] = drape::app::add_run_command(app);
  commands["validate"] = drape::app::add_validate_command(app);
  commands["check"] = drape::app::add_check_command(app);
  commands["render"] = drape::app::add_render_command(app);
  commands["check-stats"] = drape::app::add_check_stats_command(app);
  commands["ccd"] = drape::app::add_ccd_command(app);
  commands["sweep"] = drape::app::add_sweep_command(app);
  commands["batch"] = drape::app::add_batch_command(app);
  commands["measure"] = drape::app::add_measure_command(app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int status = app.exit(e);
    return status == 0 ? drape::app::EXIT_OK : drape::app::EXIT_BAD_INPUT;
  }
  for (const auto& [name, command] : commands)
    if (app.got_subcommand(name)) return command();
  return drape::app::EXIT_OK;
}
