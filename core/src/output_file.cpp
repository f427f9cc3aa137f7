#include "drape/core/output_file.h"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <system_error>

namespace drape {
namespace {

[[noreturn]] void fail(const std::filesystem::path& path, const std::string& doing, int error) {
  throw OutputError(path.string() + ": cannot " + doing + ": " + std::strerror(error));
}

}  // namespace

void write_file_atomically(const std::filesystem::path& path, std::string_view bytes) {
  const std::filesystem::path partial = path.string() + ".partial";
  std::FILE* file = std::fopen(partial.c_str(), "wb");
  if (!file) fail(path, "create the file", errno);
  const std::size_t written = std::fwrite(bytes.data(), 1, bytes.size(), file);
  int error = written == bytes.size() ? 0 : errno;
  // fclose flushes what the C library still holds: a full disk may show only here.
  if (std::fclose(file) != 0 && error == 0) error = errno;
  std::error_code ignored;
  if (error != 0) {
    std::filesystem::remove(partial, ignored);
    fail(path, "write the file", error);
  }
  std::error_code moved;
  std::filesystem::rename(partial, path, moved);
  if (moved) {
    std::filesystem::remove(partial, ignored);
    throw OutputError(path.string() + ": cannot move the finished file into place: " + moved.message());
  }
}

LineFile::LineFile(std::filesystem::path path) : path_(std::move(path)), file_(std::fopen(path_.c_str(), "w")) {
  if (!file_) fail(path_, "create the file", errno);
}

LineFile::~LineFile() { std::fclose(file_); }

void LineFile::write_line(std::string_view line) {
  const long before = std::ftell(file_);
  const bool ok = std::fwrite(line.data(), 1, line.size(), file_) == line.size() && std::fputc('\n', file_) != EOF &&
                  std::fflush(file_) == 0;
  if (ok) return;
  const int error = errno;
  // Cut what reached the file of this line, so that the file ends with a whole line.
  if (before >= 0 && ::ftruncate(::fileno(file_), before) == 0) std::fseek(file_, before, SEEK_SET);
  fail(path_, "write the file", error);
}

}  // namespace drape
