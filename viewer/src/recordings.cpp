#include "recordings.hpp"

#include <cstdio>

namespace mbi::viewer {

void Recordings::start(const std::filesystem::path& video, int fb_width, int fb_height) {
  if (video.empty()) return;
  session_ = std::make_unique<VideoRecorder>(files_.ffmpeg(), files_.video_staging(), "--video " + video.string(),
                                             fb_width, fb_height);
  std::fprintf(stderr, "mbi view: recording %s\n", session_->describe().c_str());
}

std::string Recordings::toggle(int frame, int fb_width, int fb_height) {
  if (session_) {
    paused_ = !paused_;
    return std::string(paused_ ? "video paused: " : "video recording: ") + session_->describe();
  }
  if (key_) return stop_key_video();
  char name[64];
  std::snprintf(name, sizeof name, "mbi-video-%04d.mp4", frame);
  try {
    const std::filesystem::path ffmpeg = find_ffmpeg(name, "video");
    key_output_ = files_.reserve(name);
    key_ = std::make_unique<VideoRecorder>(ffmpeg, key_output_->staging(0), name, fb_width, fb_height);
  } catch (const std::exception& e) {
    key_.reset();
    key_output_.reset();
    std::fprintf(stderr, "mbi view: video not started: %s\n", e.what());
    return std::string("video not started: ") + e.what();
  }
  std::fprintf(stderr, "mbi view: recording %s\n", key_->describe().c_str());
  return "recording " + key_->describe();
}

std::string Recordings::stop_key_video() {
  std::string said;
  try {
    key_->finish();
    key_output_->commit();
    said = "video written: " + key_->describe() + ", " + std::to_string(key_->frames()) + " frames";
  } catch (const std::exception& e) {
    said = std::string("video not written: ") + e.what();
  }
  key_.reset();
  key_output_.reset();  // removes the staging file of a failed video
  std::fprintf(stderr, "mbi view: %s\n", said.c_str());
  return said;
}

void Recordings::add_frame(std::string& message) {
  if (session_ && !paused_) session_->add_frame();
  if (!key_) return;
  try {
    key_->add_frame();
  } catch (const std::exception& e) {
    message = stop_key_video();
  }
}

void Recordings::finish() {
  if (key_) stop_key_video();
  if (!session_) return;
  session_->finish();
  std::fprintf(stderr, "mbi view: %s, %d frames\n", session_->describe().c_str(), session_->frames());
}

}  // namespace mbi::viewer
