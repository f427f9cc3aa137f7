// render_bench: milliseconds per rendered frame of a scene's initial state (default: the
// default scene at 1280x720, 2x2 supersampling), median of repeated renders, beside the cost of
// writing the PNG.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <filesystem>

#include "drape/ccd/evaluation.h"
#include "drape/render/renderer.h"

using namespace drape;

int main(int argc, char** argv) {
  CLI::App app{"Milliseconds per rendered frame (OSMesa) and per PNG written."};
  std::string scene = DRAPE_SOURCE_DIR "/scenes/drape_sphere.json";
  int width = 1280, height = 720, samples = 2, repeats = 9;
  app.add_option("scene", scene, "Scene file")->capture_default_str();
  app.add_option("--width", width)->capture_default_str();
  app.add_option("--height", height)->capture_default_str();
  app.add_option("--samples", samples, "Supersampling per axis")->capture_default_str();
  app.add_option("--repeats", repeats)->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  const Model model = build_model(load_scene(scene));
  const auto renderer = render::make_renderer(width, height, samples);
  const render::Camera camera = render::frame_scene(model, Scalar(width) / height);
  std::vector<double> render_ms, png_ms;
  const auto png = std::filesystem::temp_directory_path() / "drape_render_bench.png";
  for (int i = 0; i < repeats; ++i) {
    auto begin = std::chrono::steady_clock::now();
    const render::Image image = renderer->render(model, model.initial_positions, 0, camera);
    render_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count());
    begin = std::chrono::steady_clock::now();
    render::write_png(png, image);
    png_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count());
  }
  std::filesystem::remove(png);
  std::printf("render_bench %s: %dx%d, %dx%d supersampling, %zu cloth triangles; median of %d\n", scene.c_str(), width,
              height, samples, samples, model.triangles.size(), repeats);
  std::printf("  render %.1f ms a frame, PNG %.1f ms a frame, together %.1f ms (%.1f frames a second)\n",
              ccd::median(render_ms), ccd::median(png_ms), ccd::median(render_ms) + ccd::median(png_ms),
              1e3 / (ccd::median(render_ms) + ccd::median(png_ms)));
  return 0;
}
