// Off-screen rendering: what a frame shows, the video's format, and that simulating alone
// never creates a GL context.
#include <gtest/gtest.h>

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
      {R"({"colour": "red"})", "bad.json: /render/colour: unknown key (expected one of: camera, resolution, fps, samples, enabled)"},
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
      {R"({"fps": 0})", "bad.json: /render/fps: expected a frame rate from 0 to 240"},
  };
  for (const Case& c : cases) {
    const Scene scene = parse_scene(std::string(R"({"cloths": [{"grid": {}}], "render": )") + c.render + "}", "bad.json");
    std::string message;
    try {
      render::parse_render_settings(scene);
    } catch (const render::RenderError& e) {
      message = e.what();
    }
    EXPECT_NE(message.find(c.expected), std::string::npos) << "render: " << c.render << "\nmessage: " << message;
  }
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
  // 60 frames at 1920 x 1080 take seconds; the interrupt comes after half of one.
  const std::string status = shell("timeout --preserve-status -s INT 0.5 " + std::string(DRAPE_EXECUTABLE) +
                                   " render --resolution 1920x1080 --quiet " + out.string() + " >/dev/null 2>&1; echo $?");
  if (status == "0\n") GTEST_SKIP() << "the render finished within half a second";
  EXPECT_EQ(status, "3\n");
  EXPECT_EQ(read(out / "video.mp4"), earlier);
  for (const auto& entry : fs::recursive_directory_iterator(out))
    EXPECT_NE(entry.path().extension(), ".partial") << entry.path();
}
