#include "drape/ccd/input_file.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <system_error>

namespace drape::ccd {

std::string format_bytes(std::uintmax_t bytes) {
  char text[32];
  if (bytes < 1024) std::snprintf(text, sizeof text, "%ju bytes", bytes);
  else if (bytes < (std::uintmax_t(1) << 20)) std::snprintf(text, sizeof text, "%.3g KiB", double(bytes) / 1024);
  else if (bytes < (std::uintmax_t(1) << 30)) std::snprintf(text, sizeof text, "%.3g MiB", double(bytes) / (1 << 20));
  else std::snprintf(text, sizeof text, "%.3g GiB", double(bytes) / (1 << 30));
  return text;
}

void check_input_file(const std::filesystem::path& path, std::uintmax_t max_bytes, const std::string& what) {
  // status() follows symlinks; with an error_code a loop or a permission problem is a
  // message, not an uncaught filesystem_error.
  std::error_code error;
  const std::filesystem::file_status status = std::filesystem::status(path, error);
  if (error && status.type() != std::filesystem::file_type::not_found)
    throw InputFileError(path.string() + ": cannot read the " + what + ": " + error.message());
  switch (status.type()) {
    case std::filesystem::file_type::regular: break;
    case std::filesystem::file_type::not_found: throw InputFileError(path.string() + ": no such " + what);
    case std::filesystem::file_type::directory:
      throw InputFileError(path.string() + ": expected a " + what + ", found a folder");
    default: throw InputFileError(path.string() + ": expected a " + what + ", found a device, pipe or socket");
  }
  const std::uintmax_t size = std::filesystem::file_size(path, error);
  if (error) throw InputFileError(path.string() + ": cannot read the " + what + ": " + error.message());
  if (size > max_bytes)
    throw InputFileError(path.string() + ": the " + what + " is " + format_bytes(size) + ", larger than the " +
                         format_bytes(max_bytes) + " drape reads");
}

std::string read_input_file(const std::filesystem::path& path, std::uintmax_t max_bytes, const std::string& what) {
  check_input_file(path, max_bytes, what);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputFileError(path.string() + ": cannot open the " + what);
  std::string bytes;
  // Never more than the limit, even if the file grew since it was checked.
  std::error_code error;
  const std::uintmax_t size = std::filesystem::file_size(path, error);
  if (!error) bytes.reserve(std::size_t(std::min(size, max_bytes)));
  char buffer[1 << 16];
  while (in.read(buffer, sizeof buffer) || in.gcount() > 0) {
    bytes.append(buffer, std::size_t(in.gcount()));
    if (bytes.size() > max_bytes)
      throw InputFileError(path.string() + ": the " + what + " grew beyond " + format_bytes(max_bytes) + " while read");
  }
  if (in.bad()) throw InputFileError(path.string() + ": cannot read the " + what);
  return bytes;
}

}  // namespace drape::ccd
