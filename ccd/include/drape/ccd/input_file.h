#pragma once
/// \file
/// Reading a file a user named without trusting it (loops, devices, sizes).
///
/// Reading a file a user named (a scene, a mesh, a query file, a run's scene copy) without
/// trusting it: a symlink loop, a device such as /dev/zero, a folder or a file larger than the
/// reader's limit is refused with a message, before anything is read. Every reader of drape
/// goes through here; ccd holds it because it is the layer every other one depends on.

#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>

namespace drape::ccd {

/// A file that cannot be read as input. what() names the file and the reason.
class InputFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Largest files the readers take, in bytes: far beyond any real input of its kind, small
/// enough that reading one cannot exhaust the memory of an ordinary machine.
inline constexpr std::uintmax_t MAX_SCENE_BYTES = std::uintmax_t(16) << 20;  ///< 16 MiB of JSON
inline constexpr std::uintmax_t MAX_MESH_BYTES = std::uintmax_t(1) << 30;    ///< 1 GiB mesh file
inline constexpr std::uintmax_t MAX_QUERY_BYTES = std::uintmax_t(1) << 30;   ///< 1 GiB query file

/// Throws InputFileError unless path names (through any symlinks) a regular file of at most
/// max_bytes; `what` says what the file is for ("scene file", "mesh file", ...) in messages.
void check_input_file(const std::filesystem::path& path, std::uintmax_t max_bytes, const std::string& what);

/// check_input_file, then the whole file as bytes.
std::string read_input_file(const std::filesystem::path& path, std::uintmax_t max_bytes, const std::string& what);

/// A size in bytes for messages: "16 MiB", "1.5 GiB", "312 bytes".
std::string format_bytes(std::uintmax_t bytes);

}  // namespace drape::ccd
