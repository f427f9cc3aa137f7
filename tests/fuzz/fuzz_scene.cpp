// libFuzzer target: scene text -> the scene parser and model builder. Bad input must end in a
// SceneError (a clear message), never a crash, a hang or another exception.
#include <cstdint>
#include <string>

#include "drape/core/model.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const drape::Scene scene = drape::parse_scene(text, "fuzz.json");
    // Building allocates the cloth: keep the fuzzer's grids small (memory, not correctness).
    std::size_t vertices = 0;
    for (const auto& c : scene.cloths)
      if (c.grid) vertices += std::size_t(c.grid->resolution[0] + 1) * (c.grid->resolution[1] + 1);
    if (vertices <= 20000) drape::build_model(scene);
  } catch (const drape::SceneError&) {
  }
  return 0;
}
