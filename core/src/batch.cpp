#include "drape/core/batch.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <map>

#include "drape/ccd/input_file.h"
#include "drape/core/fingerprint.h"
#include "drape/core/model.h"
#include "drape/core/output_file.h"
#include "drape/core/penetration.h"
#include "drape/core/run.h"

namespace drape {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

// The most frames a manifest may ask of one run.
constexpr int MAX_FRAMES = 1000000;

[[noreturn]] void fail(const fs::path& manifest, const std::string& place, const std::string& what) {
  throw BatchError(manifest.string() + ": " + place + ": " + what);
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

// One manifest entry's fields as text, before they are checked.
struct Entry {
  std::string place;  // "/runs/2" or "line 4"
  std::string scene, out, overrides;
  std::optional<json> frames;
};

std::vector<Entry> json_entries(const fs::path& manifest, const std::string& text) {
  json root;
  try {
    root = json::parse(text);
  } catch (const json::exception& e) {
    fail(manifest, "invalid JSON", e.what());
  }
  std::string prefix;
  if (root.is_object()) {
    for (const auto& [key, value] : root.items())
      if (key != "runs" && key != "comment") fail(manifest, "/" + key, "unknown key (expected runs)");
    if (!root.contains("runs")) fail(manifest, "/", "expected an object with \"runs\": [...] or an array of runs");
    root = json(root["runs"]);
    prefix = "/runs";
  }
  if (!root.is_array() || root.empty()) fail(manifest, prefix.empty() ? "/" : prefix, "expected a non-empty array of runs");
  std::vector<Entry> entries;
  for (std::size_t i = 0; i < root.size(); ++i) {
    const json& r = root[i];
    Entry e;
    e.place = prefix + "/" + std::to_string(i);
    if (!r.is_object()) fail(manifest, e.place, "expected an object {\"scene\", \"frames\", \"out\", \"overrides\"}");
    for (const auto& [key, value] : r.items())
      if (key != "scene" && key != "frames" && key != "out" && key != "overrides" && key != "comment")
        fail(manifest, e.place + "/" + key, "unknown key (expected one of: scene, frames, out, overrides)");
    if (!r.contains("scene") || !r["scene"].is_string() || r["scene"].get<std::string>().empty())
      fail(manifest, e.place + "/scene", "expected the scene file's path");
    e.scene = r["scene"];
    if (r.contains("out")) {
      if (!r["out"].is_string() || r["out"].get<std::string>().empty()) fail(manifest, e.place + "/out", "expected a folder's path");
      e.out = r["out"];
    }
    if (r.contains("frames")) e.frames = r["frames"];
    if (r.contains("overrides")) {
      if (!r["overrides"].is_object()) fail(manifest, e.place + "/overrides", "expected an object of scene keys");
      e.overrides = r["overrides"].dump();
    }
    entries.push_back(e);
  }
  return entries;
}

// One CSV record's fields: comma separated, a field in double quotes may hold commas and ""
// for a quote.
std::optional<std::vector<std::string>> csv_fields(const std::string& line) {
  std::vector<std::string> fields(1);
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') fields.back() += '"', ++i;
      else if (c == '"') quoted = false;
      else fields.back() += c;
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      fields.emplace_back();
    } else if (c != '\r') {
      fields.back() += c;
    }
  }
  if (quoted) return std::nullopt;
  return fields;
}

std::vector<Entry> csv_entries(const fs::path& manifest, const std::string& text) {
  std::vector<Entry> entries;
  std::vector<std::string> columns;
  std::size_t at = 0;
  for (int line_number = 1; at < text.size(); ++line_number) {
    const std::size_t end = std::min(text.find('\n', at), text.size());
    const std::string line = text.substr(at, end - at);
    at = end + 1;
    if (line.find_first_not_of(" \t\r") == std::string::npos || line[0] == '#') continue;
    const std::string place = "line " + std::to_string(line_number);
    const auto fields = csv_fields(line);
    if (!fields) fail(manifest, place, "a quoted field is not closed");
    if (columns.empty()) {
      for (const std::string& f : *fields) {
        const std::string name = lower(f);
        if (name != "scene" && name != "frames" && name != "out" && name != "overrides")
          fail(manifest, place, "unknown column '" + f + "' (expected a header of: scene, frames, out, overrides)");
        if (std::count(columns.begin(), columns.end(), name)) fail(manifest, place, "column '" + name + "' twice");
        columns.push_back(name);
      }
      if (!std::count(columns.begin(), columns.end(), "scene")) fail(manifest, place, "the header has no 'scene' column");
      continue;
    }
    if (fields->size() != columns.size())
      fail(manifest, place, "expected " + std::to_string(columns.size()) + " fields (" + std::to_string(fields->size()) + " found)");
    Entry e;
    e.place = place;
    for (std::size_t c = 0; c < columns.size(); ++c) {
      const std::string& v = (*fields)[c];
      if (columns[c] == "scene") e.scene = v;
      if (columns[c] == "out") e.out = v;
      if (columns[c] == "frames" && !v.empty()) {
        try {
          e.frames = json::parse(v);
        } catch (const json::exception&) {
          e.frames = json(v);  // reported as not an integer below
        }
      }
      if (columns[c] == "overrides" && !v.empty()) {
        json o;
        try {
          o = json::parse(v);
        } catch (const json::exception& x) {
          fail(manifest, place + ": column overrides", std::string("expected a JSON object: ") + x.what());
        }
        if (!o.is_object()) fail(manifest, place + ": column overrides", "expected a JSON object of scene keys");
        e.overrides = o.dump();
      }
    }
    if (e.scene.empty()) fail(manifest, place + ": column scene", "expected the scene file's path");
    entries.push_back(e);
  }
  if (entries.empty()) fail(manifest, "line 1", "expected a header and at least one run");
  return entries;
}

// A path without "." and ".." parts or a trailing separator.
fs::path normal(const fs::path& path) {
  fs::path p = path.lexically_normal();
  if (p.filename().empty() && p.has_parent_path()) p = p.parent_path();
  return p;
}

// Whether path lies strictly inside folder.
bool inside(const fs::path& path, const fs::path& folder) {
  const fs::path relative = path.lexically_relative(folder);
  return !relative.empty() && *relative.begin() != ".." && relative != ".";
}

fs::path record_path(const Batch& batch, std::size_t index) {
  char name[32];
  std::snprintf(name, sizeof name, "run_%05zu.json", index);
  return batch.out / "records" / name;
}

fs::path pending_path(const Batch& batch, std::size_t index) {
  fs::path path = record_path(batch, index);
  return path.replace_extension(".pending");
}

Scene load_with_overrides(const BatchRun& run);

// What a record must match to count for this batch's run: the scene file and the meshes it
// names (their bytes), the overrides, frames and folder, and the stats columns of this build.
json identity(const BatchRun& run) {
  std::string inputs;
  try {
    inputs = scene_fingerprint(load_with_overrides(run));
  } catch (const std::exception&) {
    // A scene that cannot be read names no meshes; its own bytes are in the identity.
  }
  return {{"scene", run.scene.string()}, {"scene_fingerprint", file_fingerprint(run.scene)}, {"inputs", inputs},
          {"overrides", run.overrides}, {"frames", run.frames}, {"out", run.out.string()}, {"stats_header", stats_header()}};
}

const char* status_name(BatchStatus s) {
  return s == BatchStatus::Ok ? "ok" : s == BatchStatus::BadInput ? "bad_input" : "stopped";
}

std::string last_line(const fs::path& path) {
  std::ifstream in(path);
  std::string line, last;
  std::getline(in, line);  // the header
  while (std::getline(in, line))
    if (!line.empty()) last = line;
  return last;
}

std::string csv_quote(std::string text) {
  std::string out = "\"";
  for (const char c : text) out += c == '"' ? std::string("\"\"") : std::string(1, c == '\n' ? ' ' : c);
  return out + "\"";
}

Scene load_with_overrides(const BatchRun& run) {
  // The scene must be valid by itself (its structure, keys and values, with the file's own
  // lines in any message); the overrides then apply to it.
  const Scene base = load_scene(run.scene);
  if (run.overrides.empty()) return base;
  json scene = json::parse(base.text);
  scene.merge_patch(json::parse(run.overrides));
  try {
    return parse_scene(scene.dump(2), run.scene);
  } catch (const SceneError& e) {
    throw SceneError(std::string(e.what()) + " (with the manifest's overrides " + run.overrides + ")");
  }
}

}  // namespace

Batch load_batch(const fs::path& manifest, const fs::path& out) {
  std::string text;
  try {
    text = ccd::read_input_file(manifest, ccd::MAX_SCENE_BYTES, "batch manifest");
  } catch (const ccd::InputFileError& e) {
    throw BatchError(e.what());
  }
  const std::vector<Entry> entries =
      lower(manifest.extension().string()) == ".csv" ? csv_entries(manifest, text) : json_entries(manifest, text);
  Batch batch;
  batch.manifest = manifest;
  batch.out = normal(out);
  const fs::path root = batch.out;
  std::map<fs::path, std::size_t> folders;
  for (std::size_t i = 0; i < entries.size(); ++i) {
    const Entry& e = entries[i];
    BatchRun run;
    run.scene = fs::path(e.scene).is_absolute() ? fs::path(e.scene) : manifest.parent_path() / e.scene;
    run.overrides = e.overrides;
    if (e.frames) {
      const json& f = *e.frames;
      if (!f.is_number_integer() || f.get<long long>() < 1 || f.get<long long>() > MAX_FRAMES)
        fail(manifest, e.place + (e.place[0] == '/' ? "/frames" : ": column frames"),
             "expected an integer from 1 to " + std::to_string(MAX_FRAMES) + ", found " + f.dump());
      run.frames = f.get<int>();
    }
    char name[32];
    std::snprintf(name, sizeof name, "%03zu_", i);
    run.out = e.out.empty() ? out / (name + run.scene.stem().string()) : fs::path(e.out).is_absolute() ? fs::path(e.out) : out / e.out;
    run.out = normal(run.out);
    if (run.out.extension() == ".partial")
      fail(manifest, e.place, "out " + run.out.string() + " ends in .partial, drape's name for a run not finished; give another out");
    if (run.out == root || run.out == root / "records" || run.out == root / "batch.csv" || inside(root, run.out))
      fail(manifest, e.place, "out " + run.out.string() + " is or holds the batch's own folder " + root.string() +
                                  "; give a folder inside it, or elsewhere");
    if (const auto [it, fresh] = folders.emplace(run.out, i); !fresh)
      fail(manifest, e.place, "writes to " + run.out.string() + " as run " + std::to_string(it->second) + " does; give another out");
    batch.runs.push_back(run);
  }
  // No run's folder inside another's: removing or renaming one would touch the other.
  for (std::size_t i = 0; i < batch.runs.size(); ++i)
    for (fs::path up = batch.runs[i].out.parent_path(); !up.empty() && up != up.parent_path(); up = up.parent_path())
      if (const auto it = folders.find(up); it != folders.end())
        fail(manifest, entries[i].place, "out " + batch.runs[i].out.string() + " is inside run " + std::to_string(it->second) +
                                             "'s folder " + up.string() + "; give folders apart");
  return batch;
}

double estimated_cost(const BatchRun& run) {
  try {
    const Model model = build_model(load_with_overrides(run));
    const int frames = run.frames > 0 ? run.frames : model.scene.frames;
    return double(model.vertex_count()) * frames * model.scene.frame_steps;
  } catch (const std::exception&) {
    return 0;
  }
}

std::optional<BatchResult> completed_batch_run(const Batch& batch, std::size_t index, bool retryable_too) {
  std::ifstream in(record_path(batch, index));
  if (!in) return std::nullopt;
  json record;
  try {
    in >> record;
    if (record.at("identity") != identity(batch.runs[index])) return std::nullopt;
    if (!record.at("final").get<bool>() && !retryable_too) return std::nullopt;
    BatchResult r;
    r.index = index;
    r.status = BatchStatus(record.at("exit_status").get<int>());
    r.message = record.at("message");
    r.frames_done = record.at("frames");
    r.wall_s = record.at("wall_s");
    r.last_stats = record.at("last_stats");
    // A run that ended with frames has its folder: gone, the run is redone.
    if (r.status != BatchStatus::BadInput && !fs::exists(stats_path(batch.runs[index].out))) return std::nullopt;
    return r;
  } catch (const std::exception&) {
    return std::nullopt;  // unreadable or from another version: redone
  }
}

std::optional<BatchResult> run_batch_run(const Batch& batch, std::size_t index, int threads, const std::atomic<bool>& interrupt) {
  const BatchRun& run = batch.runs[index];
  const json id = identity(run);
  const fs::path record = record_path(batch, index), pending = pending_path(batch, index);
  const fs::path partial = fs::path(run.out.string() + ".partial");
  BatchResult result;
  result.index = index;
  const auto begin = std::chrono::steady_clock::now();
  // The outcome, recorded. final: the same run would end the same way (a bad scene, a stop);
  // not final: something outside the scene got in the way (the folder, the disk), and a
  // batch started again runs it again.
  const auto finish = [&](BatchStatus status, const std::string& message, bool final) {
    result.status = status;
    result.message = message;
    result.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
    const json r = {{"identity", id},          {"status", status_name(status)}, {"exit_status", int(status)},
                    {"message", message},      {"frames", result.frames_done},  {"wall_s", result.wall_s},
                    {"last_stats", result.last_stats}, {"final", final}};
    try {
      write_file_atomically(record, r.dump(2) + "\n");
      std::error_code ignored;
      fs::remove(pending, ignored);
    } catch (const std::exception& e) {
      result.message += std::string(result.message.empty() ? "" : "; ") + "its record could not be written: " + e.what();
    }
    return result;
  };
  try {
    std::error_code error;
    fs::create_directories(record.parent_path(), error);
    // Whether this batch made the run's folders before: a record or a pending mark of it.
    const bool ours = fs::exists(record) || fs::exists(pending);
    fs::remove(record, error);
    write_file_atomically(pending, run.out.string() + "\n");
    const Model model = build_model(load_with_overrides(run));
    if (const StartCheck start = check_start(model); !start.error.empty()) throw SceneError(start.error);
    // An earlier folder of this run (its record lost when a job was killed) is replaced; one
    // this batch did not make, or holding anything drape did not write, is left alone.
    if (fs::exists(run.out)) {
      if (!ours)
        throw RunSetupError(run.out.string() + ": the folder exists and this batch did not make it; move it, or give the run "
                                               "another out");
      remove_run_folder(run.out);
    }
    if (fs::exists(partial)) remove_run_folder(partial);
    RunSettings settings;
    settings.out = partial;
    settings.frames = run.frames > 0 ? run.frames : model.scene.frames;
    settings.write_meshes = model.scene.output.meshes;
    settings.threads = threads;
    const RunOutcome outcome = run_simulation(model, settings, interrupt, {});
    if (outcome.end == RunEnd::Interrupted) return std::nullopt;
    fs::rename(partial, run.out, error);
    if (error) throw RunSetupError(run.out.string() + ": cannot move the finished run into place: " + error.message());
    result.frames_done = outcome.frames_done;
    result.last_stats = last_line(stats_path(run.out));
    if (outcome.end == RunEnd::Stopped) return finish(BatchStatus::Stopped, outcome.message, true);
    return finish(BatchStatus::Ok, "", true);
  } catch (const SceneError& e) {
    return finish(BatchStatus::BadInput, e.what(), true);
  } catch (const RunSetupError& e) {
    return finish(BatchStatus::BadInput, e.what(), false);
  } catch (const std::exception& e) {  // a file system or output error
    return finish(BatchStatus::Stopped, e.what(), false);
  }
}

std::string batch_csv_header() { return "index,scene,out,status,exit_status,frames,wall_s,message," + stats_header(); }

void write_batch_csv(const fs::path& path, const Batch& batch, const std::vector<BatchResult>& results) {
  const std::string stats = stats_header();
  const std::size_t stats_columns = std::count(stats.begin(), stats.end(), ',') + 1;
  std::string text = batch_csv_header() + "\n";
  for (const BatchResult& r : results) {
    const BatchRun& run = batch.runs[r.index];
    // The folder relative to the batch's when inside it: tables of two batch folders compare.
    const fs::path relative = run.out.lexically_relative(batch.out);
    const fs::path shown = !relative.empty() && *relative.begin() != ".." ? relative : run.out;
    char numbers[96];
    std::snprintf(numbers, sizeof numbers, "%s,%d,%d,%.3f,", status_name(r.status), int(r.status), r.frames_done, r.wall_s);
    text += std::to_string(r.index) + "," + csv_quote(run.scene.string()) + "," + csv_quote(shown.string()) + "," + numbers +
            (r.message.empty() ? "" : csv_quote(r.message)) + "," +
            (r.last_stats.empty() ? std::string(stats_columns - 1, ',') : r.last_stats) + "\n";
  }
  write_file_atomically(path, text);
}

}  // namespace drape
