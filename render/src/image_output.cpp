// PNG files (libpng) and MP4 videos (the ffmpeg program, fed raw frames through a pipe).
#include <png.h>

#include <csignal>
#include <cstdio>
#include <cstdlib>

#include "drape/render/renderer.h"

namespace drape::render {

void write_png(const std::filesystem::path& path, const Image& image) {
  const std::filesystem::path partial = path.string() + ".partial";
  std::FILE* file = std::fopen(partial.c_str(), "wb");
  if (!file) throw RenderError(path.string() + ": cannot write the image");
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    std::fclose(file);
    std::error_code ignored;
    std::filesystem::remove(partial, ignored);
    throw RenderError(path.string() + ": libpng failed to write the image (is the disk full?)");
  }
  png_init_io(png, file);
  png_set_IHDR(png, info, image.width, image.height, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  // zlib level 3: half the time of the default level 6 on a shaded frame, for about a fifth
  // more bytes.
  png_set_compression_level(png, 3);
  png_write_info(png, info);
  for (int y = 0; y < image.height; ++y)
    png_write_row(png, const_cast<png_bytep>(image.rgb.data() + std::size_t(y) * image.width * 3));
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  if (std::fclose(file) != 0) {
    std::error_code ignored;
    std::filesystem::remove(partial, ignored);
    throw RenderError(path.string() + ": cannot finish writing the image (is the disk full?)");
  }
  std::error_code error;
  std::filesystem::rename(partial, path, error);
  if (error) throw RenderError(path.string() + ": " + error.message());
}

bool VideoWriter::ffmpeg_available() { return std::system("command -v ffmpeg >/dev/null 2>&1") == 0; }

// ffmpeg writes here; close() renames it onto the video's path once ffmpeg has finished, so an
// interrupted or failed render leaves an earlier video whole.
std::filesystem::path partial_video(const std::filesystem::path& path) { return path.string() + ".partial"; }

VideoWriter::VideoWriter(const std::filesystem::path& path, int width, int height, double fps)
    : path_(path), width_(width), height_(height) {
  if (!ffmpeg_available()) throw RenderError("the ffmpeg program is not on the PATH; no video (the PNG frames are kept)");
  // H.264 needs even sides for yuv420p: pad by one pixel when odd.
  char command[1024];
  std::snprintf(command, sizeof command,
                "ffmpeg -loglevel error -y -f rawvideo -pix_fmt rgb24 -s %dx%d -r %.6f -i - "
                "-vf 'pad=ceil(iw/2)*2:ceil(ih/2)*2' -c:v libx264 -pix_fmt yuv420p -movflags +faststart -f mp4 '%s'",
                width, height, fps, partial_video(path).c_str());
  // A dead ffmpeg must surface as a write error, not kill drape with SIGPIPE.
  std::signal(SIGPIPE, SIG_IGN);
  pipe_ = popen(command, "w");
  if (!pipe_) throw RenderError(path.string() + ": cannot start ffmpeg");
}

void VideoWriter::add(const Image& image) {
  if (pipe_ && std::fwrite(image.rgb.data(), 1, image.rgb.size(), pipe_) != image.rgb.size())
    throw RenderError(path_.string() + ": ffmpeg stopped taking frames");
}

void VideoWriter::close() {
  if (!pipe_) return;
  const int status = pclose(pipe_);
  pipe_ = nullptr;
  std::error_code error;
  if (status != 0) {
    std::filesystem::remove(partial_video(path_), error);
    throw RenderError(path_.string() + ": ffmpeg failed to encode the video (an earlier video is kept)");
  }
  std::filesystem::rename(partial_video(path_), path_, error);
  if (error) throw RenderError(path_.string() + ": cannot move the finished video into place: " + error.message());
}

VideoWriter::~VideoWriter() {
  if (!pipe_) return;
  // Not closed: the render failed or was interrupted. The unfinished file goes.
  pclose(pipe_);
  std::error_code ignored;
  std::filesystem::remove(partial_video(path_), ignored);
}

}  // namespace drape::render
