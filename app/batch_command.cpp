// drape batch: a manifest's runs, each into its own folder, across MPI ranks when started by
// mpirun or srun (core/batch.h, ranks.h).
#include <algorithm>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <iostream>

#include "commands.h"
#include "drape/core/batch.h"
#include "ranks.h"

namespace drape::app {
namespace {

std::atomic<bool> batch_interrupted{false};
extern "C" void on_batch_interrupt(int) { batch_interrupted.store(true); }

struct BatchArguments {
  std::string manifest;
  std::string out;
  int threads = 1;
  bool quiet = false;
};

const char* status_word(BatchStatus s) {
  return s == BatchStatus::Ok ? "ok" : s == BatchStatus::BadInput ? "bad input" : "stopped";
}

int batch(const BatchArguments& args, const Ranks& ranks) {
  const std::filesystem::path manifest = args.manifest;
  const std::filesystem::path out =
      args.out.empty() ? std::filesystem::path("out") / manifest.stem() : std::filesystem::path(args.out);
  Batch batch;
  try {  // every rank reads the manifest; they all fail alike
    batch = load_batch(manifest, out);
  } catch (const BatchError& e) {
    if (ranks.rank() == 0) std::cerr << "drape batch: " << e.what() << "\n";
    return EXIT_BAD_INPUT;
  }
  std::vector<std::size_t> pending;
  if (ranks.rank() == 0) {
    if (const std::string why = claim_output_folder(out, "batch.lock"); !why.empty()) {
      std::cerr << "drape batch: " << why << "\n";
      return ranks.broadcast(EXIT_BAD_INPUT);
    }
    std::size_t skipped = 0;
    for (std::size_t i = 0; i < batch.runs.size(); ++i) {
      if (completed_batch_run(batch, i)) {
        ++skipped;
        if (!args.quiet) std::printf("run %zu (%s): complete already, skipped\n", i, batch.runs[i].out.string().c_str());
      } else {
        pending.push_back(i);
      }
    }
    // The longest first: handed out in that order, the last runs to finish are short ones.
    std::vector<double> cost(batch.runs.size(), 0);
    for (const std::size_t i : pending) cost[i] = estimated_cost(batch.runs[i]);
    std::stable_sort(pending.begin(), pending.end(), [&](std::size_t a, std::size_t b) { return cost[a] > cost[b]; });
    std::printf("drape batch %s: %zu runs, %zu complete already, %zu to run on %d %s; output in %s/\n",
                manifest.string().c_str(), batch.runs.size(), skipped, pending.size(), ranks.size(),
                ranks.size() == 1 ? "process" : "MPI ranks", out.string().c_str());
    std::fflush(stdout);
  }
  if (ranks.broadcast(EXIT_OK) != EXIT_OK) return EXIT_BAD_INPUT;  // rank 0 could not start

  std::signal(SIGINT, on_batch_interrupt);
  std::signal(SIGTERM, on_batch_interrupt);
  ranks.run(pending, [&](std::size_t i) {
    const std::optional<BatchResult> r = run_batch_run(batch, i, args.threads, batch_interrupted);
    if (!r) return false;
    if (!args.quiet) {
      std::printf("%srun %zu (%s): %s, %d frames, %.1f s%s%s\n", ranks.prefix().c_str(), i,
                  batch.runs[i].scene.filename().string().c_str(), status_word(r->status), r->frames_done, r->wall_s,
                  r->message.empty() ? "" : ": ", r->message.c_str());
      std::fflush(stdout);
    }
    return true;
  });

  int status = EXIT_OK;
  if (ranks.rank() == 0) {
    // Rank 0 gathers the records of every run, those of an earlier start included.
    std::vector<BatchResult> results;
    std::size_t failed = 0;
    for (std::size_t i = 0; i < batch.runs.size(); ++i)
      if (const auto r = completed_batch_run(batch, i, true)) {
        results.push_back(*r);
        failed += r->status != BatchStatus::Ok;
      }
    const std::filesystem::path table = out / "batch.csv";
    try {
      write_batch_csv(table, batch, results);
    } catch (const std::exception& e) {
      std::cerr << "drape batch: " << e.what() << "\n";
      return ranks.broadcast(EXIT_RUN_STOPPED);
    }
    const std::size_t missing = batch.runs.size() - results.size();
    std::printf("drape batch: %zu of %zu runs done, %zu failed (bad input or stopped); table: %s\n", results.size(),
                batch.runs.size(), failed, table.string().c_str());
    if (missing > 0) {
      std::cerr << "drape batch: interrupted: " << missing
                << " runs not done; start the same command again to run only those\n";
      status = EXIT_RUN_STOPPED;
    } else if (failed > 0) {
      status = EXIT_CHECK_FAILED;
    }
  }
  return ranks.broadcast(status);
}

}  // namespace

Command add_batch_command(CLI::App& app) {
  auto args = std::make_shared<BatchArguments>();
  CLI::App* cmd = app.add_subcommand(
      "batch", "Run a list of scenes, each into its own folder, across MPI ranks when started by mpirun or srun.");
  cmd->add_option("manifest", args->manifest, "The runs: a JSON or CSV file (below)")->required()->check(EXISTING_FILE);
  cmd->add_option("--out", args->out, "The batch's folder: batch.csv, records/, and runs without their own out (default out/<manifest name>)");
  cmd->add_option("--threads", args->threads, "Threads per run (narrow phase, projective solver)")->capture_default_str()->check(CLI::Range(1, 256));
  cmd->add_flag("-q,--quiet", args->quiet, "Print only the summary and errors");
  cmd->footer(
      "Manifest, JSON:\n"
      "  {\"runs\": [{\"scene\": \"scenes/hanging.json\", \"frames\": 30},\n"
      "            {\"scene\": \"scenes/flag.json\", \"out\": \"flag_stiff\", \"overrides\": {\"frame_steps\": 20}}]}\n"
      "or CSV with a header, the overrides as a quoted JSON object:\n"
      "  scene,frames,out,overrides\n"
      "  scenes/hanging.json,30,,\n"
      "  scenes/flag.json,,flag_stiff,\"{\"\"frame_steps\"\": 20}\"\n"
      "Scene paths are relative to the manifest's folder, out folders to the batch's (default\n"
      "NNN_<scene name>); overrides are merged into the scene (RFC 7386). Each run is written\n"
      "into FOLDER.partial and renamed into place when it ends, then recorded in records/.\n"
      "batch.csv has a row per run: status (ok, bad_input, stopped), frames, wall time, message\n"
      "and the run's last stats.csv row.\n\n"
      "Started again on the same output, the runs recorded already (same scene and mesh bytes,\n"
      "overrides, frames, folder) are skipped and the others run from scratch. A run that fails\n"
      "is recorded and the others go on. A batch replaces only run folders it made itself.\n\n"
      "Exit status: 0 every run ok, 1 some failed, 2 a bad manifest, 3 interrupted.\n\n"
      "Examples:\n"
      "  drape batch runs.json\n"
      "  mpirun -np 4 drape batch runs.json --out out/runs    (as root add --allow-run-as-root)\n"
      "  srun -n 64 drape batch runs.json                      (in a Slurm job script)");
  return [args] {
    try {
      const Ranks ranks;
      return batch(*args, ranks);
    } catch (const std::runtime_error& e) {
      std::cerr << "drape batch: " << e.what() << "\n";
      return EXIT_BAD_INPUT;
    }
  };
}

}  // namespace drape::app
