// The stream camera: RTSP, HTTP MJPEG (smartphone IP-camera apps) or any
// file or URL FFmpeg reads, through OpenCV's VideoCapture.
#pragma once

#include <condition_variable>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "picksight/sources/source.hpp"

namespace cv {
class VideoCapture;
}

namespace picksight::video {

// Threading: the public methods are called from the camera's acquisition
// thread only. While open, a reader thread owns the VideoCapture and reads
// continuously, keeping only the newest frame: a network stream that is not
// drained builds up latency (RTSP) or stalls the sender (HTTP), and a read
// that blocks on a silent server must not hold up the camera's commands.
class StreamSource : public Source {
 public:
  explicit StreamSource(std::string url);
  ~StreamSource() override;
  StreamSource(const StreamSource&) = delete;
  StreamSource& operator=(const StreamSource&) = delete;

  // Connects (FFmpeg open timeout 5 s); a failure is SourceErrc::kUnavailable.
  Result<void> open() override;
  // Stops the reader; may wait for a read in progress (at most the 5 s read timeout).
  void close() override;
  SourceInfo info() const override;
  // The newest frame not yet returned; SourceErrc::kTimeout when none came in
  // time; SourceErrc::kUnavailable once the stream ended or broke (the camera
  // then reopens it with back-off). A local file (a path, no "scheme://")
  // loops instead of ending.
  Result<SourceFrame> grab(std::chrono::milliseconds timeout) override;
  // A live stream delivers at its own pace. A file does not: the camera
  // paces it at its frame rate, as it does the file and dir sources.
  bool streams() const override { return !is_file_; }

 private:
  void readLoop();

  const std::string url_;
  const bool is_file_;  // no "scheme://": seekable, so it loops
  // Used by the reader thread only while it runs; created in open() and
  // destroyed in close() after the reader has stopped.
  std::unique_ptr<cv::VideoCapture> capture_;
  std::thread reader_;
  int width_ = 0;
  int height_ = 0;

  std::mutex mutex_;  // guards everything below
  std::condition_variable frame_ready_;
  std::condition_variable frame_taken_;
  bool stop_ = false;
  bool ended_ = false;
  std::string end_reason_;
  bool has_frame_ = false;
  cv::Mat latest_;  // owned by the reader until handed over
};

}  // namespace picksight::video
