// libFuzzer target: mesh file bytes -> assimp's OBJ or PLY reader (the first byte chooses) ->
// the mesh loader and its validation. Bad input must end in a MeshFileError or a reported
// problem, never a crash, a hang or another exception.
#include <cstdint>
#include <string>

#include "drape/core/mesh.h"
#include "drape/core/mesh_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string format = (data[0] & 1) ? "ply" : "obj";
  const std::string bytes(reinterpret_cast<const char*>(data) + 1, size - 1);
  try {
    const drape::TriangleMesh mesh = drape::parse_mesh(bytes, format, "fuzz." + format);
    (void)drape::mesh_problem(mesh);
  } catch (const drape::MeshFileError&) {
  }
  return 0;
}
