// Off-screen rendering: what a frame shows, the video's format, and that simulating alone
// never creates a GL context.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "../app/drape_process.h"
#include "drape/render/renderer.h"

using namespace drape;
using drape::testing::run_drape;
namespace fs = std::filesystem;

namespace {

const std::string SOURCE = DRAPE_SOURCE_DIR;

fs::path temp_dir(const std::string& name) { return drape::testing::fresh_temp_path("render_test", name); }

std::string shell(const std::string& command) {
  std::string out;
  FILE* pipe = popen(command.c_str(), "r");
  char buffer[256];
  while (std::fgets(buffer, sizeof buffer, pipe)) out += buffer;
  pclose(pipe);
  return out;
}

// The pixel (column, row from the top) where a world point appears through the camera.
std::pair<int, int> pixel_of(const render::Camera& c, int width, int height, const Vec3& p) {
  const Vec3 f = (c.target - c.position).normalized(), s = f.cross(c.up).normalized(), u = s.cross(f);
  const Vec3 d = p - c.position;
  const double depth = d.dot(f), t = std::tan(c.fov_degrees * M_PI / 360);
  const double x = d.dot(s) / (depth * t * width / height), y = d.dot(u) / (depth * t);
  return {int(std::floor((x + 1) / 2 * width)), int(std::floor((1 - y) / 2 * height))};
}

std::array<int, 3> rgb_at(const render::Image& image, int x, int y) {
  const std::size_t at = (std::size_t(y) * image.width + x) * 3;
  return {image.rgb[at], image.rgb[at + 1], image.rgb[at + 2]};
}

double luminance(const render::Image& image, int x, int y) {
  const auto [r, g, b] = rgb_at(image, x, y);
  return 0.2126 * r + 0.7152 * g + 0.0722 * b;
}

// Mean luminance of the pixels where these world points appear (each inside the image).
double luminance_at(const render::Image& image, const render::Camera& camera, const std::vector<Vec3>& points) {
  double sum = 0;
  for (const Vec3& p : points) {
    const auto [x, y] = pixel_of(camera, image.width, image.height, p);
    EXPECT_TRUE(x >= 0 && y >= 0 && x < image.width && y < image.height) << p.transpose();
    sum += luminance(image, std::clamp(x, 0, image.width - 1), std::clamp(y, 0, image.height - 1));
  }
  return sum / points.size();
}

// A scene in scenes/ (mesh paths resolve there) from its text.
Model scene_model(const std::string& text) { return build_model(parse_scene(text, SOURCE + "/scenes/render_test.json")); }

render::Camera camera_at(const Vec3& position, const Vec3& target, double fov = 40) {
  render::Camera c;
  c.position = position;
  c.target = target;
  c.fov_degrees = fov;
  return c;
}

render::Look style(render::Look::Style s) {
  render::Look look;
  look.style = s;
  return look;
}

}  // namespace

TEST(Render, AFrameShowsTheClothOnTheBackground) {
  const Model model = build_model(load_scene(SOURCE + "/scenes/hanging.json"));
  const auto renderer = render::make_renderer(320, 180, 2);
  const render::Camera camera = render::frame_scene(model, 320.0 / 180);
  const render::Image image = renderer->render(model, model.initial_positions, 0, camera);
  ASSERT_EQ(image.rgb.size(), 320u * 180 * 3);
  int cloth = 0, background = 0;
  for (std::size_t p = 0; p < image.rgb.size(); p += 3) {
    const int r = image.rgb[p], g = image.rgb[p + 1], b = image.rgb[p + 2];
    if ((r > 120 && g < 110 && b < 110) || (r > 150 && g > 110 && b < 110)) ++cloth;  // front red, back yellow
    if (r > 225 && g > 230 && b > 235) ++background;
  }
  const double total = 320.0 * 180;
  EXPECT_GT(cloth / total, 0.03);
  EXPECT_LT(cloth / total, 0.7);
  EXPECT_GT(background / total, 0.25);
  EXPECT_LT((cloth + background) / total, 1.0001);
}

TEST(Render, RunWithRenderWritesPngsAndAnH264Video) {
  const fs::path out = temp_dir("hanging");
  const auto run = run_drape("run " + SOURCE + "/scenes/hanging.json --frames 5 --quiet --render --resolution 160x96 --out " + out.string());
  ASSERT_EQ(run.status, 0) << run.output;
  for (int f = 0; f <= 5; ++f) EXPECT_TRUE(fs::exists(out / "render" / ("frame_0000" + std::to_string(f) + ".png")));
  ASSERT_TRUE(fs::exists(out / "video.mp4"));
  const std::string probe = shell("ffprobe -v error -count_frames -select_streams v:0 -show_entries "
                                  "stream=codec_name,width,height,pix_fmt,nb_read_frames -of csv=p=0 " + (out / "video.mp4").string());
  EXPECT_EQ(probe, "h264,160,96,yuv420p,6\n");
}

TEST(Render, SimulatingAloneNeverCreatesAGlContext) {
  // DRAPE_NO_GL makes any attempt at a GL context fail: the plain run must not notice it,
  // the rendering run must.
  const fs::path plain = temp_dir("no_gl_plain"), rendered = temp_dir("no_gl_render");
  const std::string scene = SOURCE + "/scenes/hanging.json --frames 2 --quiet --out ";
  EXPECT_EQ(run_drape("run " + scene + plain.string()).status, 0);
  EXPECT_FALSE(fs::exists(plain / "render"));
  ::setenv("DRAPE_NO_GL", "1", 1);
  const auto blocked = run_drape("run " + scene + rendered.string() + " --render");
  const auto plain_again = run_drape("run " + scene + plain.string() + " --overwrite");
  ::unsetenv("DRAPE_NO_GL");
  EXPECT_EQ(plain_again.status, 0) << plain_again.output;
  EXPECT_NE(blocked.status, 0);
  EXPECT_NE(blocked.output.find("no GL context"), std::string::npos) << blocked.output;
  EXPECT_TRUE(fs::exists(rendered / "stats.csv"));  // a failed render leaves the simulation output
  std::ifstream stats(rendered / "stats.csv");
  EXPECT_EQ(std::count(std::istreambuf_iterator<char>(stats), std::istreambuf_iterator<char>(), '\n'), 4);
}

TEST(Render, BadRenderInputIsReportedNotCrashed) {
  const fs::path dir = temp_dir("bad");
  fs::create_directories(dir);
  const fs::path scene = dir / "zero.json";
  std::ofstream(scene) << R"({"cloths": [{"grid": {}}], "render": {"resolution": [0, 720]}})";
  const auto zero = run_drape("run " + scene.string() + " --frames 1 --quiet --out " + (dir / "zero_out").string());
  EXPECT_EQ(zero.status, 2);
  EXPECT_NE(zero.output.find("/render/resolution: expected each side from 16 to 8192"), std::string::npos) << zero.output;
  std::ofstream(dir / "huge.json") << R"({"cloths": [{"grid": {}}], "render": {"resolution": [8192, 8192], "samples": 4}})";
  // validate reads the render section with the parser drape run uses.
  const auto huge_validate = run_drape("validate " + (dir / "huge.json").string());
  EXPECT_EQ(huge_validate.status, 2);
  EXPECT_NE(huge_validate.output.find((dir / "huge.json").string() + ": /render/resolution: resolution times samples squared exceeds"),
            std::string::npos)
      << huge_validate.output;
  EXPECT_EQ(run_drape("run " + (dir / "huge.json").string() + " --frames 1 --quiet --out " + (dir / "huge_out").string()).status, 2);
  EXPECT_EQ(run_drape("render " + (dir / "zero_out").string() + " --resolution 5x5").status, 2);
  // A run folder whose render/ cannot be created: a file stands in its way.
  const fs::path out = dir / "blocked";
  ASSERT_EQ(run_drape("run " + SOURCE + "/scenes/hanging.json --frames 1 --quiet --out " + out.string()).status, 0);
  std::ofstream(out / "render") << "in the way";
  const auto blocked = run_drape("render " + out.string());
  EXPECT_EQ(blocked.status, 2);
  EXPECT_NE(blocked.output.find("cannot create the folder"), std::string::npos) << blocked.output;
  EXPECT_TRUE(fs::exists(out / "stats.csv"));
}

TEST(Render, WithoutFfmpegItWarnsAndKeepsThePngs) {
  const fs::path out = temp_dir("no_ffmpeg");
  ASSERT_EQ(run_drape("run " + SOURCE + "/scenes/hanging.json --frames 2 --quiet --out " + out.string()).status, 0);
  const auto run = run_drape("render " + out.string() + " --resolution 64x48 2>&1 | cat; PATH=/nonexistent " DRAPE_EXECUTABLE
                             " render " + out.string() + " --resolution 64x48");
  EXPECT_EQ(run.status, 0) << run.output;
  EXPECT_NE(run.output.find("ffmpeg program is not on the PATH"), std::string::npos) << run.output;
  EXPECT_TRUE(fs::exists(out / "render" / "frame_00002.png"));
}

TEST(Render, BadRenderSectionsNameThePathAndWhatWasExpected) {
  struct Case {
    const char* render;
    const char* expected;
  };
  const Case cases[] = {
      {R"({"colour": "red"})",
       "bad.json: /render/colour: unknown key (expected one of: camera, resolution, fps, samples, enabled, style, wireframe)"},
      {R"({"style": "cartoon"})", "bad.json: /render/style: expected \"shaded\" or \"simple\", found \"cartoon\""},
      {R"({"wireframe": 1})", "bad.json: /render/wireframe: expected true or false"},
      {R"({"samples": 0})", "bad.json: /render/samples: expected an integer from 1 to 4 (supersampling per axis), found 0"},
      {R"({"samples": 5})", "bad.json: /render/samples: expected an integer from 1 to 4"},
      {R"({"samples": 2.5})", "bad.json: /render/samples: expected an integer from 1 to 4"},
      // 2^32 + 2 and 2^64 - 1 would wrap into 2 and -1 as an int.
      {R"({"samples": 4294967298})", "bad.json: /render/samples: expected an integer from 1 to 4 (supersampling per axis), found 4294967298"},
      {R"({"samples": 18446744073709551615})", "bad.json: /render/samples: expected an integer from 1 to 4"},
      {R"({"enabled": "yes"})", "bad.json: /render/enabled: expected true or false"},
      {R"({"enabled": 1})", "bad.json: /render/enabled: expected true or false"},
      {R"({"camera": {"position": [1, 2, 3], "target": [1, 2, 3]}})", "bad.json: /render/camera: position and target must differ"},
      {R"({"camera": {"fov": 0.5}})", "bad.json: /render/camera/fov: expected degrees from 1 to 170"},
      {R"({"camera": {"fov": 180}})", "bad.json: /render/camera/fov: expected degrees from 1 to 170"},
      {R"({"camera": {"position": [0, 0, 1], "target": [0, 0, 0]}})", "bad.json: /render/camera/up: must not be along the view direction"},
      {R"({"camera": {"lens": 50}})", "bad.json: /render/camera/lens: unknown key"},
      {R"({"camera": {"position": [0, 0]}})", "bad.json: /render/camera/position: expected an array of 3 numbers"},
      {R"({"camera": 3})", "bad.json: /render/camera: expected an object"},
      {R"({"resolution": [4]})", "bad.json: /render/resolution: expected [width, height] in pixels, found [4]"},
      {R"({"resolution": "1280x720"})", "bad.json: /render/resolution: expected [width, height] in pixels"},
      {R"({"resolution": [640.5, 480]})", "bad.json: /render/resolution: expected [width, height] in pixels"},
      {R"({"resolution": [8, 720]})", "bad.json: /render/resolution: expected each side from 16 to 8192 pixels, found [8,720]"},
      // 2^32 + 16 would wrap into 16 as an int.
      {R"({"resolution": [4294967312, 720]})",
       "bad.json: /render/resolution: expected each side from 16 to 8192 pixels, found [4294967312,720]"},
      {R"({"resolution": [640, -4294966816]})", "bad.json: /render/resolution: expected each side from 16 to 8192 pixels"},
      {R"({"resolution": [8192, 8192], "samples": 4})", "bad.json: /render/resolution: resolution times samples squared exceeds"},
      {R"({"fps": 0})", "bad.json: /render/fps: expected a frame rate above 0 and at most 240"},
  };
  // The message of parse_render_settings on a scene's text, "" when it accepts it.
  const auto render_error = [](const std::string& text) {
    try {
      render::parse_render_settings(parse_scene(text, "bad.json"));
    } catch (const render::RenderError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  for (const Case& c : cases) {
    const std::string message = render_error(std::string(R"({"cloths": [{"grid": {}}], "render": )") + c.render + "}");
    EXPECT_NE(message.find(c.expected), std::string::npos) << "render: " << c.render << "\nmessage: " << message;
  }
  // A cloth's own render section.
  const Case cloth_cases[] = {
      {R"({"color": [1, 0.5]})", "bad.json: /cloths/0/render/color: expected [r, g, b] with each from 0 to 1, or \"#rrggbb\", found [1,0.5]"},
      {R"({"color": [1, 0.5, 2]})", "bad.json: /cloths/0/render/color: expected [r, g, b] with each from 0 to 1"},
      {R"({"color": "#12345g"})", "bad.json: /cloths/0/render/color: expected [r, g, b]"},
      {R"({"color": "red"})", "bad.json: /cloths/0/render/color: expected [r, g, b]"},
      {R"({"back_color": [0, 0, -0.1]})", "bad.json: /cloths/0/render/back_color: expected [r, g, b]"},
      {R"({"colour": [0, 0, 0]})", "bad.json: /cloths/0/render/colour: unknown key (expected one of: color, back_color)"},
  };
  for (const Case& c : cloth_cases) {
    const std::string message = render_error(std::string(R"({"cloths": [{"grid": {}, "render": )") + c.render + "}]}");
    EXPECT_NE(message.find(c.expected), std::string::npos) << "render: " << c.render << "\nmessage: " << message;
  }
  std::string not_object;
  try {
    parse_scene(R"({"cloths": [{"grid": {}, "render": 3}]})", "bad.json");
  } catch (const SceneError& e) {
    not_object = e.what();
  }
  EXPECT_NE(not_object.find("/cloths/0/render: expected an object"), std::string::npos) << not_object;
  // Given colours: "#rrggbb" and [r, g, b]; a back not given is a pale version of the front.
  const Scene given = parse_scene(
      R"({"cloths": [{"grid": {}, "render": {"color": "#ff8000"}}, {"grid": {}, "render": {"color": [0, 0, 1], "back_color": [0, 1, 0]}}, {"grid": {}}]})",
      "given.json");
  const render::Look look = render::parse_render_settings(given).look;
  ASSERT_EQ(look.cloths.size(), 3u);
  EXPECT_EQ(look.cloths[0].front, (render::Colour{1.0f, 128 / 255.0f, 0.0f}));
  EXPECT_GT(look.cloths[0].back[2], 0.5f);  // pale: every channel lifted
  EXPECT_EQ(look.cloths[1].back, (render::Colour{0, 1, 0}));
  EXPECT_EQ(look.cloths[2].front, render::palette_colours(2).front);
  // The limits themselves are accepted.
  const Scene edge = parse_scene(R"({"cloths": [{"grid": {}}], "render": {"resolution": [16, 8192], "samples": 4}})", "edge.json");
  const render::RenderSettings settings = render::parse_render_settings(edge);
  EXPECT_EQ(settings.width, 16);
  EXPECT_EQ(settings.height, 8192);
  EXPECT_EQ(settings.samples, 4);
}

// Ctrl-C during a render (SIGINT to drape and, through the process group, to ffmpeg): status 3,
// the earlier video whole and in place, no partial image or video left behind.
TEST(Render, AnInterruptedRenderKeepsTheEarlierVideo) {
  const fs::path out = temp_dir("interrupted");
  ASSERT_EQ(run_drape("run " + SOURCE + "/scenes/hanging.json --frames 60 --quiet --out " + out.string()).status, 0);
  ASSERT_EQ(run_drape("render --resolution 64x48 --quiet " + out.string()).status, 0);
  const auto read = [](const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  };
  const std::string earlier = read(out / "video.mp4");
  ASSERT_GT(earlier.size(), 1000u);
  // 60 frames at 1920 x 1080 take seconds. The interrupt comes once the second frame is written
  // (not after a fixed time, which a slow machine may spend starting up), to drape's own process
  // group as Ctrl-C on a terminal would: ffmpeg is in it too. A drape still running a minute
  // later is killed (status 137); one that ignores the interrupt and finishes gives 0.
  fs::remove_all(out / "render");
  const std::string second = (out / "render" / "frame_00002.png").string();
  const std::string status = shell("setsid " + std::string(DRAPE_EXECUTABLE) + " render --resolution 1920x1080 --quiet " +
                                   out.string() + " >/dev/null 2>&1 & pid=$!; i=0; while [ ! -e " + second +
                                   " ] && [ $i -lt 1200 ] && kill -0 $pid 2>/dev/null; do sleep 0.05; i=$((i+1)); done; "
                                   "kill -INT -$pid 2>/dev/null; (sleep 60; kill -KILL -$pid) >/dev/null 2>&1 & dog=$!; "
                                   "wait $pid; st=$?; kill $dog 2>/dev/null; echo $st");
  EXPECT_EQ(status, "3\n");
  EXPECT_EQ(read(out / "video.mp4"), earlier);
  for (const auto& entry : fs::recursive_directory_iterator(out))
    EXPECT_NE(entry.path().extension(), ".partial") << entry.path();
}

// A 1.2 m cloth lying on a 0.6 m box overhangs it by 0.3 m on every side. Seen from the front,
// low enough to see the ground under the overhang on the right: the key light comes from the
// camera's upper left, so that ground is in the cloth's shadow and darker than open ground in
// front. The simple style has no shadows: the same measure finds no difference there.
TEST(Render, AClothRestingOnABoxShadowsTheGroundUnderItsOverhang) {
  const Model model = scene_model(R"({"cloths": [{"grid": {"size": [1.2, 1.2], "resolution": [12, 12]},
      "transform": {"translate": [0, 0, 0.61]}}],
      "obstacles": [{"mesh": "meshes/box.obj", "transform": {"translate": [0, 0, 0.3], "scale": 0.6}},
                    {"plane": {"point": [0, 0, 0], "normal": [0, 0, 1]}}]})");
  const auto renderer = render::make_renderer(480, 270, 2);
  const render::Camera camera = camera_at(Vec3(0, -3, 0.5), Vec3(0, 0, 0.3));
  const std::vector<Vec3> under = {Vec3(0.45, -0.3, 0), Vec3(0.45, 0, 0), Vec3(0.45, 0.3, 0), Vec3(0.5, 0.15, 0)};
  const std::vector<Vec3> open = {Vec3(-1.2, -0.9, 0), Vec3(-0.9, -1.2, 0), Vec3(0.3, -1.2, 0), Vec3(-1.4, -0.5, 0)};
  const render::Image shaded = renderer->render(model, model.initial_positions, 0, camera, style(render::Look::Style::Shaded));
  const render::Image simple = renderer->render(model, model.initial_positions, 0, camera, style(render::Look::Style::Simple));
  EXPECT_LT(luminance_at(shaded, camera, under), 0.7 * luminance_at(shaded, camera, open));
  EXPECT_GT(luminance_at(simple, camera, under), 0.95 * luminance_at(simple, camera, open));
}

// A level camera looking diagonally across the ground: each column's first pixel from the top
// that is not the background's colour is on the horizon, and it is the same row in every
// column, from a narrow to a very wide field of view.
TEST(Render, TheHorizonIsStraightAtAnyFieldOfView) {
  // The cloth is behind the camera: the picture is ground and sky.
  const Model model = scene_model(R"({"cloths": [{"grid": {}, "transform": {"translate": [-6, -8, 1]}}],
      "obstacles": [{"plane": {"point": [0, 0, 0], "normal": [0, 0, 1]}}]})");
  const auto renderer = render::make_renderer(320, 180, 2);
  const render::Image blank = renderer->render(model, model.initial_positions, 0, camera_at(Vec3(0, 0, 1.5), Vec3(0, 0, 3), 40));
  const std::array<int, 3> background = rgb_at(blank, 160, 20);  // looking up: sky alone
  for (const double fov : {20.0, 60.0, 120.0, 160.0}) {
    const render::Camera camera = camera_at(Vec3(0, 0, 1.5), Vec3(3, 4, 1.4), fov);
    const render::Image image = renderer->render(model, model.initial_positions, 0, camera);
    int lowest = image.height, highest = -1;
    for (int x = 0; x < image.width; ++x) {
      int y = 0;
      while (y < image.height) {
        const auto c = rgb_at(image, x, y);
        if (std::abs(c[0] - background[0]) + std::abs(c[1] - background[1]) + std::abs(c[2] - background[2]) > 12) break;
        ++y;
      }
      lowest = std::min(lowest, y), highest = std::max(highest, y);
    }
    EXPECT_GT(lowest, 0) << "fov " << fov;             // sky above the horizon
    EXPECT_LT(highest, image.height) << "fov " << fov;  // ground below it
    EXPECT_LE(highest - lowest, 1) << "fov " << fov << ": the horizon spans rows " << lowest << " to " << highest;
  }
}

// Seen from above, the ground under a line of whole metres is darker than the ground between
// the 10 cm lines.
TEST(Render, TheGroundShowsAGridInMetres) {
  const Model model = scene_model(R"({"cloths": [{"grid": {}, "transform": {"translate": [0, -10, 5]}}],
      "obstacles": [{"plane": {"point": [0, 0, 0], "normal": [0, 0, 1]}}]})");
  const auto renderer = render::make_renderer(480, 270, 2);
  const render::Camera camera = camera_at(Vec3(0.5, -1.5, 2.5), Vec3(0.5, 0.5, 0));
  const render::Image image = renderer->render(model, model.initial_positions, 0, camera);
  for (const double y : {0.05, 0.25, 0.45, 0.65}) {  // between the lines along x
    // The darkest pixel of the 3 x 3 around the line, against the mean of those between lines.
    const auto [x, row] = pixel_of(camera, image.width, image.height, Vec3(1.0, y, 0));
    double line = 255;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) line = std::min(line, luminance(image, x + dx, row + dy));
    const double between = luminance_at(image, camera, {Vec3(0.95, y, 0), Vec3(1.05, y, 0), Vec3(0.55, y, 0)});
    EXPECT_LT(line, 0.9 * between) << "y " << y;
  }
}

namespace {

// Pixels whose colour is mostly red, mostly blue, mostly green.
struct Hues {
  int red = 0, blue = 0, green = 0, yellow = 0;
};
Hues count_hues(const render::Image& image) {
  Hues h;
  for (std::size_t p = 0; p < image.rgb.size(); p += 3) {
    const int r = image.rgb[p], g = image.rgb[p + 1], b = image.rgb[p + 2];
    if (r > g + 60 && r > b + 60) ++h.red;
    if (b > r + 60 && b > g + 20) ++h.blue;
    if (g > r + 60 && g > b + 60) ++h.green;
    if (r > b + 60 && g > b + 60) ++h.yellow;
  }
  return h;
}

}  // namespace

// Two cloths side by side: from above, cloth 0's front is red and cloth 1's blue; from below
// (no ground), cloth 0's back is yellow. A colour given in the scene replaces the palette's.
TEST(Render, EachClothHasItsOwnColoursFrontAndBack) {
  const std::string cloths = R"({"grid": {}, "transform": {"translate": [-0.6, 0, 0]}},
                                {"grid": {}, "transform": {"translate": [0.6, 0, 0]}})";
  const Model palette = scene_model(R"({"cloths": [)" + cloths + "]}");
  const auto renderer = render::make_renderer(320, 180, 2);
  const render::Camera above = camera_at(Vec3(0, -0.5, 3), Vec3(0, 0, 0)), below = camera_at(Vec3(0, -0.5, -3), Vec3(0, 0, 0));
  const render::RenderSettings settings = render::parse_render_settings(palette.scene);
  const Hues top = count_hues(renderer->render(palette, palette.initial_positions, 0, above, settings.look));
  const Hues bottom = count_hues(renderer->render(palette, palette.initial_positions, 0, below, settings.look));
  EXPECT_GT(top.red, 2000);
  EXPECT_GT(top.blue, 2000);
  EXPECT_EQ(top.green, 0);
  EXPECT_GT(bottom.yellow, 2000);
  EXPECT_LT(bottom.red, top.red / 20);

  const Model coloured = scene_model(R"({"cloths": [{"grid": {}, "transform": {"translate": [-0.6, 0, 0]}},
      {"grid": {}, "transform": {"translate": [0.6, 0, 0]}, "render": {"color": "#20c030"}}]})");
  const Hues custom =
      count_hues(renderer->render(coloured, coloured.initial_positions, 0, above, render::parse_render_settings(coloured.scene).look));
  EXPECT_GT(custom.red, 2000);
  EXPECT_GT(custom.green, 2000);
  EXPECT_EQ(custom.blue, 0);
}

// With the wireframe, a 16 x 16 cloth seen from above is crossed by dark lines: many more dark
// pixels on it than without.
TEST(Render, TheWireframeDrawsTheTriangleEdges) {
  const Model model = scene_model(R"({"cloths": [{"grid": {"resolution": [16, 16]}}]})");
  const auto renderer = render::make_renderer(320, 180, 2);
  const render::Camera camera = camera_at(Vec3(0, -0.3, 2), Vec3(0, 0, 0));
  render::Look plain, wire;
  wire.wireframe = true;
  const auto dark = [](const render::Image& image) {
    int n = 0;
    for (std::size_t p = 0; p < image.rgb.size(); p += 3) n += image.rgb[p] < 110 && image.rgb[p] > image.rgb[p + 2];
    return n;
  };
  for (const auto style : {render::Look::Style::Shaded, render::Look::Style::Simple}) {
    plain.style = wire.style = style;
    const int without = dark(renderer->render(model, model.initial_positions, 0, camera, plain));
    const int with = dark(renderer->render(model, model.initial_positions, 0, camera, wire));
    EXPECT_GT(with, without + 2000) << without << " dark red pixels without the wireframe, " << with << " with";
  }
}

// The camera framed automatically has "up" against gravity.
TEST(Render, TheAutomaticCameraIsUprightAgainstGravity) {
  const Model sideways = scene_model(R"({"gravity": [0, -9.81, 0], "cloths": [{"grid": {}}]})");
  EXPECT_TRUE(render::frame_scene(sideways, 16.0 / 9).up.isApprox(Vec3::UnitY())) << render::frame_scene(sideways, 16.0 / 9).up;
  const Model weightless = scene_model(R"({"gravity": [0, 0, 0], "cloths": [{"grid": {}}]})");
  EXPECT_TRUE(render::frame_scene(weightless, 16.0 / 9).up.isApprox(Vec3::UnitZ()));
}

// drape render's frame range, still and camera options, and its errors.
TEST(Render, TheCommandLineChoosesFramesStillAndCamera) {
  const fs::path out = temp_dir("options");
  ASSERT_EQ(run_drape("run " + SOURCE + "/scenes/hanging.json --frames 5 --quiet --out " + out.string()).status, 0);
  const auto range = run_drape("render " + out.string() + " --frames 2:4 --resolution 64x48 --quiet");
  ASSERT_EQ(range.status, 0) << range.output;
  for (int f = 0; f <= 5; ++f)
    EXPECT_EQ(fs::exists(out / "render" / ("frame_0000" + std::to_string(f) + ".png")), f >= 2 && f <= 4) << f;
  if (render::VideoWriter::ffmpeg_available()) {
    const std::string probe = shell("ffprobe -v error -count_frames -select_streams v:0 -show_entries stream=nb_read_frames -of csv=p=0 " +
                                    (out / "video.mp4").string());
    EXPECT_EQ(probe, "3\n");
  }
  const fs::path still = out / "still.png", moved = out / "moved.png";
  const auto one = run_drape("render " + out.string() + " --still 5 -o " + still.string() + " --resolution 64x48");
  ASSERT_EQ(one.status, 0) << one.output;
  EXPECT_NE(one.output.find("frame 5: " + still.string()), std::string::npos) << one.output;
  EXPECT_FALSE(fs::exists(out / "render" / "frame_00005.png"));
  ASSERT_EQ(run_drape("render " + out.string() + " --still 5 -o " + moved.string() +
                      " --resolution 64x48 --camera-position 0,-3,0.5 --camera-target 0,0,0.5 --fov 30")
                .status,
            0);
  const auto bytes = [](const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  };
  EXPECT_NE(bytes(still), bytes(moved));

  const struct {
    std::string options, expected;
  } bad[] = {
      {"--frames 4:2", "--frames: expected FIRST:LAST, FIRST: or :LAST with FIRST <= LAST, found '4:2'"},
      {"--frames x", "--frames: expected"},
      {"--frames 9:", "has no frame from 9 to"},
      {"--still 9", "has no frame 9; its frames run from 0 to 5"},
      {"--frames 1:99", "has no frame 99; its frames run from 0 to 5"},
      {"--still 2 --frames 1:3", "--still and --frames: give one of them"},
      {"--output x.png", "--output: only with --still"},
      {"--camera-position 1,2", "--camera-position: expected X,Y,Z (three numbers, no spaces), found '1,2'"},
      {"--camera-target 1,2,nan", "--camera-target: expected X,Y,Z"},
      {"--camera-position 0,0,1 --camera-target 0,0,1", "the camera's position and target must differ (--camera-position, --camera-target)"},
      {"--camera-up 0,0,0", "the camera's up must not be zero or along its view from position to target (--camera-up)"},
      {"--style fancy", "--style: expected shaded or simple, found 'fancy'"},
      {"--fov 200", "--fov"},
  };
  for (const auto& b : bad) {
    const auto result = run_drape("render " + out.string() + " --resolution 64x48 --quiet " + b.options);
    EXPECT_EQ(result.status, 2) << b.options;
    EXPECT_NE(result.output.find(b.expected), std::string::npos) << b.options << "\n" << result.output;
  }
}
