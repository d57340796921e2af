#pragma once
// Video recording (internal): the window's frames piped to Debian's ffmpeg as raw RGB
// (-f rawvideo -pix_fmt rgb24), encoded by its default codec for the file's container (H.264 in
// .mp4). ffmpeg writes a staging file that the session's output rules move into place only
// when ffmpeg has succeeded (session_io.hpp), so no half-written video is left under its name.
#include <filesystem>
#include <string>

#include <sys/types.h>

namespace mbi::viewer {

/// The containers a video may be written in (by the file's extension).
inline constexpr const char* kVideoExtensions = ".mp4, .mkv, .mov or .webm";
/// Frames per second of every video: one simulation frame (1/30 s) per video frame, so a video
/// plays at the simulation's own speed whatever the viewer's frame rate was.
inline constexpr int kVideoFps = 30;

/// ffmpeg on PATH. Throws Error "<what>: needs ffmpeg ..." when there is none, or when
/// `file`'s extension is not one of kVideoExtensions.
std::filesystem::path find_ffmpeg(const std::filesystem::path& file, const std::string& what);

class VideoRecorder {
 public:
  /// Starts `ffmpeg` writing `file`; the frames are the window's lower left width x height
  /// pixels, rounded down to even sizes (what the common codecs need). `name` names the video
  /// in messages. Throws Error.
  VideoRecorder(const std::filesystem::path& ffmpeg, const std::filesystem::path& file, std::string name,
                int width, int height);
  /// Stops an unfinished ffmpeg (its file is then removed by its owner).
  ~VideoRecorder();
  VideoRecorder(const VideoRecorder&) = delete;
  VideoRecorder& operator=(const VideoRecorder&) = delete;

  /// Sends the bound framebuffer's back buffer as the next frame. Throws Error when ffmpeg
  /// has stopped.
  void add_frame();
  /// Ends the stream and waits for ffmpeg. Throws Error unless it exits with 0.
  void finish();

  int width() const { return width_; }
  int height() const { return height_; }
  int frames() const { return frames_; }
  /// "<name>: W x H at 30 fps" (stderr, the panel).
  std::string describe() const;

 private:
  std::string name_;
  int width_, height_, frames_ = 0;
  int pipe_ = -1;
  pid_t pid_ = -1;
};

}  // namespace mbi::viewer
