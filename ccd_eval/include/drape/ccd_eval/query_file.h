#pragma once
/// \file
/// Reading and writing CCD query files in the public benchmark's CSV format.
///
/// Query files in the public CSV format of the CCD benchmark (tests/data/ccd-queries/FORMAT.md):
/// 8 rows a query, 7 integer columns x_num, x_den, y_num, y_den, z_num, z_den, truth.

#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "drape/ccd/query.h"

namespace drape::ccd {

/// A malformed or unreadable query file. what() names the file, the line and what was expected.
class QueryFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct QueryFile {
  std::filesystem::path path;
  QueryKind kind = QueryKind::VertexFace;
  std::vector<Query> queries;
  std::vector<bool> truth;  ///< ground truth of each query: the exact trajectories touch
};

/// The largest coordinate a query file may hold: the coplanarity cubic's coefficients are
/// products of three coordinate differences, which overflow a double beyond about 1e100 (a
/// contact of the public set scaled by 1e105 was missed by every method but the conservative
/// one). A coordinate beyond it, or a non-zero one that rounds to zero, is refused.
inline constexpr double MAX_QUERY_COORDINATE = 1e90;

/// The kind named by the nearest parent folder called "vertex-face" or "edge-edge".
std::optional<QueryKind> kind_from_path(const std::filesystem::path& path);

/// Reads and validates a query file. The kind is kind_override when given, else the path's.
/// Numbers may exceed 64 bits; each rational is rounded to the nearest double (the public
/// files hold only exactly representable values). Throws QueryFileError.
QueryFile read_query_file(const std::filesystem::path& path, std::optional<QueryKind> kind_override = std::nullopt);

/// The same from the file's text; path names it in messages. Throws QueryFileError.
QueryFile parse_query_text(const std::string& text, const std::filesystem::path& path, QueryKind kind);

/// The file's queries as text in the same format, each coordinate written as the exact
/// rational of its double (parse_query_text gives back the same doubles).
std::string format_query_text(const QueryFile& file);

/// Writes format_query_text(file) to path (through a temporary file renamed into place).
/// Throws QueryFileError when it cannot be written.
void write_query_file(const std::filesystem::path& path, const QueryFile& file);

}  // namespace drape::ccd
