#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdint>
#include <limits>

#include "drape/render/renderer.h"

namespace drape::render {
namespace {

using json = nlohmann::json;

// Limits of a sane request: beyond them the renderer would need gigabytes.
constexpr int MIN_SIZE = 16, MAX_SIZE = 8192;
constexpr int MAX_SAMPLES = 4;
constexpr double MAX_SUPERSAMPLED_PIXELS = 64e6;

[[noreturn]] void fail_at(const Scene& scene, const std::string& path, const std::string& what) {
  throw RenderError(scene.file.string() + ": " + path + ": " + what);
}

[[noreturn]] void fail(const Scene& scene, const std::string& path, const std::string& what) {
  fail_at(scene, "/render" + path, what);
}

// A colour as [r, g, b] from 0 to 1 or as "#rrggbb"; path is the full JSON path.
Colour colour(const Scene& scene, const json& v, const std::string& path) {
  const std::string expected = "expected [r, g, b] with each from 0 to 1, or \"#rrggbb\", found " + v.dump();
  Colour c{};
  if (v.is_string()) {
    const std::string text = v.get<std::string>();
    if (text.size() != 7 || text[0] != '#' || text.find_first_not_of("0123456789abcdefABCDEF", 1) != std::string::npos)
      fail_at(scene, path, expected);
    for (int k = 0; k < 3; ++k) c[k] = float(std::stoi(text.substr(1 + 2 * k, 2), nullptr, 16)) / 255.0f;
    return c;
  }
  if (!v.is_array() || v.size() != 3) fail_at(scene, path, expected);
  for (int k = 0; k < 3; ++k) {
    if (!v[k].is_number() || !(v[k].get<double>() >= 0 && v[k].get<double>() <= 1)) fail_at(scene, path, expected);
    c[k] = float(v[k].get<double>());
  }
  return c;
}

// A pale version of a front colour, for a back the scene does not give.
Colour pale(const Colour& front) {
  Colour c{};
  for (int k = 0; k < 3; ++k) c[k] = 0.35f * front[k] + 0.65f * 0.95f;
  return c;
}

double number(const Scene& scene, const json& v, const std::string& path) {
  if (!v.is_number()) fail(scene, path, "expected a number, found " + v.dump());
  return v.get<double>();
}

// An integer as a long long: get<int> would wrap 4294967312 into 16, so a value beyond the
// range of a long long saturates instead and meets the caller's range check.
long long integer(const json& v) {
  if (v.is_number_unsigned() && v.get<std::uint64_t>() > std::uint64_t(std::numeric_limits<long long>::max()))
    return std::numeric_limits<long long>::max();
  return v.get<long long>();
}

Vec3 vec3(const Scene& scene, const json& v, const std::string& path) {
  if (!v.is_array() || v.size() != 3) fail(scene, path, "expected an array of 3 numbers, found " + v.dump());
  return Vec3(number(scene, v[0], path + "/0"), number(scene, v[1], path + "/1"), number(scene, v[2], path + "/2"));
}

}  // namespace

ClothColours palette_colours(std::size_t index) {
  // Front hues far apart in a cycle of six; the backs pale or warm enough to tell from any front.
  static const ClothColours PALETTE[] = {
      {{0.80f, 0.22f, 0.18f}, {0.95f, 0.78f, 0.30f}},  // red, yellow back
      {{0.18f, 0.36f, 0.78f}, {0.62f, 0.80f, 0.96f}},  // blue, pale blue back
      {{0.20f, 0.58f, 0.30f}, {0.74f, 0.92f, 0.58f}},  // green, pale green back
      {{0.55f, 0.26f, 0.66f}, {0.93f, 0.70f, 0.88f}},  // purple, pink back
      {{0.88f, 0.50f, 0.10f}, {0.98f, 0.88f, 0.66f}},  // orange, cream back
      {{0.10f, 0.58f, 0.62f}, {0.66f, 0.93f, 0.90f}},  // teal, pale teal back
  };
  return PALETTE[index % std::size(PALETTE)];
}

RenderSettings parse_render_settings(const Scene& scene) {
  RenderSettings s;
  for (std::size_t i = 0; i < scene.cloths.size(); ++i) {
    ClothColours colours = palette_colours(i);
    if (!scene.cloths[i].render_json.empty()) {
      const std::string path = "/cloths/" + std::to_string(i) + "/render";
      const json r = json::parse(scene.cloths[i].render_json);
      for (const auto& [key, value] : r.items())
        if (key != "color" && key != "back_color" && key != "comment")
          fail_at(scene, path + "/" + key, "unknown key (expected one of: color, back_color)");
      if (r.contains("color")) colours.front = colour(scene, r["color"], path + "/color"), colours.back = pale(colours.front);
      if (r.contains("back_color")) colours.back = colour(scene, r["back_color"], path + "/back_color");
    }
    s.look.cloths.push_back(colours);
  }
  if (scene.render_json.empty()) return s;
  const json r = json::parse(scene.render_json);
  for (const auto& [key, value] : r.items())
    if (key != "camera" && key != "resolution" && key != "fps" && key != "samples" && key != "enabled" && key != "style" &&
        key != "wireframe" && key != "comment")
      fail(scene, "/" + key, "unknown key (expected one of: camera, resolution, fps, samples, enabled, style, wireframe)");
  if (r.contains("style")) {
    const json& v = r["style"];
    if (!v.is_string() || (v != "shaded" && v != "simple")) fail(scene, "/style", "expected \"shaded\" or \"simple\", found " + v.dump());
    s.look.style = v == "simple" ? Look::Style::Simple : Look::Style::Shaded;
  }
  if (r.contains("wireframe")) {
    if (!r["wireframe"].is_boolean()) fail(scene, "/wireframe", "expected true or false");
    s.look.wireframe = r["wireframe"].get<bool>();
  }
  if (r.contains("resolution")) {
    const json& v = r["resolution"];
    if (!v.is_array() || v.size() != 2 || !v[0].is_number_integer() || !v[1].is_number_integer())
      fail(scene, "/resolution", "expected [width, height] in pixels, found " + v.dump());
    const long long width = integer(v[0]), height = integer(v[1]);
    if (width < MIN_SIZE || height < MIN_SIZE || width > MAX_SIZE || height > MAX_SIZE)
      fail(scene, "/resolution", "expected each side from 16 to 8192 pixels, found " + v.dump());
    s.width = int(width);
    s.height = int(height);
  }
  if (r.contains("samples")) {
    const json& v = r["samples"];
    if (!v.is_number_integer() || integer(v) < 1 || integer(v) > MAX_SAMPLES)
      fail(scene, "/samples", "expected an integer from 1 to 4 (supersampling per axis), found " + v.dump());
    s.samples = int(integer(v));
  }
  if (double(s.width) * s.height * s.samples * s.samples > MAX_SUPERSAMPLED_PIXELS)
    fail(scene, "/resolution", "resolution times samples squared exceeds 64 million pixels; lower one of them");
  if (r.contains("fps")) {
    s.fps = number(scene, r["fps"], "/fps");
    if (!(s.fps > 0 && s.fps <= 240)) fail(scene, "/fps", "expected a frame rate above 0 and at most 240");
  }
  if (r.contains("enabled")) {
    if (!r["enabled"].is_boolean()) fail(scene, "/enabled", "expected true or false");
    s.enabled = r["enabled"].get<bool>();
  }
  if (r.contains("camera")) {
    const json& c = r["camera"];
    if (!c.is_object()) fail(scene, "/camera", "expected an object");
    Camera camera;
    for (const auto& [key, value] : c.items())
      if (key != "position" && key != "target" && key != "up" && key != "fov" && key != "comment")
        fail(scene, "/camera/" + key, "unknown key (expected one of: position, target, up, fov)");
    if (c.contains("position")) camera.position = vec3(scene, c["position"], "/camera/position");
    if (c.contains("target")) camera.target = vec3(scene, c["target"], "/camera/target");
    if (c.contains("up")) camera.up = vec3(scene, c["up"], "/camera/up");
    if (c.contains("fov")) {
      camera.fov_degrees = number(scene, c["fov"], "/camera/fov");
      if (!(camera.fov_degrees > 1 && camera.fov_degrees < 170)) fail(scene, "/camera/fov", "expected degrees from 1 to 170");
    }
    if (!((camera.target - camera.position).norm() > 0)) fail(scene, "/camera", "position and target must differ");
    if (!(camera.up.cross(camera.target - camera.position).norm() > 0)) fail(scene, "/camera/up", "must not be along the view direction");
    s.camera = camera;
  }
  return s;
}

Camera frame_scene(const Model& model, Scalar aspect) {
  // The box around the cloth and the spheres and meshes (planes are unbounded), seen from the
  // front-left, above, far enough for the box's bounding sphere to fill the narrower view.
  Vec3 lo = model.initial_positions[0], hi = lo;
  const auto include = [&](const Vec3& p) { lo = lo.cwiseMin(p), hi = hi.cwiseMax(p); };
  for (const Vec3& p : model.initial_positions) include(p);
  for (const Obstacle& o : model.obstacles) {
    if (o.spec.kind == ObstacleSpec::Kind::Sphere) {
      include(o.spec.center - Vec3::Constant(o.spec.radius));
      include(o.spec.center + Vec3::Constant(o.spec.radius));
    }
    for (const Vec3& p : o.mesh.vertices) include(p);
  }
  Camera c;
  c.up = model.scene.gravity.norm() > 0 ? Vec3(-model.scene.gravity.normalized()) : Vec3::UnitZ();
  c.target = 0.5 * (lo + hi);
  const Scalar radius = std::max<Scalar>(0.5 * (hi - lo).norm(), 1e-3);
  const Scalar half_fov = c.fov_degrees * M_PI / 360.0;
  const Scalar fit = std::min(std::tan(half_fov), std::tan(half_fov) * aspect);
  const Scalar distance = 0.95 * radius / fit;
  // From the front left, 18 degrees above the horizon (the horizon just in view).
  const Vec3 side = c.up.unitOrthogonal(), front = c.up.cross(side);
  const Scalar elevation = 18 * M_PI / 180;
  const Vec3 horizontal = (-0.8 * front - 0.6 * side).normalized();
  c.position = c.target + distance * (std::cos(elevation) * horizontal + std::sin(elevation) * c.up);
  return c;
}

}  // namespace drape::render
