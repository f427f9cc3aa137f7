#include "drape/core/stats_compare.h"

#include "drape/ccd/input_file.h"

#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace drape {

const std::map<std::string, ColumnTolerance>& stats_tolerances() {
  static const std::map<std::string, ColumnTolerance> tolerances = [] {
    std::map<std::string, ColumnTolerance> out;
    for (const StatsColumn& c : stats_columns())
      if (c.tolerance.ignore || c.tolerance.absolute != DEFAULT_TOLERANCE.absolute ||
          c.tolerance.relative != DEFAULT_TOLERANCE.relative)
        out[c.name] = c.tolerance;
    return out;
  }();
  return tolerances;
}

ColumnTolerance default_tolerance() { return DEFAULT_TOLERANCE; }

namespace {

std::vector<std::vector<std::string>> read_csv(const std::filesystem::path& path) {
  std::stringstream in;
  try {
    in.str(ccd::read_input_file(path, ccd::MAX_MESH_BYTES, "statistics file"));
  } catch (const ccd::InputFileError& e) {
    throw std::runtime_error(e.what());
  }
  std::vector<std::vector<std::string>> rows;
  std::size_t line_number = 0;
  for (std::string line; std::getline(in, line);) {
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    std::vector<std::string> cells;
    std::stringstream stream(line);
    for (std::string cell; std::getline(stream, cell, ',');) cells.push_back(cell);
    if (line.back() == ',') cells.emplace_back();
    // A row shorter or longer than the header is a damaged file, not a row of empty values.
    if (!rows.empty() && cells.size() != rows[0].size())
      throw std::runtime_error(path.string() + ": line " + std::to_string(line_number) + ": expected " +
                               std::to_string(rows[0].size()) + " comma-separated cells as in the header, found " +
                               std::to_string(cells.size()));
    rows.push_back(cells);
  }
  if (rows.empty()) throw std::runtime_error(path.string() + ": the statistics file is empty");
  return rows;
}

std::string describe(const ColumnTolerance& t) {
  std::ostringstream out;
  if (t.absolute == 0 && t.relative == 0) return "exact";
  out << "tolerance " << t.absolute << " absolute + " << t.relative << " relative";
  return out.str();
}

}  // namespace

std::optional<StatsDifference> compare_stats(const std::filesystem::path& run, const std::filesystem::path& golden) {
  const auto a = read_csv(run);
  const auto b = read_csv(golden);
  if (a[0] != b[0]) {
    StatsDifference d;
    d.row = -1;
    d.message = "the columns differ: run has '" + a[0].front() + "...' (" + std::to_string(a[0].size()) +
                " columns), golden has " + std::to_string(b[0].size()) + " columns";
    for (std::size_t c = 0; c < std::min(a[0].size(), b[0].size()); ++c) {
      if (a[0][c] != b[0][c]) {
        d.column = b[0][c];
        d.message = "column " + std::to_string(c + 1) + " is '" + a[0][c] + "' in the run and '" + b[0][c] + "' in the golden file";
        break;
      }
    }
    return d;
  }
  const auto& header = a[0];
  const std::size_t rows = std::min(a.size(), b.size());
  for (std::size_t r = 1; r < rows; ++r) {
    for (std::size_t c = 0; c < header.size(); ++c) {
      const auto it = stats_tolerances().find(header[c]);
      const ColumnTolerance tol = it != stats_tolerances().end() ? it->second : default_tolerance();
      if (tol.ignore) continue;
      const std::string x = c < a[r].size() ? a[r][c] : "", y = c < b[r].size() ? b[r][c] : "";
      bool same = x == y;
      if (!same && !x.empty() && !y.empty()) {
        char* end_x = nullptr;
        char* end_y = nullptr;
        const double u = std::strtod(x.c_str(), &end_x), v = std::strtod(y.c_str(), &end_y);
        if (*end_x == '\0' && *end_y == '\0')
          same = std::abs(u - v) <= tol.absolute + tol.relative * std::max(std::abs(u), std::abs(v));
      }
      if (!same) {
        StatsDifference d;
        d.row = int(r - 1);
        d.frame = a[r].empty() ? "" : a[r][0];
        d.column = header[c];
        d.run_value = x;
        d.golden_value = y;
        d.message = "frame " + d.frame + ", column " + d.column + ": run " + (x.empty() ? "(empty)" : x) + ", golden " +
                    (y.empty() ? "(empty)" : y) + " (" + describe(tol) + ")";
        return d;
      }
    }
  }
  if (a.size() != b.size()) {
    StatsDifference d;
    d.row = -1;
    d.message = "the run has " + std::to_string(a.size() - 1) + " frame rows, the golden file " + std::to_string(b.size() - 1);
    return d;
  }
  return std::nullopt;
}

}  // namespace drape
