// libFuzzer target: query-file text -> the query-file parser. Bad input must end in a
// QueryFileError, never a crash or another exception.
#include <cstdint>
#include <string>

#include "drape/ccd_eval/query_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    drape::ccd::parse_query_text(text, "fuzz.csv", drape::ccd::QueryKind::VertexFace);
  } catch (const drape::ccd::QueryFileError&) {
  }
  return 0;
}
