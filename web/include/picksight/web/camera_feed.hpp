// One camera's frames for the web server: a subscriber thread keeps the
// newest frame, and its JPEG is made once, lazily, for every viewer.
//
// Threading: the feed's thread alone owns the SUB socket; it only swaps a
// shared_ptr under mutex_ and wakes waiters, so no viewer ever slows it.
// jpeg() may be called from any thread: the first caller that needs a new
// frame's JPEG encodes it under encode_mutex_, the others wait for it and
// reuse it. A viewer that falls behind simply gets the newest frame next
// time (frames in between are skipped for it alone).
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include <zmq.hpp>

#include "picksight/common/frame.hpp"
#include "picksight/web/jpeg_encoder.hpp"

namespace picksight::web {

// A frame's JPEG, shared by all the viewers that send it.
struct EncodedJpeg {
  uint64_t sequence = 0;
  uint64_t host_timestamp_ns = 0;
  std::string bytes;
};

class CameraFeed {
 public:
  // Subscribes to `camera` on `frames_endpoint` and starts the thread.
  CameraFeed(zmq::context_t& context, std::string frames_endpoint, std::string camera,
             int jpeg_quality = 80);
  ~CameraFeed();  // stops and joins the thread
  CameraFeed(const CameraFeed&) = delete;
  CameraFeed& operator=(const CameraFeed&) = delete;

  const std::string& camera() const { return camera_; }
  const std::string& framesEndpoint() const { return frames_endpoint_; }

  // The newest frame (null before the first one).
  std::shared_ptr<const Frame> latest() const;
  // Counts frames received (never goes back, unlike sequence numbers after a
  // video server restart): what a viewer waits on.
  uint64_t generation() const;
  // Waits until generation() differs from `seen` or `timeout` passes, or the
  // feed stops; returns the generation.
  uint64_t waitNewer(uint64_t seen, std::chrono::milliseconds timeout) const;

  // The newest frame's JPEG, encoded now if nobody did yet; null before the
  // first frame or when encoding failed.
  std::shared_ptr<const EncodedJpeg> jpeg();

  // Viewers of the MJPEG stream (for /metrics), counted by ViewerCount.
  int viewers() const { return viewers_.load(); }
  void addViewer(int delta) { viewers_ += delta; }
  // CPU time spent encoding JPEGs, in seconds (thread CPU clock).
  double encodeSeconds() const;
  uint64_t encodedFrames() const { return encoded_frames_.load(); }

  void stop();

 private:
  void run(zmq::context_t& context);

  const std::string frames_endpoint_;
  const std::string camera_;

  mutable std::mutex mutex_;
  mutable std::condition_variable changed_;
  std::shared_ptr<const Frame> latest_;  // under mutex_
  uint64_t generation_ = 0;              // under mutex_
  bool stopping_ = false;                // under mutex_

  std::mutex encode_mutex_;
  JpegEncoder encoder_;                      // under encode_mutex_
  std::shared_ptr<const EncodedJpeg> jpeg_;  // under encode_mutex_
  const Frame* jpeg_of_ = nullptr;           // under encode_mutex_: the frame jpeg_ was made from
  std::shared_ptr<const Frame> jpeg_frame_;  // under encode_mutex_: keeps jpeg_of_ unique

  std::atomic<int> viewers_{0};
  std::atomic<uint64_t> encode_ns_{0};
  std::atomic<uint64_t> encoded_frames_{0};
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// Counts a viewer for as long as it lives.
class ViewerCount {
 public:
  explicit ViewerCount(CameraFeed& feed) : feed_(feed) { feed_.addViewer(1); }
  ~ViewerCount() { feed_.addViewer(-1); }
  ViewerCount(const ViewerCount&) = delete;
  ViewerCount& operator=(const ViewerCount&) = delete;

 private:
  CameraFeed& feed_;
};

}  // namespace picksight::web
