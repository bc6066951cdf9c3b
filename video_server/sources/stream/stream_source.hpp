// The stream camera: RTSP, HTTP MJPEG (smartphone IP-camera apps) or any
// file or URL FFmpeg reads, through OpenCV's VideoCapture.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "picksight/sources/source.hpp"

namespace picksight::codecs {
class VideoStream;
}

namespace picksight::video {

// A stream source string after "stream:": the URL, then optionally
// "|latency_ms=N", the part of the delay between exposure and arrival that
// the host cannot measure (the sender's encoding and buffering, the network):
// 0 to 10000 ms, default 0.
struct StreamOptions {
  std::string url;
  std::chrono::milliseconds latency{0};
};
Result<StreamOptions> parseStreamOptions(const std::string& text);

// How late a stream's frames are, measured per frame: the decode time, and
// the buffering delay seen as the frame's lag behind the stream's own clock
// (its presentation time) compared with the least-delayed recent frame. The
// presentation time is trusted only while it advances at the rate frames
// arrive (an MJPEG-over-HTTP server has none: FFmpeg then counts frames at a
// nominal rate, which says nothing of when they were taken).
class StreamDelay {
 public:
  // A frame whose bytes were in at `in_ns` and decoded at `decoded_ns`
  // (CLOCK_MONOTONIC), with presentation time `pts_ms` (negative: none).
  // Returns its delay from exposure to decoded, without the configured latency.
  std::chrono::nanoseconds add(uint64_t in_ns, uint64_t decoded_ns, double pts_ms);
  void reset() { window_.clear(); }

 private:
  struct Sample {
    uint64_t in_ns;
    double pts_ms;
  };
  bool ptsIsAClock() const;
  std::deque<Sample> window_;
};

// Threading: the public methods are called from the camera's acquisition
// thread only. While open, a reader thread owns the VideoStream and reads
// continuously, keeping only the newest frame: a network stream that is not
// drained builds up latency (RTSP) or stalls the sender (HTTP), and a read
// that blocks on a silent server must not hold up the camera's commands.
class StreamSource : public Source {
 public:
  explicit StreamSource(StreamOptions options);
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
  // Live streams stamp their frames with their estimated age.
  bool reportsAge() const override { return !is_file_; }
  // Read only: latency_ms (configured) and pipeline_delay_ms (the last
  // frame's estimated delay from exposure to decoded, latency included).
  std::vector<Feature> features() override;
  Result<Feature> feature(const std::string& name) override;

 private:
  void readLoop();

  const std::string url_;
  const std::chrono::milliseconds latency_;
  const bool is_file_;  // no "scheme://": seekable, so it loops
  // Used by the reader thread only while it runs; created in open() and
  // destroyed in close() after the reader has stopped.
  std::unique_ptr<codecs::VideoStream> capture_;
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
  cv::Mat latest_;                            // owned by the reader until handed over
  uint64_t latest_decoded_ns_ = 0;            // CLOCK_MONOTONIC
  std::chrono::nanoseconds latest_delay_{0};  // exposure to decoded, latency included
  StreamDelay delay_;                         // reader thread only
};

}  // namespace picksight::video
