#pragma once
/// \file
/// Off-screen rendering of a run's frames to PNG and MP4.
///
/// Off-screen rendering of a run's frames, behind drape's own interface. The implementation
/// uses OSMesa (software, no display); Mesa removed OSMesa in 25.1, so nothing outside
/// render/src/osmesa_renderer.cpp knows about it, and another back end (surfaceless EGL) can
/// take its place.

#include <array>
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

/// A linear RGB colour, each channel from 0 to 1.
using Colour = std::array<float, 3>;

/// The two sides of a cloth. The front is the side its triangles' normals point to (counter-
/// clockwise winding seen from the front).
struct ClothColours {
  Colour front, back;
};

/// The colours of cloth number `index` in a scene without its own: a palette of distinct
/// hues, each with a pale back (cloth 0: red front, yellow back).
ClothColours palette_colours(std::size_t index);

/// How a frame looks.
struct Look {
  enum class Style {
    Shaded,  ///< shadows from the key light, per-pixel lighting, an endless ground with a grid in metres
    Simple,  ///< fixed-function lighting, no shadows, a plain finite ground: the look before shadows, cheaper
  };
  Style style = Style::Shaded;
  bool wireframe = false;              ///< the cloth's triangle edges drawn over it
  std::vector<ClothColours> cloths;    ///< per cloth of the model; missing entries take palette_colours
  ClothColours cloth(std::size_t index) const { return index < cloths.size() ? cloths[index] : palette_colours(index); }
};

/// The render section of a scene: {"camera": {"position", "target", "up", "fov"},
/// "resolution": [w, h], "fps", "samples", "enabled", "style", "wireframe"}, and each cloth's
/// {"render": {"color", "back_color"}}; every key optional.
struct RenderSettings {
  std::optional<Camera> camera;  ///< absent: framed automatically from the scene's extent
  int width = 1280, height = 720;
  int samples = 2;     ///< supersampling factor per axis (anti-aliasing)
  double fps = 0;      ///< video frame rate; 0: 1 / frame_time
  bool enabled = false;  ///< render during drape run without --render
  Look look;
};

/// Reads and validates a scene's render section (kept verbatim in Scene::render_json).
/// Throws RenderError naming the scene file and JSON path.
RenderSettings parse_render_settings(const Scene& scene);

/// A camera that sees the cloth and the obstacles at the start of the run.
Camera frame_scene(const Model& model, Scalar aspect);

class Renderer {
 public:
  virtual ~Renderer() = default;
  /// The cloths (front and back faces in distinct colours), the obstacles at time t and the
  /// planes, lit by a key light (casting shadows in the shaded style), a fill light and the sky.
  virtual Image render(const Model& model, const std::vector<Vec3>& cloth_positions, Scalar t, const Camera& camera,
                       const Look& look = {}) = 0;
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
