// libFuzzer target: a run folder's frame bytes -> drape's own OBJ frame reader
// (parse_frame_positions) against a small grid's topology (the first byte picks its size).
// Bad input must end in a MeshFileError, never a crash, a hang or another exception.
#include <cstdint>
#include <string>

#include "drape/core/grid.h"
#include "drape/core/mesh_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  drape::GridSpec spec;
  spec.resolution = {1 + data[0] % 4, 1 + (data[0] / 4) % 4};
  const drape::GridMesh grid = drape::make_grid(spec);
  const std::string bytes(reinterpret_cast<const char*>(data) + 1, size - 1);
  try {
    (void)drape::parse_frame_positions(bytes, "fuzz.obj", grid.mesh);
  } catch (const drape::MeshFileError&) {
  }
  return 0;
}
