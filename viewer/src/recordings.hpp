#pragma once
// Which videos a session records (internal): --video from the first frame to the end (the
// video key pauses and resumes it), or, without --video, one video per press of the key:
// "mbi-video-FRAME.mp4" started by one press and written by the next, under the same rules as
// the p key's screenshots. Every video is moved into place only when ffmpeg has succeeded.
#include "session_io.hpp"
#include "video.hpp"

#include <memory>
#include <string>

namespace mbi::viewer {

class Recordings {
 public:
  explicit Recordings(SessionFiles& files) : files_(files) {}
  /// Starts --video, if asked, for frames of the window's framebuffer size. Throws Error.
  void start(const std::filesystem::path& video, int fb_width, int fb_height);
  /// The video key at `frame`; returns what to tell the user. Never throws: a video that cannot
  /// be started or written is said.
  std::string toggle(int frame, int fb_width, int fb_height);
  /// Sends this frame (the back buffer) to the running video, if any. Throws Error
  /// (--video); a key's video that fails is dropped and said in `message`.
  void add_frame(std::string& message);
  /// Ends the videos: --video's ffmpeg must succeed before the session's files are moved into
  /// place (throws Error); a key's video is written.
  void finish();
  bool recording() const { return (session_ && !paused_) || key_; }

 private:
  std::string stop_key_video();
  SessionFiles& files_;
  std::unique_ptr<VideoRecorder> session_, key_;
  std::unique_ptr<io::OutputSet> key_output_;
  bool paused_ = false;
};

}  // namespace mbi::viewer
