#include "drape/ccd_eval/query_file.h"

#include "drape/ccd/input_file.h"

#include <gmpxx.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace drape::ccd {
namespace {

constexpr int COLUMNS = 7;
constexpr int ROWS_PER_QUERY = 8;

[[noreturn]] void fail(const std::filesystem::path& path, std::size_t line, const std::string& what) {
  std::ostringstream message;
  message << path.string() << ":" << line << ": " << what;
  throw QueryFileError(message.str());
}

std::string trim(const std::string& s) {
  const auto first = s.find_first_not_of(" \t\r");
  if (first == std::string::npos) return {};
  const auto last = s.find_last_not_of(" \t\r");
  return s.substr(first, last - first + 1);
}

bool is_integer(const std::string& s) {
  std::size_t i = (!s.empty() && (s[0] == '-' || s[0] == '+')) ? 1 : 0;
  if (i == s.size()) return false;
  for (; i < s.size(); ++i)
    if (s[i] < '0' || s[i] > '9') return false;
  return true;
}

mpz_class parse_integer(const std::string& text, const std::filesystem::path& path, std::size_t line, int column) {
  if (!is_integer(text))
    fail(path, line, "column " + std::to_string(column) + ": expected an integer, found '" + text + "'");
  mpz_class value;
  value.set_str(text[0] == '+' ? text.substr(1) : text, 10);
  return value;
}

// The double nearest to q (mpq_get_d truncates toward zero).
double nearest_double(const mpq_class& q) {
  const double truncated = q.get_d();
  if (!std::isfinite(truncated) || mpq_class(truncated) == q) return truncated;
  const double away = std::nextafter(truncated, q > 0 ? HUGE_VAL : -HUGE_VAL);
  const mpq_class error_truncated = abs(q - mpq_class(truncated));
  return std::isfinite(away) && abs(mpq_class(away) - q) < error_truncated ? away : truncated;
}

}  // namespace

std::optional<QueryKind> kind_from_path(const std::filesystem::path& path) {
  for (auto p = path.parent_path(); !p.empty() && p != p.parent_path(); p = p.parent_path()) {
    const auto name = p.filename().string();
    if (name == "vertex-face") return QueryKind::VertexFace;
    if (name == "edge-edge") return QueryKind::EdgeEdge;
  }
  return std::nullopt;
}

QueryFile read_query_file(const std::filesystem::path& path, std::optional<QueryKind> kind_override) {
  QueryFile file;
  file.path = path;
  const auto kind = kind_override ? kind_override : kind_from_path(path);
  if (!kind)
    throw QueryFileError(path.string() +
                         ": cannot tell the query kind: no parent folder is named 'vertex-face' or 'edge-edge' (give --kind)");
  file.kind = *kind;

  std::string text;
  try {
    text = read_input_file(path, MAX_QUERY_BYTES, "query file");
  } catch (const InputFileError& e) {
    throw QueryFileError(e.what());
  }
  return parse_query_text(text, path, file.kind);
}

QueryFile parse_query_text(const std::string& text, const std::filesystem::path& path, QueryKind kind) {
  QueryFile file;
  file.path = path;
  file.kind = kind;
  std::vector<std::string> lines;
  std::stringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(trim(line));
  while (!lines.empty() && lines.back().empty()) lines.pop_back();  // trailing blank lines
  if (lines.empty()) fail(path, 1, "the file is empty; expected 8 rows per query");

  Query query;
  bool query_truth = false;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const std::size_t line_number = i + 1;
    const std::string& line = lines[i];
    if (line.empty()) fail(path, line_number, "empty line; expected 7 comma-separated integers");
    std::vector<std::string> fields;
    std::stringstream stream(line);
    for (std::string field; std::getline(stream, field, ',');) fields.push_back(trim(field));
    if (line.back() == ',') fields.emplace_back();
    if (fields.size() != COLUMNS)
      fail(path, line_number,
           "expected 7 comma-separated integers (x_num, x_den, y_num, y_den, z_num, z_den, truth), found " +
               std::to_string(fields.size()) + " columns");
    Vec3 point;
    for (int axis = 0; axis < 3; ++axis) {
      const mpz_class numerator = parse_integer(fields[2 * axis], path, line_number, 2 * axis + 1);
      const mpz_class denominator = parse_integer(fields[2 * axis + 1], path, line_number, 2 * axis + 2);
      if (denominator == 0) fail(path, line_number, "column " + std::to_string(2 * axis + 2) + ": zero denominator");
      mpq_class value(numerator, denominator);
      value.canonicalize();
      point[axis] = nearest_double(value);
      if (!std::isfinite(point[axis]))
        fail(path, line_number, "column " + std::to_string(2 * axis + 1) + ": value out of the range of a double");
      if (std::abs(point[axis]) > MAX_QUERY_COORDINATE) {
        char found[32];
        std::snprintf(found, sizeof found, "%.3g", point[axis]);
        fail(path, line_number,
             "column " + std::to_string(2 * axis + 1) + ": expected a coordinate within +-1e90 (the cubic's coefficients, " +
                 "products of three coordinates, would overflow a double), found about " + found);
      }
      if (point[axis] == 0 && value != 0)
        fail(path, line_number,
             "column " + std::to_string(2 * axis + 2) + ": the value is too small for a double (it rounds to 0); expected a "
                                                         "denominator that leaves it representable");
    }
    const mpz_class truth = parse_integer(fields[6], path, line_number, 7);
    if (truth != 0 && truth != 1) fail(path, line_number, "column 7: expected the truth value 0 or 1");

    const std::size_t row = i % ROWS_PER_QUERY;
    if (row == 0) query_truth = truth == 1;
    else if (query_truth != (truth == 1))
      fail(path, line_number, "column 7: the 8 rows of a query must share one truth value");
    (row < 4 ? query.start[row] : query.end[row - 4]) = point;
    if (row == ROWS_PER_QUERY - 1) {
      file.queries.push_back(query);
      file.truth.push_back(query_truth);
    }
  }
  if (lines.size() % ROWS_PER_QUERY != 0)
    fail(path, lines.size(),
         "the file has " + std::to_string(lines.size()) + " rows, not a multiple of 8 (8 rows per query)");
  return file;
}

std::string format_query_text(const QueryFile& file) {
  std::string text;
  const auto append_row = [&](const Vec3& point, bool truth) {
    for (int axis = 0; axis < 3; ++axis) {
      const mpq_class value(point[axis]);  // exact: every finite double is a dyadic rational
      text += value.get_num().get_str();
      text += ',';
      text += value.get_den().get_str();
      text += ',';
    }
    text += truth ? "1\n" : "0\n";
  };
  for (std::size_t q = 0; q < file.queries.size(); ++q) {
    const bool truth = q < file.truth.size() && file.truth[q];
    for (const Vec3& p : file.queries[q].start) append_row(p, truth);
    for (const Vec3& p : file.queries[q].end) append_row(p, truth);
  }
  return text;
}

void write_query_file(const std::filesystem::path& path, const QueryFile& file) {
  std::filesystem::path temporary = path;
  temporary += ".partial";
  {
    std::ofstream out(temporary, std::ios::binary);
    out << format_query_text(file);
    if (!out.flush()) fail(path, 0, "cannot write the file");
  }
  std::error_code error;
  std::filesystem::rename(temporary, path, error);
  if (error) fail(path, 0, "cannot write the file: " + error.message());
}

}  // namespace drape::ccd
