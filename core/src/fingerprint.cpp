#include "drape/core/fingerprint.h"

#include <cstdint>
#include <cstdio>

#include "drape/ccd/input_file.h"

namespace drape {
namespace {

// Files up to this size are fingerprinted whole (meshes included).
constexpr std::uintmax_t MAX_FINGERPRINTED_BYTES = std::uintmax_t(1) << 30;

}  // namespace

std::string fingerprint(std::string_view bytes) {
  std::uint64_t h = 1469598103934665603ull;
  for (const unsigned char c : bytes) h = (h ^ c) * 1099511628211ull;
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(h));
  return text;
}

std::string file_fingerprint(const std::filesystem::path& file) {
  try {
    return fingerprint(ccd::read_input_file(file, MAX_FINGERPRINTED_BYTES, "file"));
  } catch (const std::exception&) {
    return "";
  }
}

std::string scene_fingerprint(const Scene& scene) {
  std::string all = fingerprint(scene.text);
  const auto add = [&](const std::filesystem::path& mesh) {
    if (mesh.empty()) return;
    all.append(1, ' ').append(mesh.string()).append(1, ' ').append(file_fingerprint(mesh));
  };
  for (const ClothSpec& c : scene.cloths) add(c.mesh_file);
  for (const ObstacleSpec& o : scene.obstacles) add(o.mesh_file);
  return fingerprint(all);
}

}  // namespace drape
