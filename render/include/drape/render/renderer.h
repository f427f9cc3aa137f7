#pragma once
/// \file
/// Off-screen rendering of a run's frames, behind drape's own interface. The implementation
/// uses OSMesa (software, no display); Mesa removed OSMesa in 25.1, so nothing outside
/// render/src/osmesa_renderer.cpp knows about it, and another back end (surfaceless EGL) can
/// take its place.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "drape/core/model.h"

namespace drape::render {

/// Bad render settings or a renderer that cannot start. what() says which.
class RenderError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// An 8-bit RGB image, rows top to bottom.
struct Image {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;
};

struct Camera {
  Vec3 position = Vec3(2, -2, 1.5);
  Vec3 target = Vec3::Zero();
  Vec3 up = Vec3::UnitZ();
  Scalar fov_degrees = 40;  ///< vertical field of view
};

/// The render section of a scene: {"camera": {"position", "target", "up", "fov"},
/// "resolution": [w, h], "fps", "samples", "enabled"}; every key optional.
struct RenderSettings {
  std::optional<Camera> camera;  ///< absent: framed automatically from the scene's extent
  int width = 1280, height = 720;
  int samples = 2;     ///< supersampling factor per axis (anti-aliasing)
  double fps = 0;      ///< video frame rate; 0: 1 / frame_time
  bool enabled = false;  ///< render during drape run without --render
};

/// Reads and validates a scene's render section (kept verbatim in Scene::render_json).
/// Throws RenderError naming the scene file and JSON path.
RenderSettings parse_render_settings(const Scene& scene);

/// A camera that sees the cloth and the obstacles at the start of the run.
Camera frame_scene(const Model& model, Scalar aspect);

class Renderer {
 public:
  virtual ~Renderer() = default;
  /// The cloth (front and back faces in distinct colours), the obstacles at time t and the
  /// ground plane, softly lit.
  virtual Image render(const Model& model, const std::vector<Vec3>& cloth_positions, Scalar t, const Camera& camera) = 0;
};

/// The OSMesa renderer at width x height (rendered at samples times that and filtered down).
/// Throws RenderError when OSMesa cannot make a context, or when the environment variable
/// DRAPE_NO_GL is set (which forbids GL contexts).
std::unique_ptr<Renderer> make_renderer(int width, int height, int samples);

/// Writes a PNG (libpng). Throws RenderError naming the file.
void write_png(const std::filesystem::path& path, const Image& image);

/// An MP4 (H.264, yuv420p) written by piping raw frames into the ffmpeg program.
class VideoWriter {
 public:
  /// Throws RenderError when ffmpeg is not on the PATH or cannot start.
  VideoWriter(const std::filesystem::path& path, int width, int height, double fps);
  ~VideoWriter();
  void add(const Image& image);
  /// Finishes the file; throws RenderError when ffmpeg failed.
  void close();
  static bool ffmpeg_available();

 private:
  std::FILE* pipe_ = nullptr;
  std::filesystem::path path_;
  int width_, height_;
};

}  // namespace drape::render
