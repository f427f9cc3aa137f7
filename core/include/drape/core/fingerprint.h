#pragma once
/// \file
/// Fingerprints that tell whether a scene or a file changed since a run was kept.
///
/// Fingerprints that tell whether a scene, or a file, changed since a run was kept: a batch or
/// a sweep started again reruns a run whose inputs changed (FNV-1a, 64 bits; not a security
/// hash).

#include <filesystem>
#include <string>
#include <string_view>

#include "drape/core/scene.h"

namespace drape {

/// The bytes' fingerprint as 16 hexadecimal digits.
std::string fingerprint(std::string_view bytes);

/// A file's fingerprint; "" when it cannot be read.
std::string file_fingerprint(const std::filesystem::path& file);

/// The fingerprint of a scene's text and of the bytes of every mesh file it names.
std::string scene_fingerprint(const Scene& scene);

}  // namespace drape
