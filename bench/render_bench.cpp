// render_bench: milliseconds per rendered frame of a scene's initial state (default: the
// default scene at 1280x720, 2x2 supersampling), median of repeated renders, in the shaded style
// (shadows, the endless ground with its grid) beside the simple style (the look before shadows:
// fixed-function lighting, no shadow pass), rendered alternately, and beside the cost of writing
// the PNG.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <filesystem>

#include "drape/ccd_eval/evaluation.h"
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
  render::Look shaded = render::parse_render_settings(model.scene).look, simple = shaded;
  shaded.style = render::Look::Style::Shaded;
  simple.style = render::Look::Style::Simple;
  std::vector<double> shaded_ms, simple_ms, ratio, png_ms;
  const auto png = std::filesystem::temp_directory_path() / "drape_render_bench.png";
  const auto time = [&](const render::Look& look, render::Image* image) {
    const auto begin = std::chrono::steady_clock::now();
    *image = renderer->render(model, model.initial_positions, 0, camera, look);
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count();
  };
  render::Image image;
  time(shaded, &image), time(simple, &image);  // the shaders and the shadow map are made once, before timing
  for (int i = 0; i < repeats; ++i) {
    simple_ms.push_back(time(simple, &image));
    shaded_ms.push_back(time(shaded, &image));
    ratio.push_back(shaded_ms.back() / simple_ms.back());
    const auto begin = std::chrono::steady_clock::now();
    render::write_png(png, image);
    png_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count());
  }
  std::filesystem::remove(png);
  std::printf("render_bench %s: %dx%d, samples %d (simple: %dx%d supersampling; shaded: %s), %zu cloth triangles; "
              "median of %d, styles alternated\n",
              scene.c_str(), width, height, samples, samples, samples,
              samples == 1 ? "no anti-aliasing" : samples == 2 ? "4x multisampling" : "4x multisampling, 2x2 supersampling",
              model.triangles.size(), repeats);
  std::printf("  %-8s %8s %16s\n", "style", "ms/frame", "vs simple");
  std::printf("  %-8s %8.1f %16s\n", "simple", ccd::median(simple_ms), "1.00x");
  std::printf("  %-8s %8.1f %15.2fx  (median of the pairs' ratios; target at most 2x)\n", "shaded", ccd::median(shaded_ms),
              ccd::median(ratio));
  std::printf("  PNG %.1f ms a frame; shaded with PNG %.1f ms (%.1f frames a second)\n", ccd::median(png_ms),
              ccd::median(shaded_ms) + ccd::median(png_ms), 1e3 / (ccd::median(shaded_ms) + ccd::median(png_ms)));
  return 0;
}
