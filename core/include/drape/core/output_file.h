#pragma once
/// \file
/// Every file drape writes, written so that no write fails silently.
///
/// Every file drape writes goes through here, so that no write fails silently: a full disk,
/// a quota or any I/O error throws OutputError naming the file, and what was complete before
/// stays complete (whole files appear by rename, rows are appended whole).

#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>

namespace drape {

/// A file that could not be written. what() names the file and the system's reason.
class OutputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Writes bytes to path + ".partial", closes it, then renames it onto path: a reader (or a
/// later run) sees the old file or the whole new one, never part of it. The partial file is
/// removed when anything fails. Throws OutputError.
void write_file_atomically(const std::filesystem::path& path, std::string_view bytes);

/// A file written a line at a time (stats.csv): each line is written and flushed whole, and a
/// failure throws OutputError. Created empty (truncated) when opened.
class LineFile {
 public:
  explicit LineFile(std::filesystem::path path);
  ~LineFile();
  LineFile(const LineFile&) = delete;
  LineFile& operator=(const LineFile&) = delete;
  void write_line(std::string_view line);
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
  std::FILE* file_;
};

}  // namespace drape
