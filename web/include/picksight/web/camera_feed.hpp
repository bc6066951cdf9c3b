// One camera's frames for the web server: a subscriber thread keeps the
// newest frame, and an encoder thread makes its JPEG once, lazily, for every
// viewer, at the lowest CPU priority so that it never competes with a
// vision pass.
//
// Threading: the feed's thread alone owns the SUB socket; it only swaps a
// shared_ptr under mutex_ and wakes waiters, so no viewer ever slows it.
// The encoder thread encodes (SCHED_IDLE: it runs on a core nothing else
// wants), and only frames a viewer asked for through jpeg(), which may be
// called from any thread and waits for it. When the cores stay busy for
// kEncoderStarved, the waiting caller encodes the newest frame itself, at
// its own (normal) priority, one caller at a time: a saturated machine
// slows the page to about a frame per kEncoderStarved, never freezes it. A
// viewer that falls behind simply gets the newest frame next time (frames in
// between are skipped for it alone).
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

// How long a viewer waits for the idle-priority encoder before it encodes the
// frame itself: rare enough that a saturated machine's robots hardly feel it
// (at most one normal-priority JPEG per camera in that time), short enough
// that the page is never frozen.
constexpr std::chrono::milliseconds kEncoderStarved{3000};

// A frame's JPEG, shared by all the viewers that send it.
struct EncodedJpeg {
  uint64_t generation = 0;  // CameraFeed::generation() of its frame
  uint64_t sequence = 0;
  uint64_t host_timestamp_ns = 0;
  std::string bytes;
};

class CameraFeed {
 public:
  // Subscribes to `camera` on `frames_endpoint` and starts the threads.
  CameraFeed(zmq::context_t& context, std::string frames_endpoint, std::string camera,
             int jpeg_quality = 80);
  ~CameraFeed();  // stops and joins the threads
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

  // The JPEG of the newest frame, of generation `generation` or newer
  // (generation() when 0), encoded for this call if nobody asked for it
  // yet; waits for the encoder at most `timeout`. Null before the first
  // frame, on timeout, when stopping or when that frame could not be
  // encoded.
  std::shared_ptr<const EncodedJpeg> jpeg(
      uint64_t generation = 0, std::chrono::milliseconds timeout = std::chrono::milliseconds(5000));

  // Viewers of the MJPEG stream (for /metrics), counted by ViewerCount.
  int viewers() const { return viewers_.load(); }
  void addViewer(int delta) { viewers_ += delta; }
  // CPU time spent encoding JPEGs, in seconds (thread CPU clock).
  double encodeSeconds() const;
  uint64_t encodedFrames() const { return encoded_frames_.load(); }

  void stop();

 private:
  void run(zmq::context_t& context);
  void encodeLoop();
  // Encodes the newest frame with `encoder` and publishes its JPEG.
  void encodeNewest(JpegEncoder& encoder);

  const std::string frames_endpoint_;
  const std::string camera_;

  mutable std::mutex mutex_;
  mutable std::condition_variable changed_;
  std::shared_ptr<const Frame> latest_;  // under mutex_
  uint64_t generation_ = 0;              // under mutex_
  bool stopping_ = false;                // under mutex_

  std::mutex encode_mutex_;
  std::condition_variable encode_wake_;      // wakes the encoder thread
  std::condition_variable encoded_;          // wakes the callers of jpeg()
  JpegEncoder encoder_;                      // the encoder thread's
  std::mutex starved_mutex_;                 // one starved caller encodes at a time
  JpegEncoder starved_encoder_;              // under starved_mutex_
  std::shared_ptr<const EncodedJpeg> jpeg_;  // under encode_mutex_
  uint64_t wanted_ = 0;                      // under encode_mutex_: generation asked for
  uint64_t attempted_ = 0;                   // under encode_mutex_: generation last encoded
  bool encode_stopping_ = false;             // under encode_mutex_

  std::atomic<int> viewers_{0};
  std::atomic<uint64_t> encode_ns_{0};
  std::atomic<uint64_t> encoded_frames_{0};
  std::atomic<bool> stop_{false};
  std::thread thread_;
  std::thread encode_thread_;
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
