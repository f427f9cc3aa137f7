#pragma once
/// \file
/// The subcommands of the drape program. Each registers its options on the CLI11 app and
/// returns the function that runs it; the function returns the process exit status.

#include <CLI/CLI.hpp>
#include <functional>

namespace drape::app {

/// Exit statuses shared by all commands.
inline constexpr int EXIT_OK = 0;
inline constexpr int EXIT_CHECK_FAILED = 1;  ///< the command ran and found a problem
inline constexpr int EXIT_BAD_INPUT = 2;     ///< a flag, scene, mesh or query file is malformed
inline constexpr int EXIT_RUN_STOPPED = 3;   ///< a simulation had to stop (or was interrupted)

using Command = std::function<int()>;

Command add_ccd_command(CLI::App& app);
Command add_run_command(CLI::App& app);
Command add_validate_command(CLI::App& app);
Command add_check_stats_command(CLI::App& app);
Command add_check_command(CLI::App& app);

}  // namespace drape::app
